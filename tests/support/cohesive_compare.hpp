#pragma once
// Cohesive meshes made two ways (1 and N partitions or ranks) against each other, and each
// against the independent checker (quality/cohesive.hpp): the same cohesive cells (the
// checksum hashes each one's bottom coordinates and phases, whichever partition emitted
// it), the same number of copies, every interface facet covered once (across periodic
// planes too), one node per (position, phase), and every slave copy with a same-phase
// master (mesh::periodic_links throws otherwise).
#include <gtest/gtest.h>

#include <algorithm>
#include <array>
#include <string>

#include "geometry/scene.hpp"
#include "mesh/periodic_links.hpp"
#include "parallel/checksum.hpp"
#include "pipeline/cohesive.hpp"
#include "quality/cohesive.hpp"

namespace cisamr::testing {

// The exact face coordinates of a scene's lattice (as driver::face_box computes them).
template <int Dim>
quality::CohesivePeriodicity<Dim> cohesive_frame(const geometry::SceneDesc& scene, const grid::Lattice<Dim>& lattice) {
  quality::CohesivePeriodicity<Dim> frame;
  for (int d = 0; d < Dim; ++d) {
    frame.faces.min[d] = lattice.coordinate(d, 0);
    frame.faces.max[d] = lattice.coordinate(d, lattice.fine_period(d));
    frame.axes[static_cast<std::size_t>(d)] = scene.periodic[static_cast<std::size_t>(d)];
  }
  return frame;
}

// `m`: a whole cohesive mesh (sequential, or gathered).
template <int Dim>
::testing::AssertionResult cohesive_mesh_is_right(const mesh::SimplexMesh<Dim>& m,
                                                  const quality::CohesivePeriodicity<Dim>& frame, bool voids = false) {
  const quality::CohesiveReport<Dim> r = quality::check_cohesive<Dim>(m, &frame);
  if (!r.ok()) return ::testing::AssertionFailure() << r.summary();
  if (r.cohesive_cells != r.interface_facets)
    return ::testing::AssertionFailure() << r.cohesive_cells << " cohesive cells for " << r.interface_facets
                                         << " interface facets";
  bool periodic = false;
  for (bool a : frame.axes) periodic = periodic || a;
  if (periodic) {
    try {
      (void)mesh::periodic_links<Dim>(m, frame.faces, frame.axes, voids);
    } catch (const std::exception& e) {
      return ::testing::AssertionFailure() << e.what();
    }
  }
  return ::testing::AssertionSuccess();
}

// Cohesive cells lying on a periodic min face (made by the join across the plane).
template <int Dim>
std::int64_t cohesive_cells_on_periodic_planes(const mesh::SimplexMesh<Dim>& m,
                                               const quality::CohesivePeriodicity<Dim>& frame) {
  std::int64_t count = 0;
  for (std::size_t c = 0; c < m.cohesive.count(); ++c)
    for (int a = 0; a < Dim; ++a) {
      if (!frame.axes[static_cast<std::size_t>(a)]) continue;
      bool all = true;
      for (int k = 0; k < Dim; ++k) all = all && m.point(m.cohesive.cell(c)[k])[a] == frame.faces.min[a];
      if (all) {
        ++count;
        break;
      }
    }
  return count;
}

// Positions where three or more phases' copies meet (triple points in 2D, points of
// triple lines in 3D): what the tests need to have seen.
template <int Dim>
std::int64_t multi_phase_points(const mesh::SimplexMesh<Dim>& m) {
  const quality::WeldedMesh<Dim> welded = quality::weld_view(m);
  std::vector<int> copies(welded.mesh.node_count(), 0);
  for (LocalId w : welded.class_of) ++copies[static_cast<std::size_t>(w)];
  return std::ranges::count_if(copies, [](int n) { return n >= 3; });
}

// What `cisamr mesh --cohesive` does to a sequential result (pipeline::insert_cohesive_whole),
// periodic planes included, checked as above, and the bulk unchanged (the welded split
// mesh has the original's cells corner by corner). Adds the cells made to `cells` and
// those on periodic planes to `plane_cells`.
template <int Dim>
::testing::AssertionResult cohesive_whole_is_right(const pipeline::Result<Dim>& result, const geometry::SceneDesc& scene,
                                                   std::int64_t* cells = nullptr, std::int64_t* plane_cells = nullptr) {
  const grid::Lattice<Dim> lattice = pipeline::make_lattice<Dim>(scene, {});
  pipeline::Result<Dim> split = result;
  pipeline::insert_cohesive_whole(split, lattice);
  const quality::CohesivePeriodicity<Dim> frame = cohesive_frame<Dim>(scene, lattice);
  const bool voids = std::ranges::any_of(scene.phases, [](const geometry::Phase& p) { return p.is_void; });
  if (auto ok = cohesive_mesh_is_right(split.mesh, frame, voids); !ok) return ok;
  const quality::WeldedMesh<Dim> welded = quality::weld_view(split.mesh);
  const auto& m = result.mesh;
  if (welded.mesh.cell_count() != m.cell_count() || welded.mesh.cell_phase != m.cell_phase)
    return ::testing::AssertionFailure() << "the split changed the bulk cells";
  for (std::size_t i = 0; i < m.cell_nodes.size(); ++i)
    if (welded.mesh.point(welded.mesh.cell_nodes[i]) != m.point(m.cell_nodes[i]))
      return ::testing::AssertionFailure() << "corner " << i << " moved by the split";
  if (cells != nullptr) *cells += static_cast<std::int64_t>(split.mesh.cohesive.count());
  if (plane_cells != nullptr) *plane_cells += cohesive_cells_on_periodic_planes(split.mesh, frame);
  return ::testing::AssertionSuccess();
}

}  // namespace cisamr::testing
