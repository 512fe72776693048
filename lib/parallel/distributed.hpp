#pragma once
// Parallel CISAMR in 2D and 3D (paper Algorithm 2, DESIGN.md §8). Collective over a
// core::Comm: the same code runs on one process (SerialComm) or under mpiexec (MpiComm).
//
//   read      every rank parses the scene file itself (no broadcast), without opening its
//             STL files; in 3D each STL file is then read by one rank (round-robin), which
//             all-gathers its surfaces' boxes, sends their partition loads to rank 0 and
//             decides their same-phase unions (share_stl_surfaces)
//   partition rank 0 runs partition::partition_domain, the boxes are broadcast; partition
//             i goes to the rank whose block of consecutive ids holds it
//   ghost     per own partition, the ghost region (ghost.hpp): which inclusions, which cells
//   oracle    per own partition, an Oracle2/Oracle3 from exactly its ghost region's
//             inclusions (original order kept); the rest of the scene's descriptors is
//             dropped first, and the STL files of the kept ones are read (once per rank)
//   kernel    pipeline::run unchanged on each own partition
//   merge     nodes merged by lattice identity, owners, global ids (merge.hpp)
// Every stage ends with an agreement on errors (collective.hpp).
#include <algorithm>
#include <cstdint>
#include <functional>
#include <string>
#include <vector>

#include "core/comm.hpp"
#include "core/timer.hpp"
#include "geometry/scene.hpp"
#include "io/scene_io.hpp"
#include "parallel/ghost.hpp"
#include "parallel/merge.hpp"
#include "partition/partition.hpp"
#include "pipeline/pipeline.hpp"

