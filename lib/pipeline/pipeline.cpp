#include "pipeline/pipeline.hpp"

#include <algorithm>
#include <cmath>

#include "core/error.hpp"
#include "grid/tet_lattice.hpp"
#include "pipeline/assembly.hpp"
#include "pipeline/cohesive.hpp"
#include "pipeline/effective_levels.hpp"

namespace cisamr::pipeline {

template <int Dim>
grid::Lattice<Dim> make_lattice(const geometry::SceneDesc& scene, const Options& options) {
  grid::Lattice<Dim> lattice;
  lattice.h = scene.h;
  int levels = scene.levels;
  for (const auto& inclusion : scene.inclusions) levels = std::max(levels, inclusion.levels);
  lattice.max_level = levels + std::max(0, options.extra_levels);
  for (int d = 0; d < Dim; ++d) {
    const auto axis = static_cast<std::size_t>(d);
    lattice.origin[d] = scene.domain_min[axis];
    const double cells = (scene.domain_max[axis] - scene.domain_min[axis]) / scene.h;
    lattice.coarse_cells[d] = static_cast<std::int64_t>(std::llround(cells));
    if (lattice.coarse_cells[d] < 1) throw InputError(scene.source, "mesh.h", "larger than the domain");
    lattice.periodic[d] = scene.periodic[axis];
    // A node and its images across the period must be distinct lattice points of a cell.
    if (lattice.periodic[d] && lattice.coarse_cells[d] < 2)
      throw InputError(scene.source, "mesh.h",
                       std::string("a periodic axis needs at least 2 cells of h; ") + "xyz"[d] + " has 1");
  }
  // The five-tetrahedron honeycomb alternates with the parity of the cube (tet_lattice.hpp):
  // it closes on a torus only with an even cell count. And an edge (at most one cell long
  // per axis) must be told from its image across the period by its ends' canonical keys,
  // which takes more than 2 cells: so at least 4.
  if constexpr (Dim == 3)
    for (int d = 0; d < Dim; ++d)
      if (lattice.periodic[d] && (lattice.coarse_cells[d] % 2 != 0 || lattice.coarse_cells[d] < 4))
        throw InputError(scene.source, "mesh.h",
                         std::string("periodic axis ") + "xyz"[d] + " has " + std::to_string(lattice.coarse_cells[d]) +
                             " cells of h; a periodic 3D mesh needs an even number, at least 4");
  if constexpr (Dim == 3) grid::require_key3(lattice);
  return lattice;
}

template <int Dim>
double coarse_cells(const geometry::SceneDesc& scene) {
  double cells = 1;
  for (std::size_t d = 0; d < Dim; ++d) cells *= std::round((scene.domain_max[d] - scene.domain_min[d]) / scene.h);
  return cells;
}
template double coarse_cells<2>(const geometry::SceneDesc&);
template double coarse_cells<3>(const geometry::SceneDesc&);

template <int Dim>
MeshEstimate estimate_mesh(const geometry::SceneDesc& scene) {
  // Calibrated on the examples: about 2 triangles per square, 6 tetrahedra per cube, and a
  // band of refined cells 3 wide along an interface, its coarser levels adding as much again.
  constexpr double kPerCell = Dim == 2 ? 2.0 : 6.0;
  constexpr double kBand = 2 * 3 * kPerCell;
  MeshEstimate estimate;
  estimate.background = kPerCell * coarse_cells<Dim>(scene);
  double largest = 0;
  const std::vector<Box3> boxes = holding_boxes(scene);  // empty for an STL surface not loaded
  for (std::size_t k = 0; k < scene.inclusions.size(); ++k) {
    const Box3& box = boxes[k];
    std::array<double, Dim> side{};
    for (std::size_t d = 0; d < Dim; ++d)
      side[d] = std::max(0.0, std::min(box.max[d], scene.domain_max[d]) - std::max(box.min[d], scene.domain_min[d]));
    // The interface's size: the box's perimeter (2D) or surface area (3D).
    const double size = Dim == 2 ? 2 * (side[0] + side[1])
                                 : 2 * (side[0] * side[1] + side[1] * side[Dim - 1] + side[0] * side[Dim - 1]);
    const double fine = scene.h / std::exp2(scene.inclusions[k].levels);
    const double added = kBand * size / std::pow(fine, Dim - 1);
    estimate.refined += added;
    if (added > largest) largest = added, estimate.largest_inclusion = static_cast<std::int64_t>(k);
  }
  return estimate;
}

template <int Dim>
grid::CellRange<Dim> ghosted_range(const grid::Lattice<Dim>& lattice, const grid::CellRange<Dim>& box, const GhostSides& ghost) {
  grid::CellRange<Dim> range = box;
  for (int d = 0; d < Dim; ++d) {
    const int below = ghost[static_cast<std::size_t>(d)][0], above = ghost[static_cast<std::size_t>(d)][1];
    if (lattice.periodic[d]) {  // the ghost wraps around the period (the forest takes it so)
      range.lo[d] = box.lo[d] - below;
      range.hi[d] = box.hi[d] + above;
      if (range.hi[d] - range.lo[d] >= lattice.coarse_cells[d]) range.lo[d] = 0, range.hi[d] = lattice.coarse_cells[d];
      continue;
    }
    range.lo[d] = std::max<std::int64_t>(0, box.lo[d] - below);
    range.hi[d] = std::min<std::int64_t>(lattice.coarse_cells[d], box.hi[d] + above);
  }
  return range;
}

template <int Dim>
void assemble(const geometry::SceneDesc& scene, MeshParts<Dim>&& parts, int partition_id, Result<Dim>& result) {
  constexpr std::size_t corners = Dim + 1;
  const std::size_t lattice_count = parts.lattice_key.size();
  const std::size_t total = lattice_count + parts.extra_points.size();
  std::vector<std::int32_t> new_id(total, -1);
  const std::size_t cell_count = parts.phase.size();
  std::size_t kept = 0;
  std::int32_t next = 0;
  for (std::size_t c = 0; c < cell_count; ++c) {
    const auto& phase = scene.phases[static_cast<std::size_t>(parts.phase[c])];
    if (phase.is_void) continue;
    // Kept cells move down in place (kept ≤ c: nothing unread is overwritten).
    for (std::size_t k = 0; k < corners; ++k) {
      std::int32_t& id = new_id[static_cast<std::size_t>(parts.cells[corners * c + k])];
      if (id < 0) id = next++;
      parts.cells[corners * kept + k] = id;
    }
    parts.phase[kept++] = parts.phase[c];
  }
  parts.cells.resize(corners * kept);
  mesh::SimplexMesh<Dim>& m = result.mesh;
  m.cell_nodes = std::move(parts.cells);
  m.cell_phase.resize(kept);
  for (std::size_t c = 0; c < kept; ++c) m.cell_phase[c] = scene.phases[parts.phase[c]].id;
  std::vector<std::uint8_t>().swap(parts.phase);
  const auto nodes = static_cast<std::size_t>(next);
  m.coords.resize(Dim * nodes);
  result.node_identity.resize(nodes);
  for (std::size_t n = 0; n < total; ++n) {
    const std::int32_t id = new_id[n];
    if (id < 0) continue;
    const auto i = static_cast<std::size_t>(id);
    if (n < lattice_count) {
      if constexpr (Dim == 2)
        result.node_identity[i] = parts.lattice_key[n];
      else
        result.node_identity[i] = {parts.lattice_key[n], parts.lattice_key[n]};
    } else {
      result.node_identity[i] =
          parts.extra_identity.empty() ? Result<Dim>::kUnshared : parts.extra_identity[n - lattice_count];
    }
    const Vec<Dim>& p = n < lattice_count ? parts.lattice_position[n] : parts.extra_points[n - lattice_count];
    for (int d = 0; d < Dim; ++d) m.coords[Dim * i + static_cast<std::size_t>(d)] = p[d];
  }
  m.cell_partition.assign(m.cell_phase.size(), partition_id);
  m.node_global_id.resize(nodes);
  for (std::size_t i = 0; i < nodes; ++i) m.node_global_id[i] = static_cast<GlobalId>(i);
}

template <int Dim>
Result<Dim> run(const geometry::Oracle<Dim>& oracle, const grid::Lattice<Dim>& lattice, const grid::CellRange<Dim>& box,
                const Ghost& ghost, const Options& options, int partition_id, std::span<const int> levels) {
  Result<Dim> result;
  result.times.progress = options.progress;
  MeshParts<Dim> parts = run_stages(oracle, lattice, box, ghost, options, levels, result);
  {
    ScopedPhase timer(&result.times, "assemble");
    assemble(oracle.scene(), std::move(parts), partition_id, result);
  }
  return result;
}

namespace {

// The whole mesh's cohesive cells (pipeline/cohesive.hpp), the domain as one partition.
template <int Dim>
Result<Dim> with_cohesive(Result<Dim> result, const grid::Lattice<Dim>& lattice, const Options& options) {
  if (!options.cohesive) return result;
  {
    ScopedPhase timer(&result.times, "cohesive");  // ends before `result` is moved out
    insert_cohesive_whole(result, lattice);
  }
  return result;
}

}  // namespace

Result<2> mesh(const geometry::Oracle2& oracle, const Options& options) {
  const grid::Lattice2 lattice = make_lattice<2>(oracle.scene(), options);
  begin_phase(options.progress, "levels");
  const std::vector<int> levels = effective_levels2(oracle.scene(), lattice);
  return with_cohesive(run(oracle, lattice, lattice.whole_domain(), Ghost{}, options, 0, levels), lattice, options);
}

Result<3> mesh(const geometry::Oracle3& oracle, const Options& options) {
  const grid::Lattice3 lattice = make_lattice<3>(oracle.scene(), options);
  begin_phase(options.progress, "levels");
  const std::vector<int> levels =
      effective_levels3(oracle.scene(), lattice, {}, surface_unions(oracle.scene()));
  return with_cohesive(run(oracle, lattice, lattice.whole_domain(), Ghost{}, options, 0, levels), lattice, options);
}

template grid::Lattice<2> make_lattice<2>(const geometry::SceneDesc&, const Options&);
template grid::Lattice<3> make_lattice<3>(const geometry::SceneDesc&, const Options&);
template MeshEstimate estimate_mesh<2>(const geometry::SceneDesc&);
template MeshEstimate estimate_mesh<3>(const geometry::SceneDesc&);
template grid::CellRange<2> ghosted_range<2>(const grid::Lattice<2>&, const grid::CellRange<2>&, const GhostSides&);
template grid::CellRange<3> ghosted_range<3>(const grid::Lattice<3>&, const grid::CellRange<3>&, const GhostSides&);
template void assemble<2>(const geometry::SceneDesc&, MeshParts<2>&&, int, Result<2>&);
template void assemble<3>(const geometry::SceneDesc&, MeshParts<3>&&, int, Result<3>&);
template Result<2> run<2>(const geometry::Oracle2&, const grid::Lattice<2>&, const grid::CellRange<2>&, const Ghost&,
                          const Options&, int, std::span<const int>);
template Result<3> run<3>(const geometry::Oracle3&, const grid::Lattice<3>&, const grid::CellRange<3>&, const Ghost&,
                          const Options&, int, std::span<const int>);

}  // namespace cisamr::pipeline
