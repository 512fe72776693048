#pragma once
// The load density on (a possibly coarsened copy of) the background lattice:
// cell (i,j,k) holds Σ_k R_k^M × (the part of |A_k| inside the cell), and a summed-volume
// table answers the load of any lattice-aligned box in O(1). Internal to lib/partition.
#include <array>
#include <cstdint>
#include <span>
#include <vector>

#include "core/types.hpp"
#include "geometry/scene.hpp"
#include "partition/partition.hpp"

namespace cisamr::partition {

struct LoadField {
  int dim = 2;
  Box3 domain{};
  double h = 1;
  std::array<bool, 3> periodic{};  // per axis
  bool any_periodic() const { return periodic[0] || periodic[1] || periodic[2]; }
  double exponent = 1;
  std::array<std::int64_t, 3> lattice_cells{1, 1, 1};  // background cells per axis
  std::int64_t coarsen = 1;                             // raster cell = coarsen × h (last may be shorter)
  std::array<std::int64_t, 3> n{1, 1, 1};               // raster cells per axis
  std::vector<double> cells;                            // load per raster cell, x fastest
  std::vector<double> prefix;                           // (n+1)-sized summed-volume table

  // Background-lattice index of raster line i along `axis`.
  std::int64_t lattice_index(int axis, std::int64_t i) const {
    return std::min(i * coarsen, lattice_cells[axis]);
  }
  double coordinate(int axis, std::int64_t i) const { return domain.min[axis] + lattice_index(axis, i) * h; }
  // Load of raster box [lo, hi) (half-open raster indices).
  double box_load(const std::array<std::int64_t, 3>& lo, const std::array<std::int64_t, 3>& hi) const;
  double total() const;
  // The parallel mesher's ghost (PartitionOptions::ghost_cells_at_level): its width in
  // lattice cells and in raster cells (rounded up), and the weight of its load.
  std::int64_t ghost_cells = 0, ghost_raster = 0;
  double ghost_weight = 0;
  // What meshing raster box [lo, hi) costs: its load plus ghost_weight times the load of its
  // ghost (the box grown by ghost_raster, clipped to the domain).
  double box_cost(const std::array<std::int64_t, 3>& lo, const std::array<std::int64_t, 3>& hi) const;
};

// `given`: per inclusion (scene order), the loads of STL surfaces whose triangles the scene
// does not hold (stl_surface_load, computed where they were read); other entries unused.
// An STL surface's samples are summed per raster cell before they are added (the same
// whether computed here or given), so the field does not depend on where they were read.
LoadField build_load_field(const geometry::SceneDesc& scene, const PartitionOptions& options,
                           std::span<const InclusionLoad> given = {});

// Levels an inclusion asks for: its own, else the scene's.
int requested_levels(const geometry::SceneDesc& scene, const geometry::Inclusion& inc);
// Levels R_k used for an inclusion's load (requested_levels, at least 1: an inclusion
// without refinement still costs its cut elements).
int effective_levels(const geometry::SceneDesc& scene, const geometry::Inclusion& inc);

// Axis-aligned box that holds any scene shape (geometry::shape_holding_box).
Box3 inclusion_box(const geometry::Shape& s);

}  // namespace cisamr::partition
