#pragma once
// Inside the pipeline module: what both dimensions' kernels share around their stages.
#include <cstdint>
#include <span>
#include <vector>

#include "core/types.hpp"
#include "geometry/scene.hpp"
#include "grid/lattice.hpp"
#include "pipeline/pipeline.hpp"

namespace cisamr::pipeline {


// What the mesh is made of once the stages are done (their working state released): the
// lattice nodes, the points subdivision added (node ids follow the lattice nodes'), and
// the cells over both.
template <int Dim>
struct MeshParts {
  std::vector<std::uint64_t> lattice_key;  // per lattice node
  std::vector<Vec<Dim>> lattice_position;  // per lattice node, after snapping
  std::vector<Vec<Dim>> extra_points;
  std::vector<NodeIdentity<Dim>> extra_identity;  // per extra point; empty: none is shared
  std::vector<std::int32_t> cells;  // Dim+1 node ids per cell, positively oriented
  std::vector<std::uint8_t> phase;  // phase index (into scene.phases) per cell: a byte while the stages are alive
};

// The mesh: cells of void phases dropped, nodes renumbered in order of first use and unused
// ones removed, node identities kept. The parts' cell arrays become the mesh's (compacted
// in place: no second copy of the connectivity).
template <int Dim>
void assemble(const geometry::SceneDesc& scene, MeshParts<Dim>&& parts, int partition_id, Result<Dim>& result);

// Each dimension's kernel (kernel2.cpp, kernel3.cpp): runs its stages on the coarse cells of
// `box` grown by `ghost`, fills the counters and stage times of `result`, and returns what
// the mesh is made of; the stages' working state is released on return, before assembly.
MeshParts<2> run_stages(const geometry::Oracle2& oracle, const grid::Lattice<2>& lattice, const grid::CellRange<2>& box,
                        const Ghost& ghost, const Options& options, std::span<const int> levels, Result<2>& result);
MeshParts<3> run_stages(const geometry::Oracle3& oracle, const grid::Lattice<3>& lattice, const grid::CellRange<3>& box,
                        const Ghost& ghost, const Options& options, std::span<const int> levels, Result<3>& result);

}  // namespace cisamr::pipeline
