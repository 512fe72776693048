// PARTS.json and the SVG drawing of a partition.
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <sstream>

#include <nlohmann/json.hpp>

#include "geometry/shapes.hpp"
#include "partition/load_field.hpp"
#include "partition/partition.hpp"

namespace cisamr::partition {
namespace {

// One boolean when every axis agrees (the scene's own form), else one per axis.
nlohmann::json periodic_json(const std::array<bool, 3>& periodic, int dim) {
  bool same = true;
  for (int d = 1; d < dim; ++d) same &= periodic[static_cast<std::size_t>(d)] == periodic[0];
  if (same) return periodic[0];
  nlohmann::json axes = nlohmann::json::array();
  for (int d = 0; d < dim; ++d) axes.push_back(periodic[static_cast<std::size_t>(d)]);
  return axes;
}

using json = nlohmann::ordered_json;  // keys in the order written
using namespace geometry;

json vec(const Vec3& v, int dim) {
  json a = json::array();
  for (int d = 0; d < dim; ++d) a.push_back(v[d]);
  return a;
}
json ivec(const std::array<std::int64_t, 3>& v, int dim) {
  json a = json::array();
  for (int d = 0; d < dim; ++d) a.push_back(v[d]);
  return a;
}

std::string fmt(double v) {
  char buf[32];
  std::snprintf(buf, sizeof buf, "%.6g", v);
  return buf;
}

// Fill colour from white (no load) to red (the maximum load).
std::string heat(double load, double max) {
  const double t = max > 0 ? std::clamp(load / max, 0.0, 1.0) : 0;
  const int gb = static_cast<int>(std::lround(255 * (1 - 0.45 * t)));
  char buf[16];
  std::snprintf(buf, sizeof buf, "#ff%02x%02x", gb, gb);
  return buf;
}

struct Panel {  // one drawing: domain x/y → pixels, y up
  double x0, y0, scale, offset_px, height_px;
  double px(double x) const { return offset_px + (x - x0) * scale; }
  double py(double y) const { return height_px - (y - y0) * scale; }
};

struct PixelRect {  // a part box in the panel's pixels
  double x, y, w, h;
  std::string svg_attributes() const {
    return "x=\"" + fmt(x) + "\" y=\"" + fmt(y) + "\" width=\"" + fmt(w) + "\" height=\"" + fmt(h) + "\"";
  }
};

// The parts cut by the plane z (all of them in 2D), with their rectangles.
template <class Draw>
void for_each_part_rect(const Partition& p, const Panel& pan, double z, Draw draw) {
  for (const auto& part : p.parts) {
    if (p.dimension == 3 && (z < part.box.min[2] || z > part.box.max[2])) continue;
    draw(part, PixelRect{pan.px(part.box.min[0]), pan.py(part.box.max[1]),
                         (part.box.max[0] - part.box.min[0]) * pan.scale, (part.box.max[1] - part.box.min[1]) * pan.scale});
  }
}

void draw_boxes(std::ostringstream& s, const Partition& p, const Panel& pan, double z) {
  const double maxl = p.max_load();
  for_each_part_rect(p, pan, z, [&](const Part& part, const PixelRect& r) {
    s << "<rect " << r.svg_attributes() << " fill=\"" << heat(part.load, maxl) << "\" stroke=\"none\"><title>part "
      << part.id << " load " << fmt(part.load) << "</title></rect>\n";
  });
}

void draw_outlines(std::ostringstream& s, const Partition& p, const Panel& pan, double z) {
  for_each_part_rect(p, pan, z, [&](const Part& part, const PixelRect& r) {
    s << "<rect " << r.svg_attributes() << " fill=\"none\" stroke=\"#1040a0\" stroke-width=\"1.5\"/>\n";
    s << "<text x=\"" << fmt(r.x + r.w / 2) << "\" y=\"" << fmt(r.y + r.h / 2) << "\" font-size=\""
      << fmt(std::clamp(std::min(r.w, r.h) / 4, 6.0, 16.0)) << "\" text-anchor=\"middle\" fill=\"#1040a0\">" << part.id
      << "</text>\n";
  });
}

void draw_inclusions_2d(std::ostringstream& s, const SceneDesc& scene, const Panel& pan) {
  const std::string style = " fill=\"#606060\" fill-opacity=\"0.55\" stroke=\"#303030\" stroke-width=\"0.3\"";
  // Every family alike: a polygon through 64 boundary pieces (an exact polygon's edges
  // are cut, not bent).
  for (const auto& inc : scene.inclusions) {
    s << "<polygon points=\"";
    for (const Vec3& q : shape_boundary_samples(inc.shape, shape_boundary_measure(inc.shape) / 64))
      s << fmt(pan.px(q[0])) << "," << fmt(pan.py(q[1])) << " ";
    s << "\"" << style << "/>\n";
  }
}

// Sections of the 3D inclusions by the plane z = z0 (spheres, ellipsoids, axis fibres).
void draw_inclusions_slice(std::ostringstream& s, const SceneDesc& scene, const Panel& pan, double z0) {
  const std::string style = " fill=\"#606060\" fill-opacity=\"0.55\" stroke=\"#303030\" stroke-width=\"0.3\"";
  auto ellipse = [&](double cx, double cy, double a, double b, double angle) {
    s << "<ellipse cx=\"" << fmt(pan.px(cx)) << "\" cy=\"" << fmt(pan.py(cy)) << "\" rx=\"" << fmt(a * pan.scale)
      << "\" ry=\"" << fmt(b * pan.scale) << "\" transform=\"rotate(" << fmt(-angle * 180 / M_PI) << " "
      << fmt(pan.px(cx)) << " " << fmt(pan.py(cy)) << ")\"" << style << "/>\n";
  };
  for (const auto& inc : scene.inclusions) {
    if (auto* sp = std::get_if<Sphere>(&inc.shape)) {
      const double dz = z0 - sp->center[2];
      if (std::abs(dz) < sp->radius) {
        const double r = std::sqrt(sp->radius * sp->radius - dz * dz);
        ellipse(sp->center[0], sp->center[1], r, r, 0);
      }
    } else if (auto* e = std::get_if<Ellipsoid>(&inc.shape)) {
      double A[3][3] = {};
      for (int i = 0; i < 3; ++i)
        for (int j = 0; j < 3; ++j)
          for (int k = 0; k < 3; ++k)
            A[i][j] += e->rotation[i][k] * e->rotation[j][k] / (e->semi_axes[k] * e->semi_axes[k]);
      const double dz = z0 - e->center[2];
      const double b0 = A[0][2] * dz, b1 = A[1][2] * dz;
      const double det = A[0][0] * A[1][1] - A[0][1] * A[0][1];
      const double w0 = -(A[1][1] * b0 - A[0][1] * b1) / det, w1 = -(-A[0][1] * b0 + A[0][0] * b1) / det;
      const double k = 1 - A[2][2] * dz * dz - (b0 * w0 + b1 * w1);
      if (k <= 0) continue;
      const double tr = A[0][0] + A[1][1], disc = std::sqrt(std::max(0.0, tr * tr / 4 - det));
      const double l1 = tr / 2 - disc, l2 = tr / 2 + disc;  // l1 ≤ l2: l1 gives the major axis
      const double angle = std::abs(A[0][1]) > 1e-300 ? std::atan2(l1 - A[0][0], A[0][1]) : (A[0][0] <= A[1][1] ? 0 : M_PI / 2);
      ellipse(e->center[0] + w0, e->center[1] + w1, std::sqrt(k / l1), std::sqrt(k / l2), angle);
    } else if (auto* c = std::get_if<Cylinder>(&inc.shape)) {
      Vec3 u{c->end[0] - c->start[0], c->end[1] - c->start[1], c->end[2] - c->start[2]};
      if (std::abs(u[2]) < 1e-12 * (std::abs(u[0]) + std::abs(u[1]))) {  // lies in z-planes: a band
        const double dz = z0 - c->start[2];
        if (std::abs(dz) >= c->radius) continue;
        const double half = std::sqrt(c->radius * c->radius - dz * dz);
        const double len = std::hypot(u[0], u[1]);
        const double nx = -u[1] / len * half, ny = u[0] / len * half;
        s << "<polygon points=\"" << fmt(pan.px(c->start[0] + nx)) << "," << fmt(pan.py(c->start[1] + ny)) << " "
          << fmt(pan.px(c->end[0] + nx)) << "," << fmt(pan.py(c->end[1] + ny)) << " " << fmt(pan.px(c->end[0] - nx))
          << "," << fmt(pan.py(c->end[1] - ny)) << " " << fmt(pan.px(c->start[0] - nx)) << ","
          << fmt(pan.py(c->start[1] - ny)) << "\"" << style << "/>\n";
      } else if (std::abs(u[0]) + std::abs(u[1]) < 1e-12 * std::abs(u[2])) {  // along z: a disc
        if (z0 >= std::min(c->start[2], c->end[2]) && z0 <= std::max(c->start[2], c->end[2]))
          ellipse(c->start[0], c->start[1], c->radius, c->radius, 0);
      }
    }
  }
}

}  // namespace

std::string to_json(const Partition& p, const std::string& scene_path) {
  const int dim = p.dimension;
  json doc;
  doc["format"] = "cisamr-partition/1";
  doc["scene"] = scene_path;
  doc["method"] = p.method;
  doc["dimension"] = dim;
  doc["domain"] = {{"min", vec(p.domain.min, dim)}, {"max", vec(p.domain.max, dim)}, {"periodic", periodic_json(p.periodic, dim)}};
  doc["h"] = p.h;
  doc["lattice_cells"] = ivec(p.cells, dim);
  doc["load_exponent"] = p.load_exponent;
  if (p.method == "algorithm1") {
    json leaves = json::array();
    for (int d = 0; d < dim; ++d) leaves.push_back(p.leaves[d]);
    doc["over_decomposition"] = leaves;
    doc["merges"] = p.merges;
  }
  if (p.method != "uniform-grid") doc["rebalance_moves"] = p.rebalance_moves;
  doc["summary"] = {{"parts", p.parts.size()},
                    {"total_load", p.total_load},
                    {"max_load", p.max_load()},
                    {"mean_load", p.mean_load()},
                    {"imbalance", p.imbalance()},
                    {"shared_face_measure", p.shared_face_measure()}};
  if (p.ghost_weight > 0) {  // the cuts balanced each box's load plus its ghost's
    doc["summary"]["ghost_cells"] = p.ghost_cells;
    doc["summary"]["ghost_weight"] = p.ghost_weight;
    doc["summary"]["max_cost"] = p.max_cost();
    doc["summary"]["mean_cost"] = p.mean_cost();
  }
  json parts = json::array();
  for (const auto& part : p.parts) {
    json j;
    j["id"] = part.id;
    j["rank"] = part.rank;
    j["min"] = vec(part.box.min, dim);
    j["max"] = vec(part.box.max, dim);
    j["lattice_min"] = ivec(part.lattice_min, dim);
    j["lattice_max"] = ivec(part.lattice_max, dim);
    j["load"] = part.load;
    if (p.ghost_weight > 0) j["cost"] = part.cost;
    json nbs = json::array();
    for (const auto& nb : part.neighbours) {
      json n;
      n["part"] = nb.part;
      n["axis"] = nb.axis;
      n["side"] = nb.side;
      n["face"] = {{"min", vec(nb.face.min, dim)}, {"max", vec(nb.face.max, dim)}};
      n["periodic"] = nb.periodic;
      if (nb.periodic) n["shift"] = vec(nb.shift, dim);
      nbs.push_back(n);
    }
    j["neighbours"] = nbs;
    j["inclusions"] = part.inclusions;
    parts.push_back(j);
  }
  // One line per header field and per part: readable, diffable, and still plain JSON.
  std::string out = "{\n";
  for (auto it = doc.begin(); it != doc.end(); ++it) out += " \"" + it.key() + "\": " + it.value().dump() + ",\n";
  out += " \"parts\": [\n";
  for (std::size_t i = 0; i < parts.size(); ++i) out += "  " + parts[i].dump() + (i + 1 < parts.size() ? ",\n" : "\n");
  out += " ]\n}\n";
  return out;
}

std::string to_svg(const Partition& p, const SceneDesc& scene) {
  const double wx = p.domain.max[0] - p.domain.min[0], wy = p.domain.max[1] - p.domain.min[1];
  const double panel_px = 900;
  const double scale = panel_px / std::max(wx, wy);
  const double height = wy * scale;
  const int panels = p.dimension == 2 ? 1 : 3;
  const double gap_px = 30;
  std::ostringstream s;
  s << "<svg xmlns=\"http://www.w3.org/2000/svg\" width=\"" << fmt(panels * wx * scale + (panels - 1) * gap_px)
    << "\" height=\"" << fmt(height + 24) << "\" font-family=\"sans-serif\">\n";
  s << "<rect width=\"100%\" height=\"100%\" fill=\"white\"/>\n";
  for (int k = 0; k < panels; ++k) {
    Panel pan{p.domain.min[0], p.domain.min[1], scale, k * (wx * scale + gap_px), height};
    const double z = p.dimension == 3 ? p.domain.min[2] + (0.22 + 0.28 * k) * (p.domain.max[2] - p.domain.min[2]) : 0;
    draw_boxes(s, p, pan, z);
    if (p.dimension == 2) draw_inclusions_2d(s, scene, pan);
    else draw_inclusions_slice(s, scene, pan, z);
    draw_outlines(s, p, pan, z);
    s << "<text x=\"" << fmt(pan.offset_px + 4) << "\" y=\"" << fmt(height + 18) << "\" font-size=\"13\">";
    if (p.dimension == 3) s << "z = " << fmt(z) << ": ";
    s << p.parts.size() << " parts (" << p.method << "), max/mean load " << fmt(p.imbalance()) << "</text>\n";
  }
  s << "</svg>\n";
  return s.str();
}

}  // namespace cisamr::partition
