#pragma once
// A picture of a 2D mesh: triangles filled by phase, edges drawn thin. For the README's
// example and quick looks; ParaView is the tool for anything serious.
#include <string>

#include "geometry/scene.hpp"
#include "mesh/simplex_mesh.hpp"

namespace cisamr::io {

// Writes an SVG (through AtomicFile). Large meshes are drawn without edges, which would
// only blacken the picture. width_px: the width of the drawing.
void write_mesh_svg(const std::string& path, const mesh::Mesh2& m, const geometry::SceneDesc& scene,
                    int width_px = 1600);

}  // namespace cisamr::io
