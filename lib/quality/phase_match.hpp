#pragma once
// Which scene phase each phase of a mesh read from a file is (certify against a scene).
// Other tools number phases their own way (Gmsh physical tags, Abaqus ELSETs in order, TetGen
// region attributes), so a mesh's phase ids need not be the scene's: phases are matched
// by an explicit map first, then by the name the file gives them, then by number.
#include <map>
#include <string>
#include <vector>

#include "geometry/scene.hpp"
#include "mesh/simplex_mesh.hpp"

namespace cisamr::quality {

// One entry of `--phase-map MESH=SCENE,...`: each side a phase id or a phase name.
struct PhaseMapEntry {
  std::string mesh;
  std::string scene;
};

// Parses "A=B,C=D". Throws InputError(option, "", ...) naming the bad entry.
std::vector<PhaseMapEntry> parse_phase_map(const std::string& text, const std::string& option = "--phase-map");

struct MeshPhase {
  int id = 0;
  std::string name;  // as the file names it; empty when it does not
};

// The scene phase id of every mesh phase: an entry of `map` naming the mesh phase (by id or
// name) wins; else a file name equal to a scene phase's name; else the same id, when the
// file names the phase not at all or with the writers' default "phase<id>". Throws
// InputError(mesh_path, "phase", ...) for a mesh phase without a scene phase, or a map
// entry that names no mesh or no scene phase.
std::map<int, int> match_phases(const std::vector<MeshPhase>& mesh_phases,
                                const std::vector<geometry::Phase>& scene_phases,
                                const std::vector<PhaseMapEntry>& map, const std::string& mesh_path);

// Rewrites the cells' phase ids through `scene_id` (every cell's id is a key).
template <int Dim>
void relabel_phases(mesh::SimplexMesh<Dim>& m, const std::map<int, int>& scene_id);

}  // namespace cisamr::quality
