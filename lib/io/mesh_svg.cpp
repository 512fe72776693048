#include "io/mesh_svg.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <string>

#include "core/error.hpp"
#include "io/atomic_file.hpp"

namespace cisamr::io {
namespace {

const char* colour_of(std::size_t index) {
  static const char* kPalette[] = {"#d9d9d9", "#e6550d", "#3182bd", "#31a354", "#756bb1",
                                   "#fdae6b", "#9ecae1", "#a1d99b", "#bcbddc", "#636363"};
  return kPalette[index % (sizeof(kPalette) / sizeof(kPalette[0]))];
}

// Draws polygons filled by phase over the rectangle [lo, hi] (one path per phase keeps the
// file small and the colours consistent). `polygon(i, out)` appends polygon i's points.
template <class Polygon>
void write_polygons(const std::string& path, std::size_t count, const std::vector<int>& phase_of,
                    const Polygon& polygon, const geometry::SceneDesc& scene, Vec2 lo, Vec2 hi, int width_px) {
  const double w = hi[0] - lo[0], h = hi[1] - lo[1];
  const double scale = width_px / w;
  const int height_px = static_cast<int>(h * scale + 0.5);
  const bool edges = count <= 400000;
  AtomicFile file(path);
  char buf[256];
  std::snprintf(buf, sizeof buf,
                "<svg xmlns=\"http://www.w3.org/2000/svg\" width=\"%d\" height=\"%d\" viewBox=\"0 0 %d %d\">\n",
                width_px, height_px, width_px, height_px);
  file.write(buf);
  file.write("<rect width=\"100%\" height=\"100%\" fill=\"white\"/>\n");
  std::vector<Vec2> points;
  for (std::size_t p = 0; p < scene.phases.size(); ++p) {
    const int id = scene.phases[p].id;
    std::snprintf(buf, sizeof buf, "<path fill=\"%s\" stroke=\"%s\" stroke-width=\"%.2f\" d=\"", colour_of(p),
                  edges ? "#202020" : "none", edges ? 0.3 : 0.0);
    file.write(buf);
    std::string s;
    for (std::size_t c = 0; c < count; ++c) {
      if (phase_of[c] != id) continue;
      points.clear();
      polygon(c, points);
      s.clear();
      for (std::size_t k = 0; k < points.size(); ++k) {
        // SVG's y axis points down.
        std::snprintf(buf, sizeof buf, "%c%.2f %.2f", k == 0 ? 'M' : 'L', (points[k][0] - lo[0]) * scale,
                      (h - (points[k][1] - lo[1])) * scale);
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

}  // namespace

SlicePolygons slice_mesh(const mesh::Mesh3& m, int axis, double at) {
  const int u = axis == 0 ? 1 : 0, v = axis == 2 ? 1 : 2;
  SlicePolygons out;
  std::vector<Vec2> ring;
  for (std::size_t c = 0; c < m.cell_count(); ++c) {
    const LocalId* n = m.cell(c);
    Vec3 p[4];
    double s[4];
    bool below = false, above = false;
    for (int k = 0; k < 4; ++k) {
      p[k] = m.point(n[k]);
      s[k] = p[k][axis] - at;
      (s[k] < 0 ? below : above) = true;
    }
    if (!below || !above) continue;
    // The plane meets the edges from a vertex below to one on or above it (at that vertex
    // when it lies on the plane).
    ring.clear();
    for (int i = 0; i < 4; ++i)
      for (int j = 0; j < 4; ++j) {
        if (!(s[i] < 0 && s[j] >= 0)) continue;
        const double t = s[i] / (s[i] - s[j]);
        const Vec2 q = s[j] == 0 ? Vec2{p[j][u], p[j][v]}
                                 : Vec2{p[i][u] + t * (p[j][u] - p[i][u]), p[i][v] + t * (p[j][v] - p[i][v])};
        if (std::none_of(ring.begin(), ring.end(), [&](const Vec2& r) { return r[0] == q[0] && r[1] == q[1]; }))
          ring.push_back(q);
      }
    if (ring.size() < 3) continue;  // the plane only touches an edge or a vertex
    // Convex: counter-clockwise by angle around the centroid.
    Vec2 centre{0, 0};
    for (const Vec2& q : ring) centre[0] += q[0] / static_cast<double>(ring.size()), centre[1] += q[1] / static_cast<double>(ring.size());
    std::sort(ring.begin(), ring.end(), [&](const Vec2& a, const Vec2& b) {
      return std::atan2(a[1] - centre[1], a[0] - centre[0]) < std::atan2(b[1] - centre[1], b[0] - centre[0]);
    });
    out.points.insert(out.points.end(), ring.begin(), ring.end());
    out.offsets.push_back(out.points.size());
    out.phase.push_back(m.cell_phase[c]);
  }
  return out;
}

void write_mesh_svg(const std::string& path, const mesh::Mesh2& m, const geometry::SceneDesc& scene, int width_px) {
  write_polygons(
      path, m.cell_count(), m.cell_phase,
      [&](std::size_t c, std::vector<Vec2>& points) {
        for (int k = 0; k < 3; ++k) points.push_back(m.point(m.cell(c)[k]));
      },
      scene, {scene.domain_min[0], scene.domain_min[1]}, {scene.domain_max[0], scene.domain_max[1]}, width_px);
}

void write_mesh_svg(const std::string& path, const mesh::Mesh3& m, const geometry::SceneDesc& scene,
                    const SlicePlane& plane, int width_px) {
  const auto axis = static_cast<std::size_t>(plane.axis);
  const double lo = scene.domain_min[axis], hi = scene.domain_max[axis];
  const double at = plane.at.value_or(0.5 * (lo + hi));
  if (!(at > lo && at < hi))
  {
    char text[160];
    std::snprintf(text, sizeof text, "the slice plane %c = %g is not inside the domain (%g, %g)", "xyz"[axis], at, lo, hi);
    throw InputError("--svg-at", "", text);
  }
  const SlicePolygons slice = slice_mesh(m, plane.axis, at);
  const std::size_t u = axis == 0 ? 1 : 0, v = axis == 2 ? 1 : 2;
  write_polygons(
      path, slice.size(), slice.phase,
      [&](std::size_t i, std::vector<Vec2>& points) {
        points.assign(slice.points.begin() + static_cast<std::ptrdiff_t>(slice.offsets[i]),
                      slice.points.begin() + static_cast<std::ptrdiff_t>(slice.offsets[i + 1]));
      },
      scene, {scene.domain_min[u], scene.domain_min[v]}, {scene.domain_max[u], scene.domain_max[v]}, width_px);
}

}  // namespace cisamr::io