namespace cisamr::parallel {

struct MeshOptions {
  pipeline::Options pipeline;
  int partitions = 1;  // at least the number of ranks
  partition::PartitionOptions partitioning;
  GhostRule ghost;
  // 3D: exchange the decisions near the boxes' faces after r-adaptivity (README.md,
  // "Decisions exchanged near faces"): a narrower ghost, but the working state of every
  // partition of a rank is held between the kernel's parts. false: every partition
  // recomputes them in a wider ghost, one partition held at a time (a streamed run; comparisons).
  bool exchange_near_faces = true;
};

// The kernel's parts a 3D run with exchanges near faces times apart (SAMR; the forest's
// exchange taken and the guard's first pass; its second pass; face swapping to the
// partition's mesh): every rank waits at each exchange for the slowest.
inline constexpr int kKernelStages = 4;

struct PartitionSummary {
  int id = 0, rank = 0;
  std::array<std::int64_t, 3> lattice_min{}, lattice_max{};  // coarse cells [min, max) (Dim used)
  double load = 0;                // paper Eq. 2
  double cost = 0;                // what the partitioner balanced: load + the ghost's weighted load (3D)
  int ghost = 0;                  // ghost width (coarse cells) it was meshed with
  std::int64_t ghost_cells = 0;   // coarse cells meshed beyond its box
  std::int64_t inclusions = 0;    // inclusions its ghost region loads
  std::int64_t elements = 0, nodes = 0;
  double kernel_seconds = 0;      // pipeline::run (the sum of stage_seconds)
  std::array<double, kKernelStages> stage_seconds{};  // by kKernelStages' parts; [0] only when nothing was exchanged
};

// The largest and the mean of one figure of the partitions (load, cost), and their ratio.
struct Spread {
  double max = 0, mean = 0;
  double imbalance() const { return mean > 0 ? max / mean : 1.0; }
};
inline Spread spread_of(const std::vector<PartitionSummary>& parts, double PartitionSummary::*figure) {
  Spread s;
  for (const PartitionSummary& p : parts) s.max = std::max(s.max, p.*figure), s.mean += p.*figure;
  if (!parts.empty()) s.mean /= static_cast<double>(parts.size());
  return s;
}

// What the ranks learn about the STL surfaces whose triangles the scene does not hold
// (README.md, "Reading the scene").
struct StlShares {
  std::vector<Box3> known;                          // per inclusion: its box (STL surfaces; others unset)
  std::vector<partition::InclusionLoad> loads;      // per inclusion: its partition load (rank 0 only)
  std::vector<pipeline::SurfacePair> unions;        // = pipeline::surface_unions(scene with every triangle)
  io::StlCache cache;                               // the files this rank read (path → triangles)
  std::int64_t files_read = 0;                      // files this rank read
};

// Collective (3D). Every STL file is read by one rank: files in order of first
// appearance, file j by rank j mod P. The reader computes its surfaces' boxes
// (all-gathered) and, with `loads_needed`, their partition loads (gathered on rank 0).
// Every rank then replays pipeline::surface_unions' sweep over all boxes; a candidate pair
// with an unread STL member is decided by the reader of its first such member (which
// reads the other member's file too if it must), other pairs by the ranks in turn; the
// pairs are all-gathered. The result equals surface_unions of the scene with every
// triangle read: the same candidate pairs, each decided by the same call on the same
// arguments in the same order. On return the scene's STL surfaces hold no triangles (the
// files read are in `cache`). Errors (a file that cannot be read) are collective.
StlShares share_stl_surfaces(const Comm& comm, geometry::SceneDesc& scene, const partition::PartitionOptions& options,
                             bool loads_needed);

// Block distribution: rank r meshes partitions [first, last).
std::array<int, 2> partitions_of_rank(int partitions, int ranks, int rank);
int rank_of_partition(int partition, int partitions, int ranks);

template <int Dim>
struct DistributedMesh {
  NumberedPiece<Dim> piece;         // this rank's cells and nodes, global ids
  std::vector<geometry::Phase> phases;
  Box<Dim> domain{};
  std::int64_t scene_inclusions = 0;
  std::int64_t periodic_images = 0;  // images of inclusions across periodic faces (geometry/periodic.hpp)
  std::int64_t global_cells = 0;
  std::string partition_method;
  std::vector<PartitionSummary> partitions;     // every partition, by id, on every rank
  std::vector<std::int32_t> loaded_inclusions;  // what this rank's partitions load: scene indices, ascending
  std::int64_t stl_files_read = 0;  // STL files this rank read (3D): its share, then what its partitions need
  pipeline::Counters<Dim> counters;  // over all partitions of all ranks (coarse cells: the boxes')
  bool near_faces_exchanged = false;  // 3D: the decisions near faces were exchanged (MeshOptions::exchange_near_faces)
  std::int64_t exchanged_nodes = 0;   // nodes that took their owner's refusals or decisions (all ranks, both rounds)
  std::int64_t exchanged_cubes = 0;   // ghost cubes whose refinement came from their owner (all ranks)
  std::int64_t replaced_cubes = 0;    // of those, the cubes whose own refinement differed
  PhaseTimes times;                 // this rank's phase times
};
using DistributedMesh2 = DistributedMesh<2>;
using DistributedMesh3 = DistributedMesh<3>;

// Collective. Reads the scene on every rank, then as above. Errors (bad scene, N < ranks,
// a mesh the rules cannot build, a scene of the other dimension) are thrown on every rank
// alike (collective.hpp).
template <int Dim>
DistributedMesh<Dim> mesh_distributed(const Comm& comm, const std::string& scene_path, const MeshOptions& options);

// Collective. The same from a scene every rank already holds (tests, library use). In 3D,
// STL surfaces without triangles are read from their files by the ranks that need them.
template <int Dim>
DistributedMesh<Dim> mesh_distributed(const Comm& comm, geometry::SceneDesc scene, const MeshOptions& options);

// What receives each partition as soon as the kernel has meshed it (with the global
// lattice); it may move the result out.
template <int Dim>
using PartitionSink = std::function<void(PartitionOutput<Dim>&, const grid::Lattice<Dim>&)>;

// Collective. mesh_distributed up to the kernel: this rank's partitions are meshed one after
// another (ascending ids) and each is handed to `sink` when done, so that only one is held
// at a time (the merge or the streamed output decide what to keep). With
// options.exchange_near_faces (3D) the kernel runs in parts with the exchanges between
// them, and the working state of every partition of the rank is held between the parts. The result has no
// piece; its partitions, counters, times, phases, domain and global_cells are set.
template <int Dim>
DistributedMesh<Dim> mesh_partitions(const Comm& comm, geometry::SceneDesc scene, const MeshOptions& options,
                                     const PartitionSink<Dim>& sink);

}  // namespace cisamr::parallel
