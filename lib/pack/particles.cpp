#include "pack/particles.hpp"

#include <algorithm>
#include <cmath>
#include <cstring>
#include <fstream>
#include <sstream>
#include <stdexcept>

#include "core/error.hpp"
#include "core/overloaded.hpp"
#include "geometry/shapes.hpp"

namespace cisamr::pack {
namespace {

using namespace geometry;

double sq(double x) { return x * x; }

Rotation3 rotation_z(double angle) {
  const double c = std::cos(angle), s = std::sin(angle);
  return {{{c, -s, 0}, {s, c, 0}, {0, 0, 1}}};
}

// Control points of one of our periodic cubic blobs (drop the 3 wrapped ones).
std::vector<Vec2> blob_control_points(const NurbsCurve& c) {
  if (c.degree != 3 || c.control_points.size() < 7)
    throw std::invalid_argument("pack: only periodic cubic NURBS blobs are supported");
  return {c.control_points.begin(), c.control_points.end() - 3};
}

double polyline_area(const std::vector<Vec3>& p) {
  double a = 0;
  for (std::size_t i = 0, n = p.size(); i < n; ++i) {
    const Vec3& u = p[i];
    const Vec3& v = p[(i + 1) % n];
    a += u[0] * v[1] - v[0] * u[1];
  }
  return 0.5 * std::abs(a);
}

bool polyline_contains(const std::vector<Vec3>& p, const Vec3& q) {
  bool inside = false;
  for (std::size_t i = 0, n = p.size(), j = n - 1; i < n; j = i++) {
    const Vec3& a = p[i];
    const Vec3& b = p[j];
    if ((a[1] > q[1]) != (b[1] > q[1]) &&
        q[0] < (b[0] - a[0]) * (q[1] - a[1]) / (b[1] - a[1]) + a[0])
      inside = !inside;
  }
  return inside;
}

double point_segment_distance(const Vec3& p, const Vec3& a, const Vec3& b) {
  Vec3 ab{b[0] - a[0], b[1] - a[1], b[2] - a[2]};
  Vec3 ap{p[0] - a[0], p[1] - a[1], p[2] - a[2]};
  const double l2 = ab[0] * ab[0] + ab[1] * ab[1] + ab[2] * ab[2];
  double t = l2 > 0 ? (ap[0] * ab[0] + ap[1] * ab[1] + ap[2] * ab[2]) / l2 : 0;
  t = std::clamp(t, 0.0, 1.0);
  return std::sqrt(sq(ap[0] - t * ab[0]) + sq(ap[1] - t * ab[1]) + sq(ap[2] - t * ab[2]));
}

// Is the point within `margin` of the closed polyline region?
bool polyline_near(const std::vector<Vec3>& p, const Vec3& q, double margin) {
  if (polyline_contains(p, q)) return true;
  for (std::size_t i = 0, n = p.size(); i < n; ++i)
    if (point_segment_distance(q, p[i], p[(i + 1) % n]) <= margin) return true;
  return false;
}

std::vector<Vec3> polygon_points(const Polygon& p) {
  std::vector<Vec3> v;
  for (const auto& q : p.vertices) v.push_back({q[0], q[1], 0});
  return v;
}

// Quadratic form of an ellipse/ellipsoid at p: Σ (body_i / s_i)² (1 on the boundary).
double ellipsoid_form(const Vec3& c, const Vec3& axes, const Rotation3& r, const Vec3& p, int dim) {
  double q = 0;
  for (int i = 0; i < dim; ++i) {
    double b = 0;
    for (int j = 0; j < dim; ++j) b += r[j][i] * (p[j] - c[j]);
    q += sq(b / axes[i]);
  }
  return q;
}

// Largest distance between consecutive points of a closed polyline: a bound of how far the
// sampled curve strays from the polyline (each arc is within half its length of an end).
double max_chord(const std::vector<Vec3>& p) {
  double m = 0;
  for (std::size_t i = 0, n = p.size(); i < n; ++i) {
    const Vec3& a = p[i];
    const Vec3& b = p[(i + 1) % n];
    m = std::max(m, std::hypot(b[0] - a[0], b[1] - a[1]));
  }
  return m;
}

}  // namespace

std::vector<Vec3> periodic_cubic_polyline(const std::vector<Vec2>& cp, int per_span) {
  const std::size_t n = cp.size();
  std::vector<Vec3> out;
  out.reserve(n * per_span);
  for (std::size_t i = 0; i < n; ++i) {
    const Vec2& p0 = cp[i];
    const Vec2& p1 = cp[(i + 1) % n];
    const Vec2& p2 = cp[(i + 2) % n];
    const Vec2& p3 = cp[(i + 3) % n];
    for (int k = 0; k < per_span; ++k) {
      const double t = static_cast<double>(k) / per_span;
      const double b0 = (1 - t) * (1 - t) * (1 - t) / 6;
      const double b1 = (3 * t * t * t - 6 * t * t + 4) / 6;
      const double b2 = (-3 * t * t * t + 3 * t * t + 3 * t + 1) / 6;
      const double b3 = t * t * t / 6;
      out.push_back({b0 * p0[0] + b1 * p1[0] + b2 * p2[0] + b3 * p3[0],
                     b0 * p0[1] + b1 * p1[1] + b2 * p2[1] + b3 * p3[1], 0});
    }
  }
  return out;
}

Box3 particle_box(const Shape& shape) {
  if (std::holds_alternative<StlSurface>(shape) || std::holds_alternative<NurbsSurface>(shape))
    throw std::invalid_argument("pack: unsupported shape");
  return shape_holding_box(shape);  // a blob: the control points' box contains it
}

double particle_measure(const Shape& shape) {
  if (const auto* c = std::get_if<NurbsCurve>(&shape))  // the packer's blobs, as the containment test sees them
    return polyline_area(periodic_cubic_polyline(blob_control_points(*c), 64));
  if (std::holds_alternative<StlSurface>(shape) || std::holds_alternative<NurbsSurface>(shape))
    throw std::invalid_argument("pack: unsupported shape");
  return shape_measure(shape);
}

ConvexBody particle_body(const Shape& shape) {
  ConvexBody b;
  auto hull = [&](std::vector<Vec3> pts) {
    b.kind = ConvexBody::Kind::hull;
    Vec3 c{};
    for (const auto& p : pts)
      for (int d = 0; d < 3; ++d) c[d] += p[d] / pts.size();
    double r = 0;
    for (const auto& p : pts) r = std::max(r, std::sqrt(sq(p[0] - c[0]) + sq(p[1] - c[1]) + sq(p[2] - c[2])));
    b.reference = c;
    b.bound_radius = r;
    b.points = std::move(pts);
  };
  std::visit(Overloaded{
                 [&](const Circle& c) {
                   b.kind = ConvexBody::Kind::ball;
                   b.center = b.reference = {c.center[0], c.center[1], 0};
                   b.radius = b.bound_radius = c.radius;
                 },
                 [&](const Ellipse& e) {
                   b.kind = ConvexBody::Kind::ellipsoid;
                   b.center = b.reference = {e.center[0], e.center[1], 0};
                   b.semi_axes = {e.semi_axes[0], e.semi_axes[1], 0};
                   b.rotation = rotation_z(e.angle);
                   b.bound_radius = std::max(e.semi_axes[0], e.semi_axes[1]);
                 },
                 [&](const Polygon& p) { hull(polygon_points(p)); },
                 [&](const NurbsCurve& c) {
                   std::vector<Vec3> pts;
                   for (const auto& q : blob_control_points(c)) pts.push_back({q[0], q[1], 0});
                   hull(std::move(pts));
                 },
                 [&](const Sphere& s) {
                   b.kind = ConvexBody::Kind::ball;
                   b.center = b.reference = s.center;
                   b.radius = b.bound_radius = s.radius;
                 },
                 [&](const Ellipsoid& e) {
                   b.kind = ConvexBody::Kind::ellipsoid;
                   b.center = b.reference = e.center;
                   b.semi_axes = e.semi_axes;
                   b.rotation = e.rotation;
                   b.bound_radius = std::max({e.semi_axes[0], e.semi_axes[1], e.semi_axes[2]});
                 },
                 [&](const Cylinder& c) {
                   b.kind = ConvexBody::Kind::cylinder;
                   b.center = c.start;
                   b.end = c.end;
                   b.radius = c.radius;
                   for (int d = 0; d < 3; ++d) b.reference[d] = 0.5 * (c.start[d] + c.end[d]);
                   const double half = 0.5 * std::sqrt(sq(c.end[0] - c.start[0]) + sq(c.end[1] - c.start[1]) +
                                                       sq(c.end[2] - c.start[2]));
                   b.bound_radius = std::sqrt(half * half + c.radius * c.radius);
                 },
                 [&](const auto&) { throw std::invalid_argument("pack: unsupported shape"); },
             },
             shape);
  return b;
}

bool particle_contains(const Shape& shape, const Vec3& p) {
  return std::visit(
      Overloaded{
          [&](const Circle& c) { return sq(p[0] - c.center[0]) + sq(p[1] - c.center[1]) <= sq(c.radius); },
          [&](const Ellipse& e) {
            return ellipsoid_form({e.center[0], e.center[1], 0}, {e.semi_axes[0], e.semi_axes[1], 1},
                                  rotation_z(e.angle), p, 2) <= 1;
          },
          [&](const Polygon& poly) { return polyline_contains(polygon_points(poly), p); },
          [&](const NurbsCurve& c) {
            return polyline_contains(periodic_cubic_polyline(blob_control_points(c), 16), p);
          },
          [&](const Sphere& s) {
            return sq(p[0] - s.center[0]) + sq(p[1] - s.center[1]) + sq(p[2] - s.center[2]) <= sq(s.radius);
          },
          [&](const Ellipsoid& e) { return ellipsoid_form(e.center, e.semi_axes, e.rotation, p, 3) <= 1; },
          [&](const Cylinder& c) {
            Vec3 u{c.end[0] - c.start[0], c.end[1] - c.start[1], c.end[2] - c.start[2]};
            const double l2 = sq(u[0]) + sq(u[1]) + sq(u[2]);
            const double t = ((p[0] - c.start[0]) * u[0] + (p[1] - c.start[1]) * u[1] + (p[2] - c.start[2]) * u[2]) / l2;
            if (t < 0 || t > 1) return false;
            return point_segment_distance(p, c.start, c.end) <= c.radius;
          },
          [&](const auto&) { return false; },
      },
      shape);
}

std::uint64_t secondary_cover(const Shape& shape, const Box3& box, int dim) {
  const int n = secondary_cells_per_axis(dim);
  Vec3 cell{};
  double half_diag2 = 0;
  for (int d = 0; d < dim; ++d) {
    cell[d] = (box.max[d] - box.min[d]) / n;
    half_diag2 += sq(0.5 * cell[d]);
  }
  const double half_diag = std::sqrt(half_diag2);
  // "May this cell (centre p, half-diagonal δ) touch the particle?" — a superset test.
  std::vector<Vec3> outline;
  double outline_margin = 0;
  if (auto* poly = std::get_if<Polygon>(&shape)) outline = polygon_points(*poly);
  if (auto* c = std::get_if<NurbsCurve>(&shape)) {
    outline = periodic_cubic_polyline(blob_control_points(*c), 16);
    outline_margin = max_chord(outline);
  }
  auto may_touch = [&](const Vec3& p) -> bool {
    return std::visit(
        Overloaded{
            [&](const Ellipse& e) {
              // E ⊕ disk(δ) ⊆ (1 + δ/b) E, b the smaller semi-axis.
              const double bmin = std::min(e.semi_axes[0], e.semi_axes[1]);
              return ellipsoid_form({e.center[0], e.center[1], 0}, {e.semi_axes[0], e.semi_axes[1], 1},
                                    rotation_z(e.angle), p, 2) <= sq(1 + half_diag / bmin);
            },
            [&](const Ellipsoid& e) {
              const double bmin = std::min({e.semi_axes[0], e.semi_axes[1], e.semi_axes[2]});
              return ellipsoid_form(e.center, e.semi_axes, e.rotation, p, 3) <= sq(1 + half_diag / bmin);
            },
            [&](const Cylinder& c) { return point_segment_distance(p, c.start, c.end) <= c.radius + half_diag; },
            [&](const Polygon&) { return polyline_near(outline, p, half_diag); },
            [&](const NurbsCurve&) { return polyline_near(outline, p, half_diag + outline_margin); },
            [&](const auto&) { return true; },
        },
        shape);
  };
  std::uint64_t mask = 0;
  const int nz = dim == 3 ? n : 1;
  for (int k = 0; k < nz; ++k)
    for (int j = 0; j < n; ++j)
      for (int i = 0; i < n; ++i) {
        Vec3 p{box.min[0] + (i + 0.5) * cell[0], box.min[1] + (j + 0.5) * cell[1],
               dim == 3 ? box.min[2] + (k + 0.5) * cell[2] : 0.0};
        if (may_touch(p)) mask |= std::uint64_t{1} << (i + n * (j + n * k));
      }
  return mask;
}

Shape scaled_about_origin(const Shape& shape, double f) {
  return std::visit(
      Overloaded{
          [&](Circle c) -> Shape { c.radius *= f; return c; },
          [&](Ellipse e) -> Shape { e.semi_axes[0] *= f; e.semi_axes[1] *= f; return e; },
          [&](Polygon p) -> Shape {
            for (auto& v : p.vertices) { v[0] *= f; v[1] *= f; }
            return p;
          },
          [&](NurbsCurve c) -> Shape {
            for (auto& v : c.control_points) { v[0] *= f; v[1] *= f; }
            return c;
          },
          [&](Sphere s) -> Shape { s.radius *= f; return s; },
          [&](Ellipsoid e) -> Shape { for (auto& a : e.semi_axes) a *= f; return e; },
          [&](Cylinder c) -> Shape { c.radius *= f; return c; },  // fibres keep their length
          [&](StlSurface s) -> Shape {
            s.scale *= f;
            for (auto& t : s.translate) t *= f;
            return s;
          },
          [&](const auto& s) -> Shape { return s; },  // families the packer does not generate
      },
      shape);
}

std::vector<double> read_stl_triangles(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  if (!in) throw InputError(path, "", "cannot open the STL file");
  std::string data((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  std::vector<double> tri;
  const bool looks_ascii = data.compare(0, 5, "solid") == 0 && data.find("facet") != std::string::npos;
  if (looks_ascii) {
    std::istringstream s(data);
    std::string word;
    while (s >> word) {
      if (word != "vertex") continue;
      double x, y, z;
      if (!(s >> x >> y >> z)) throw InputError(path, "", "malformed ASCII STL vertex");
      tri.insert(tri.end(), {x, y, z});
    }
    if (tri.size() % 9 != 0 || tri.empty()) throw InputError(path, "", "ASCII STL without whole triangles");
    return tri;
  }
  if (data.size() < 84) throw InputError(path, "", "binary STL shorter than its header");
  std::uint32_t count;
  std::memcpy(&count, data.data() + 80, 4);
  if (data.size() < 84 + 50ull * count || count == 0)
    throw InputError(path, "", "binary STL shorter than its triangle count says");
  for (std::uint32_t t = 0; t < count; ++t) {
    const char* rec = data.data() + 84 + 50ull * t + 12;
    for (int k = 0; k < 9; ++k) {
      float v;
      std::memcpy(&v, rec + 4 * k, 4);
      tri.push_back(v);
    }
  }
  return tri;
}

}  // namespace cisamr::pack
