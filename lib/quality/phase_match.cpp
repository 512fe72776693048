#include "quality/phase_match.hpp"

#include <charconv>
#include <optional>

#include "core/error.hpp"

namespace cisamr::quality {
namespace {

std::optional<int> as_id(const std::string& text) {
  int value = 0;
  const auto r = std::from_chars(text.data(), text.data() + text.size(), value);
  if (text.empty() || r.ec != std::errc() || r.ptr != text.data() + text.size()) return std::nullopt;
  return value;
}

std::string describe(const MeshPhase& p) {
  return "mesh phase " + std::to_string(p.id) + (p.name.empty() ? "" : " '" + p.name + "'");
}

std::string scene_list(const std::vector<geometry::Phase>& scene) {
  std::string text;
  for (const geometry::Phase& p : scene)
    text += (text.empty() ? "" : ", ") + std::to_string(p.id) + (p.name.empty() ? "" : " " + p.name);
  return text;
}

}  // namespace

std::vector<PhaseMapEntry> parse_phase_map(const std::string& text, const std::string& option) {
  std::vector<PhaseMapEntry> entries;
  std::size_t start = 0;
  while (start <= text.size()) {
    const std::size_t comma = std::min(text.find(',', start), text.size());
    const std::string entry = text.substr(start, comma - start);
    const std::size_t eq = entry.find('=');
    if (eq == std::string::npos || eq == 0 || eq + 1 == entry.size() || entry.find('=', eq + 1) != std::string::npos)
      throw InputError(option, "", "entry '" + entry.substr(0, 80) + "' is not MESH=SCENE (a phase id or name each side)");
    entries.push_back({entry.substr(0, eq), entry.substr(eq + 1)});
    start = comma + 1;
  }
  return entries;
}

std::map<int, int> match_phases(const std::vector<MeshPhase>& mesh_phases,
                                const std::vector<geometry::Phase>& scene_phases,
                                const std::vector<PhaseMapEntry>& map, const std::string& mesh_path) {
  auto scene_by_id = [&](int id) -> const geometry::Phase* {
    for (const geometry::Phase& p : scene_phases)
      if (p.id == id) return &p;
    return nullptr;
  };
  auto scene_by_name = [&](const std::string& name) -> const geometry::Phase* {
    for (const geometry::Phase& p : scene_phases)
      if (!name.empty() && p.name == name) return &p;
    return nullptr;
  };
  // The map's entries resolved to scene ids first, so that a bad entry fails even if unused.
  std::vector<int> entry_scene(map.size());
  std::vector<bool> entry_used(map.size(), false);
  for (std::size_t k = 0; k < map.size(); ++k) {
    const std::optional<int> id = as_id(map[k].scene);
    const geometry::Phase* p = id ? scene_by_id(*id) : scene_by_name(map[k].scene);
    if (!p)
      throw InputError("--phase-map", "", "'" + map[k].scene + "' is not a phase of the scene (" +
                                              scene_list(scene_phases) + ")");
    entry_scene[k] = p->id;
  }
  std::map<int, int> result;
  for (const MeshPhase& m : mesh_phases) {
    std::optional<int> matched;
    for (std::size_t k = 0; k < map.size() && !matched; ++k) {
      const std::optional<int> id = as_id(map[k].mesh);
      if ((id && *id == m.id) || (!id && !m.name.empty() && map[k].mesh == m.name)) {
        matched = entry_scene[k];
        entry_used[k] = true;
      }
    }
    if (!matched && !m.name.empty()) {
      if (const geometry::Phase* p = scene_by_name(m.name)) matched = p->id;
      else if (m.name != "phase" + std::to_string(m.id))
        throw InputError(mesh_path, "phase",
                         describe(m) + " has no scene phase of that name (scene phases: " + scene_list(scene_phases) +
                             "); use --phase-map " + std::to_string(m.id) + "=SCENE_ID");
    }
    if (!matched) {
      if (!scene_by_id(m.id))
        throw InputError(mesh_path, "phase",
                         describe(m) + " is not a phase of the scene (" + scene_list(scene_phases) +
                             "); use --phase-map " + std::to_string(m.id) + "=SCENE_ID");
      matched = m.id;
    }
    result[m.id] = *matched;
  }
  for (std::size_t k = 0; k < map.size(); ++k)
    if (!entry_used[k])
      throw InputError("--phase-map", "", "'" + map[k].mesh + "' is not a phase of the mesh " + mesh_path);
  return result;
}

template <int Dim>
void relabel_phases(mesh::SimplexMesh<Dim>& m, const std::map<int, int>& scene_id) {
  for (std::int32_t& phase : m.cell_phase) phase = scene_id.at(phase);
}

template void relabel_phases<2>(mesh::SimplexMesh<2>&, const std::map<int, int>&);
template void relabel_phases<3>(mesh::SimplexMesh<3>&, const std::map<int, int>&);

}  // namespace cisamr::quality
