// Mesh readers: the checks every reader ends with, and the choice of reader by extension.
#include <algorithm>
#include <cctype>
#include <filesystem>
#include <limits>
#include <unordered_map>

#include "core/error.hpp"
#include "io/mesh_io.hpp"
#include "io/mesh_read_internal.hpp"

namespace cisamr::io {
namespace detail {
namespace {

template <int Dim>
void fill_mesh(RawMesh& raw, mesh::SimplexMesh<Dim>& m) {
  const std::size_t nodes = raw.coords.size() / 3;
  m.coords.resize(nodes * Dim);
  for (std::size_t n = 0; n < nodes; ++n)
    for (int d = 0; d < Dim; ++d) m.coords[n * Dim + d] = raw.coords[3 * n + d];
  m.cell_nodes = std::move(raw.cell_nodes);
  m.cell_phase = std::move(raw.cell_phase);
  m.cell_partition = std::move(raw.cell_partition);
  if (m.cell_partition.empty()) m.cell_partition.assign(m.cell_phase.size(), 0);
  m.node_global_id = std::move(raw.node_global_id);
  if (m.node_global_id.empty()) {
    m.node_global_id.resize(nodes);
    for (std::size_t n = 0; n < nodes; ++n) m.node_global_id[n] = static_cast<GlobalId>(n);
  }
  if (raw.cohesive_nodes.empty()) return;
  const std::size_t cohesive = raw.cohesive_nodes.size() / (2 * Dim);
  m.cohesive.nodes = std::move(raw.cohesive_nodes);
  m.cohesive.phase = std::move(raw.cohesive_phase);
  m.cohesive.partition = std::move(raw.cohesive_partition);
  if (m.cohesive.partition.empty()) m.cohesive.partition.assign(cohesive, 0);
  m.node_phase = std::move(raw.node_phase);
  if (m.node_phase.empty()) {
    // Not in the file: each node's first bulk cell's phase, or for a copy of no bulk cell (a
    // periodic master only the join made) the side its first cohesive cell puts it on.
    m.node_phase.assign(nodes, 0);
    std::vector<bool> seen(nodes, false);
    for (std::size_t i = 0; i < m.cell_nodes.size(); ++i) {
      const auto n = static_cast<std::size_t>(m.cell_nodes[i]);
      if (!seen[n]) seen[n] = true, m.node_phase[n] = m.cell_phase[i / (Dim + 1)];
    }
    for (std::size_t i = 0; i < m.cohesive.nodes.size(); ++i) {
      const auto n = static_cast<std::size_t>(m.cohesive.nodes[i]);
      const std::size_t cell = i / (2 * Dim), side = (i % (2 * Dim)) / Dim;  // 0: bottom, 1: top
      if (!seen[n]) seen[n] = true, m.node_phase[n] = m.cohesive.phase[2 * cell + side];
    }
  }
}

// The axes the file's periodic constraints tie: the translation of each $Periodic link
// (row a, column 4 of its affine map), and the axes along which a node and its
// periodic_master (a global id) differ.
std::array<bool, 3> constrained_axes(const RawMesh& raw) {
  std::array<bool, 3> axes = raw.periodic_axes;
  for (const LoadedMesh::PeriodicLink& link : raw.periodic_links)
    if (link.affine.size() == 16)
      for (int a = 0; a < 3; ++a) axes[static_cast<std::size_t>(a)] = axes[static_cast<std::size_t>(a)] || link.affine[4 * a + 3] != 0;
  if (std::none_of(raw.periodic_master.begin(), raw.periodic_master.end(), [](GlobalId g) { return g >= 0; })) return axes;
  std::unordered_map<GlobalId, std::size_t> node_of;
  const std::size_t nodes = raw.coords.size() / 3;
  for (std::size_t n = 0; n < nodes; ++n) node_of.emplace(raw.node_global_id.empty() ? GlobalId(n) : raw.node_global_id[n], n);
  for (std::size_t n = 0; n < nodes; ++n) {
    if (raw.periodic_master[n] < 0) continue;
    const auto master = node_of.find(raw.periodic_master[n]);
    if (master == node_of.end()) continue;  // a master in no piece read: nothing to compare
    for (int a = 0; a < 3; ++a)
      axes[static_cast<std::size_t>(a)] =
          axes[static_cast<std::size_t>(a)] || raw.coords[3 * n + a] != raw.coords[3 * master->second + a];
  }
  return axes;
}

// The cohesive cells' checks: their kind matches the bulk cells', node indices in range,
// one entry per cell in every per-cell array.
void check_cohesive_arrays(const RawMesh& raw, std::size_t nodes, const std::string& path) {
  if (raw.cohesive_nodes.empty()) {
    if (!raw.node_phase.empty() && raw.node_phase.size() != nodes)
      throw InputError(path, "node_phase", "has " + std::to_string(raw.node_phase.size()) + " values for " +
                                               std::to_string(nodes) + " points");
    return;
  }
  const int wanted = raw.corners == 4 ? 6 : 4;
  if (raw.cohesive_corners != wanted)
    throw InputError(path, "", raw.cohesive_corners == 6 ? "cohesive prisms (wedges) in a triangle mesh: they go with tetrahedra"
                                                         : "cohesive quads in a tetrahedral mesh: they go with triangles");
  const std::size_t corners = static_cast<std::size_t>(wanted);
  if (raw.cohesive_nodes.size() % corners != 0) throw InputError(path, "", "cohesive cells with missing nodes");
  const std::size_t cells = raw.cohesive_nodes.size() / corners;
  for (std::size_t i = 0; i < raw.cohesive_nodes.size(); ++i)
    if (raw.cohesive_nodes[i] < 0 || static_cast<std::size_t>(raw.cohesive_nodes[i]) >= nodes)
      throw InputError(path, "", "cohesive cell " + std::to_string(i / corners) + " refers to node " +
                                     std::to_string(raw.cohesive_nodes[i]) + " of " + std::to_string(nodes));
  if (raw.cohesive_phase.size() != 2 * cells || (!raw.cohesive_partition.empty() && raw.cohesive_partition.size() != cells) ||
      (!raw.cohesive_set_of_cell.empty() && raw.cohesive_set_of_cell.size() != cells))
    throw InputError(path, "", "cohesive cell data do not match the number of cohesive cells");
  if (!raw.node_phase.empty() && raw.node_phase.size() != nodes)
    throw InputError(path, "node_phase", "has " + std::to_string(raw.node_phase.size()) + " values for " +
                                             std::to_string(nodes) + " points");
}

}  // namespace

LoadedMesh finish(RawMesh raw, const std::string& path) {
  const std::size_t nodes = raw.coords.size() / 3;
  if (nodes > static_cast<std::size_t>(std::numeric_limits<LocalId>::max()))
    throw InputError(path, "", "too many nodes (" + std::to_string(nodes) + ")");
  for (std::size_t i = 0; i < raw.cell_nodes.size(); ++i)
    if (raw.cell_nodes[i] < 0 || static_cast<std::size_t>(raw.cell_nodes[i]) >= nodes)
      throw InputError(path, "", "cell " + std::to_string(i / std::max(raw.corners, 1)) +
                                     " refers to node " + std::to_string(raw.cell_nodes[i]) +
                                     " of " + std::to_string(nodes));
  const std::size_t cells = raw.corners ? raw.cell_nodes.size() / static_cast<std::size_t>(raw.corners) : 0;
  if (cells == 0) throw InputError(path, "", "no triangles or tetrahedra: not a mesh");
  if (raw.cell_phase.empty()) raw.cell_phase.assign(cells, 1);
  if (raw.cell_phase.size() != cells || (!raw.cell_partition.empty() && raw.cell_partition.size() != cells))
    throw InputError(path, "", "cell data do not match the number of cells");
  if (!raw.node_global_id.empty() && raw.node_global_id.size() != nodes)
    throw InputError(path, "", "point data do not match the number of points");
  check_cohesive_arrays(raw, nodes, path);

  LoadedMesh result;
  bool flat = true;
  for (std::size_t n = 0; n < nodes; ++n)
    if (raw.coords[3 * n + 2] != 0) {
      flat = false;
      break;
    }
  if (raw.corners == 3 && !flat)
    throw InputError(path, "", "triangles outside the plane z = 0: a surface mesh, not a 2D "
                               "or volume mesh (only 2D triangle and 3D tetrahedron meshes are read)");
  result.dimension = raw.corners == 4 || (raw.corners == 0 && !flat) ? 3 : 2;

  std::vector<std::int32_t> ids;  // distinct phase ids: few, so a linear search is cheap
  std::int32_t last = 0;
  for (const std::int32_t id : raw.cell_phase) {
    if ((id == last && !ids.empty()) || std::find(ids.begin(), ids.end(), id) != ids.end()) continue;
    ids.push_back(id);
    last = id;
  }
  std::sort(ids.begin(), ids.end());
  for (const std::int32_t id : ids) {
    auto it = raw.phase_names.find(id);
    if (it != raw.phase_names.end() && it->second.empty()) it = raw.phase_names.end();
    result.phases.push_back(geometry::Phase{
        id, it != raw.phase_names.end() ? it->second : "phase" + std::to_string(id), false});
    if (it != raw.phase_names.end()) result.phase_names_in_file.emplace(id, it->second);
  }
  if (!raw.periodic_master.empty() && raw.periodic_master.size() != nodes)
    throw InputError(path, "periodic_master", "has " + std::to_string(raw.periodic_master.size()) + " values for " +
                                                  std::to_string(nodes) + " points");
  result.periodic_axes = constrained_axes(raw);
  result.periodic_links = std::move(raw.periodic_links);
  result.periodic_master = std::move(raw.periodic_master);
  if (!raw.cohesive_nodes.empty()) {
    result.cohesive_sets = std::move(raw.cohesive_sets);
    result.cohesive_set_of_cell = std::move(raw.cohesive_set_of_cell);
  }
  if (result.dimension == 2)
    fill_mesh(raw, result.mesh2);
  else
    fill_mesh(raw, result.mesh3);
  return result;
}

}  // namespace detail

LoadedMesh read_mesh(const std::string& path) {
  // Formats read but not written: by their extension first.
  const std::string extension = lowercase_extension(path);
  if (extension == ".pvtu") return detail::read_pvtu(path);
  if (extension == ".vtk") return detail::read_legacy_vtk(path);
  if (extension == ".node" || extension == ".ele") return detail::read_tetgen(path);
  using namespace detail;
  switch (mesh_format_of(path)) {
    case MeshFormat::vtu: return read_vtu(path);
    case MeshFormat::msh: return read_msh(path);
    case MeshFormat::inp: return read_inp(path);
    case MeshFormat::medit: return read_medit(path);
  }
  throw InputError(path, "", "unknown mesh format");
}

}  // namespace cisamr::io
