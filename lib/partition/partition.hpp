#pragma once
// Load-balanced partitioning of the domain into boxes (paper Algorithm 1, note §9).
// Pure and sequential: no MPI, no printing, no files. See README.md for the algorithm and
// for the PARTS.json format that to_json writes (the parallel mesher reads it).
#include <array>
#include <cstdint>
#include <span>
#include <string>
#include <vector>

#include "core/types.hpp"
#include "geometry/scene.hpp"

namespace cisamr::partition {

struct PartitionOptions {
  // merge: Algorithm 1 as the paper states it (over-decomposition + merging);
  // bisection: load-weighted recursive bisection on the lattice;
  // best: both, keep the lower maximum load (see README.md for why).
  enum class Method { best, merge, bisection };
  Method method = Method::best;
  int oversubscription = 8;         // the over-decomposition has at least this × n leaves
  int extra_depths = 2;             // also try this many finer over-decompositions (below 512 leaves per part), keep the best
  double load_exponent = 0;         // M in R^M·|A|; 0 = the paper's 1 (2D) or 1.5 (3D)
  bool rebalance = true;            // after merging, slide shared faces to lower the max load
  std::int64_t max_load_cells = std::int64_t{1} << 23;  // load raster; coarser lattice above this
  double sample_spacing = 0;        // boundary samples (non-circles); 0 = a quarter raster cell
  // The parallel mesher meshes each box with a ghost around it, which a balance of the boxes'
  // own loads ignores: a box inside the domain carries ghost on six sides, one at a corner of
  // the domain on three (E4 at 16 partitions: ghost of 0.53 to 0.95 times the box). With a
  // ghost, each box costs its load plus ghost_weight times the load of the box grown by
  // ghost_cells_at_level[l] lattice cells (clipped to the domain), l the coarsest level
  // requested by any inclusion (the last entry for finer ones), and the cuts balance that
  // cost. Empty (the default): boxes balanced on their loads. Not on periodic scenes.
  std::vector<int> ghost_cells_at_level;
  double ghost_weight = 0;
};

struct SharedFace {
  int part = -1;            // the neighbour's id
  int axis = 0;             // normal of the face
  int side = +1;            // +1: the neighbour lies on the max side along `axis`, −1: min side
  Box3 face{};              // the shared face (min[axis] == max[axis]), in this part's frame
  bool periodic = false;    // across the domain boundary of a periodic scene
  Vec3 shift{};             // periodic: the neighbour's box plus `shift` touches this part
};

struct Part {
  int id = 0;
  int rank = 0;
  std::array<std::int64_t, 3> lattice_min{}, lattice_max{};  // background cells (multiples of h)
  Box3 box{};
  double load = 0;
  double cost = 0;  // load + the ghost's weighted load (PartitionOptions::ghost_weight); = load without
  std::vector<SharedFace> neighbours;
  std::vector<std::int32_t> inclusions;  // inclusions whose bounding box meets the closed box
};

struct Partition {
  std::string method;                  // "algorithm1" (merging), "bisection" or "uniform-grid"
  int dimension = 2;
  Box3 domain{};
  double h = 1;
  std::array<std::int64_t, 3> cells{};  // background cells per axis
  std::array<bool, 3> periodic{};  // per axis
  double load_exponent = 1;
  double total_load = 0;
  std::array<int, 3> leaves{};          // over-decomposition that produced the result
  int merges = 0;
  int rebalance_moves = 0;
  std::vector<Part> parts;

  double ghost_weight = 0;              // what the cuts balanced (PartitionOptions)
  std::int64_t ghost_cells = 0;
  double max_load() const;
  double mean_load() const;
  double max_cost() const;
  double mean_cost() const;
  double imbalance() const { return mean_load() > 0 ? max_load() / mean_load() : 1.0; }
  double cost_imbalance() const { return mean_cost() > 0 ? max_cost() / mean_cost() : 1.0; }
  // Σ of the shared (internal) face measures, each face once: lengths in 2D, areas in 3D.
  double shared_face_measure() const;
};

// Algorithm 1: over-decomposition on the background lattice, load per leaf, repeated merging
// of the two face-sharing boxes of least combined load, optional face sliding; with
// Method::best also load-weighted recursive bisection, keeping the better result. Throws
// InputError when n < 1 or the lattice has fewer cells than n.
Partition partition_domain(const geometry::SceneDesc& scene, int n, const PartitionOptions& options = {});

// The load an STL surface adds to the load raster of `scene` (its boundary samples summed
// per raster cell): raster cells (ascending) and their loads. It needs the surface's
// triangles, nothing else of the scene but its header: the parallel mesher computes it on
// the rank that read the file and partitions on another (partition_domain with `given`).
struct InclusionLoad {
  std::vector<std::int64_t> cells;
  std::vector<double> loads;
  Box3 box{};  // the surface's bounding box (Part::inclusions)
};
InclusionLoad stl_surface_load(const geometry::SceneDesc& scene, std::int32_t inclusion,
                               const PartitionOptions& options = {});

// partition_domain for a scene whose STL surfaces need not hold their triangles: the load
// of such a surface k is given[k] (`given` indexed by inclusion, other entries unused).
// The same partition as with every triangle present.
Partition partition_domain(const geometry::SceneDesc& scene, int n, const PartitionOptions& options,
                           std::span<const InclusionLoad> given);

// The baseline: a g_x × g_y (× g_z) grid with Π g = n, factors chosen to make the boxes as
// cubic as possible, faces on the lattice; loads computed the same way.
Partition uniform_grid_partition(const geometry::SceneDesc& scene, int n, const PartitionOptions& options = {});

// Σ_k R_k^M |A_k| over the parts of the boundaries inside the domain (wrapped if periodic).
double total_load(const geometry::SceneDesc& scene, const PartitionOptions& options = {});

// PARTS.json ("cisamr-partition/1"); `scene_path` is recorded as given.
std::string to_json(const Partition& p, const std::string& scene_path);

// An SVG of the boxes over the inclusions (2D), or of three z-slices (3D: at 22, 50 and
// 78 % of the height; spheres, ellipsoids and axis-parallel cylinders are drawn).
std::string to_svg(const Partition& p, const geometry::SceneDesc& scene);

}  // namespace cisamr::partition
