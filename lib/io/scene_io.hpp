#pragma once
// Reading and writing scenes (DESIGN.md §5, format "cisamr-scene/1"). The reader is strict:
// every problem, unknown keys included, is an InputError(file, field, problem) whose field
// is a path such as "inclusions[3].radius" or "domain.max[2]". It checks types, counts,
// ranges and references between fields; geometric validity (self-intersections, overlaps
// of different phases, closure of NURBS) is left to the geometry oracle.
// See lib/io/README.md for the rules and defaults.
#include <cstdint>
#include <span>
#include <string>

#include "geometry/scene.hpp"

namespace cisamr::io {

// Reads and validates a scene file. STL files are resolved against the scene's directory
// and stored as absolute paths.
geometry::SceneDesc read_scene(const std::string& path);

// Lazy STL loading (the parallel mesher: a rank reads only the STL files its partitions
// need). With load_stl = false every field is read and checked as usual (the STL file must
// exist and be readable) but StlSurface::triangles stay empty; load_stl_surfaces fills them.
struct ReadSceneOptions {
  bool load_stl = true;
};
geometry::SceneDesc read_scene(const std::string& path, const ReadSceneOptions& options);
geometry::SceneDesc parse_scene(const std::string& json_text, const std::string& source,
                                const ReadSceneOptions& options);

// Reads the triangles of the listed inclusions (scene indices) that are STL surfaces with
// none yet. Errors as read_scene's (InputError naming the STL file).
void load_stl_surfaces(geometry::SceneDesc& scene, std::span<const std::int32_t> inclusions);

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
