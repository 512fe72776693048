#pragma once
// What `cisamr mesh --cohesive` does to a finished mesh (mesh::insert_cohesive), checked by
// the independent checker (quality/cohesive.hpp, no code shared with the insertion): every
// facet between different phases covered by exactly one cohesive cell, tops on bottoms bit
// for bit, no node shared by two phases, bottoms on the lower phase oriented into the top
// one; and the bulk mesh unchanged (the welded split mesh has the original's cells, corner
// by corner, at the same coordinates).
#include <gtest/gtest.h>

#include <cstdint>

#include "mesh/cohesive.hpp"
#include "quality/cohesive.hpp"

namespace cisamr::testing {

template <int Dim>
::testing::AssertionResult cohesive_split_is_right(const mesh::SimplexMesh<Dim>& m, std::int64_t* cells = nullptr) {
  mesh::SimplexMesh<Dim> split = m;
  mesh::insert_cohesive(split, 0);
  const quality::CohesiveReport<Dim> report = quality::check_cohesive(split);
  if (!report.ok()) return ::testing::AssertionFailure() << report.summary();
  if (report.cohesive_cells != report.interface_facets)
    return ::testing::AssertionFailure() << report.cohesive_cells << " cohesive cells for " << report.interface_facets
                                         << " interface facets";
  const quality::WeldedMesh<Dim> welded = quality::weld_view(split);
  if (welded.mesh.cell_count() != m.cell_count() || welded.mesh.cell_phase != m.cell_phase)
    return ::testing::AssertionFailure() << "the split changed the bulk cells";
  for (std::size_t i = 0; i < m.cell_nodes.size(); ++i)
    if (welded.mesh.point(welded.mesh.cell_nodes[i]) != m.point(m.cell_nodes[i]))
      return ::testing::AssertionFailure() << "corner " << i << " moved by the split";
  if (cells != nullptr) *cells += static_cast<std::int64_t>(split.cohesive.count());
  return ::testing::AssertionSuccess();
}

}  // namespace cisamr::testing
