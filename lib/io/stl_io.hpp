#pragma once
// STL surfaces (ASCII or binary) for the "stl" inclusion: read_scene fills
// StlSurface::triangles with this, so that geometry never opens files.
#include <array>
#include <string>
#include <vector>

#include "core/types.hpp"

namespace cisamr::io {

using StlTriangle = std::array<Vec3, 3>;

// Triangles in the file's own coordinates. Binary files are recognised by their size
// (84 + 50·n bytes), whatever their header says; anything else must be ASCII
// ("solid ... facet normal ... outer loop vertex x y z ×3 endloop endfacet ... endsolid",
// possibly several solids one after the other: their triangles are all kept). Only regular
// files are read (a FIFO or a device is an InputError, not a wait).
// Throws InputError(path, "" or "line N", problem) for unreadable, malformed or empty files.
std::vector<StlTriangle> read_stl(const std::string& path);

}  // namespace cisamr::io
