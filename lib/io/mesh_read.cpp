// Mesh readers: the checks every reader ends with, and the choice of reader by extension.
#include <algorithm>
#include <cctype>
#include <filesystem>
#include <limits>

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
  result.periodic_links = std::move(raw.periodic_links);
  result.periodic_master = std::move(raw.periodic_master);
  if (result.dimension == 2)
    fill_mesh(raw, result.mesh2);
  else
    fill_mesh(raw, result.mesh3);
  return result;
}

}  // namespace detail

LoadedMesh read_mesh(const std::string& path) {
  // Formats read but not written: by their extension first.
  std::string extension = std::filesystem::path(path).extension().string();
  for (char& c : extension) c = static_cast<char>(std::tolower(static_cast<unsigned char>(c)));
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
