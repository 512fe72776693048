#include "io/mesh_svg.hpp"

#include <algorithm>
#include <cstdio>
#include <string>

#include "io/atomic_file.hpp"

namespace cisamr::io {
namespace {

const char* colour_of(std::size_t index) {
  static const char* kPalette[] = {"#d9d9d9", "#e6550d", "#3182bd", "#31a354", "#756bb1",
                                   "#fdae6b", "#9ecae1", "#a1d99b", "#bcbddc", "#636363"};
  return kPalette[index % (sizeof(kPalette) / sizeof(kPalette[0]))];
}

}  // namespace

void write_mesh_svg(const std::string& path, const mesh::Mesh2& m, const geometry::SceneDesc& scene, int width_px) {
  const double x0 = scene.domain_min[0], y0 = scene.domain_min[1];
  const double w = scene.domain_max[0] - x0, h = scene.domain_max[1] - y0;
  const double scale = width_px / w;
  const int height_px = static_cast<int>(h * scale + 0.5);
  const bool edges = m.cell_count() <= 400000;
  AtomicFile file(path);
  char buf[256];
  std::snprintf(buf, sizeof buf,
                "<svg xmlns=\"http://www.w3.org/2000/svg\" width=\"%d\" height=\"%d\" viewBox=\"0 0 %d %d\">\n",
                width_px, height_px, width_px, height_px);
  file.write(buf);
  file.write("<rect width=\"100%\" height=\"100%\" fill=\"white\"/>\n");
  // One path per phase keeps the file small and the colours consistent.
  for (std::size_t p = 0; p < scene.phases.size(); ++p) {
    const int id = scene.phases[p].id;
    std::snprintf(buf, sizeof buf, "<path fill=\"%s\" stroke=\"%s\" stroke-width=\"%.2f\" d=\"", colour_of(p),
                  edges ? "#202020" : "none", edges ? 0.3 : 0.0);
    file.write(buf);
    for (std::size_t c = 0; c < m.cell_count(); ++c) {
      if (m.cell_phase[c] != id) continue;
      const LocalId* n = m.cell(c);
      std::string s;
      for (int k = 0; k < 3; ++k) {
        const Vec2 q = m.point(n[k]);
        // SVG's y axis points down.
        std::snprintf(buf, sizeof buf, "%c%.2f %.2f", k == 0 ? 'M' : 'L', (q[0] - x0) * scale,
                      (h - (q[1] - y0)) * scale);
        s += buf;
      }
      s += 'Z';
      file.write(s);
    }
    file.write("\"/>\n");
  }
  file.write("</svg>\n");
  file.commit();
}

}  // namespace cisamr::io
