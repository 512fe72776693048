#pragma once
// Reading and writing scenes (DESIGN.md §5, format "cisamr-scene/1"). The reader is strict:
// every problem, unknown keys included, is an InputError(file, field, problem) whose field
// is a path such as "inclusions[3].radius" or "domain.max[2]". It checks types, counts,
// ranges and references between fields; geometric validity (self-intersections, overlaps
// of different phases, closure of NURBS) is left to the geometry oracle.
// See lib/io/README.md for the rules and defaults.
#include <cstdint>
#include <map>
#include <span>
#include <string>
#include <vector>

#include "geometry/scene.hpp"

namespace cisamr::io {

// Reads and validates a scene file. STL files are resolved against the scene's directory
// and stored as absolute paths.
geometry::SceneDesc read_scene(const std::string& path);

// Lazy STL loading (the parallel mesher: a rank reads only the STL files its partitions
// need). With load_stl = false every field is read and checked as usual but
// StlSurface::triangles stay empty; load_stl_surfaces fills them. probe_stl (with
// load_stl = false): still open each STL file to check that it can be read; false leaves
// that check, with the same message, to load_stl_surfaces.
struct ReadSceneOptions {
  bool load_stl = true;
  bool probe_stl = true;
};
geometry::SceneDesc read_scene(const std::string& path, const ReadSceneOptions& options);
geometry::SceneDesc parse_scene(const std::string& json_text, const std::string& source,
                                const ReadSceneOptions& options);

// Reads the triangles of the listed inclusions (scene indices) that are STL surfaces with
// none yet, each file once (per call, or per `cache`: file → triangles, filled as files
// are read). Returns the number of files read. Errors as read_scene's: a file that cannot
// be opened is an InputError naming the scene and "inclusions[k].file", a malformed one an
// InputError naming the STL file.
using StlCache = std::map<std::string, std::vector<std::array<Vec3, 3>>>;
std::int64_t load_stl_surfaces(geometry::SceneDesc& scene, std::span<const std::int32_t> inclusions,
                               StlCache* cache = nullptr);

// The same on text already in memory; `source` names it in errors and its directory
// resolves relative STL paths ("" = the current directory).
geometry::SceneDesc parse_scene(const std::string& json_text, const std::string& source);

// Writes the scene as pretty JSON (atomically). Every double is printed with the shortest
// text that reads back to the same bits, so read_scene(write_scene(s)) == s exactly. STL
// paths are written relative to the new file's directory.
void write_scene(const std::string& path, const geometry::SceneDesc& scene);

// The same, as text (no trailing file I/O); `destination` is where relative STL paths are
// taken from ("" = the current directory).
std::string scene_to_json(const geometry::SceneDesc& scene, const std::string& destination);

}  // namespace cisamr::io
