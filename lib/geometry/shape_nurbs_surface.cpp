// NURBS surfaces: the scene members, and the questions about a descriptor, answered on the
// exact surface through its body (surface_body.hpp); the oracle's model is
// nurbs_surface_model.cpp.
#include "geometry/shape_nurbs_surface.hpp"

#include <algorithm>
#include <array>
#include <cmath>
#include <optional>
#include <stdexcept>

#include "core/error.hpp"
#include "geometry/shape_fields.hpp"
#include "geometry/shape_nurbs_curve.hpp"
#include "geometry/nurbs_surface_model.hpp"
#include "geometry/shape_model.hpp"
#include "geometry/surface_body.hpp"

namespace cisamr::geometry {
namespace {

// One patch: degrees, knots (the counts follow from them), the control net and its
// weights, each as count_v rows of count_u or one flat list u fastest (FieldReader grids).
NurbsPatch read_patch(const FieldReader& f) {
  f.allow_keys({"degree", "knots_u", "knots_v", "control_points", "weights"});
  NurbsPatch p;
  std::array<std::size_t, 2> counts{};
  for (int a = 0; a < 2; ++a) {
    p.degree[a] = f.integer_of("degree", 2, static_cast<std::size_t>(a), 1, 30, "degree in u and v");
    const char* key = a == 0 ? "knots_u" : "knots_v";
    const std::size_t size = f.array_size(key);
    const std::size_t minimum = 2 * static_cast<std::size_t>(p.degree[a] + 1);
    if (size < minimum)
      f.fail(key, "a degree-" + std::to_string(p.degree[a]) + " direction needs at least " + std::to_string(minimum) +
                      " knots, got " + std::to_string(size));
    (a == 0 ? p.knots_u : p.knots_v) = read_knots(f, key, p.degree[a], 0);
    counts[a] = size - static_cast<std::size_t>(p.degree[a]) - 1;
  }
  p.control_points = f.point_grid3("control_points", counts[0], counts[1]);
  if (f.has("weights")) p.weights = f.number_grid("weights", counts[0], counts[1], /*positive=*/true);
  return p;
}

class NurbsSurfaceFamily final : public FamilyOf<NurbsSurface> {
 public:
  std::string_view name() const override { return "nurbs_surface"; }
  int dimension() const override { return 3; }
  Shape read(const FieldReader& f) const override {
    f.allow_keys({"patches", "scale", "rotation", "translate"});
    NurbsSurface surface;
    if (f.array_size("patches") == 0) f.fail("patches", "needs at least one patch");
    f.objects("patches", [&](const FieldReader& patch) { surface.patches.push_back(read_patch(patch)); });
    read_placement(f, surface);
    return surface;
  }
  // The flat form (u fastest) and the placement where it is not the default, as for STL:
  // reading it back gives the same descriptor bit for bit.
  void write(const Shape& shape, FieldWriter& f) const override {
    const NurbsSurface& s = of(shape);
    write_placement(s, f);
    f.objects("patches", s.patches.size(), [&](FieldWriter& w, std::size_t i) {
      const NurbsPatch& p = s.patches[i];
      w.integers("degree", {p.degree[0], p.degree[1]});
      w.numbers("knots_u", p.knots_u);
      w.numbers("knots_v", p.knots_v);
      w.points("control_points", p.control_points);
      if (!p.weights.empty()) w.numbers("weights", p.weights);
    });
  }
  // The body of the descriptor, once per process; a surface that does not close a volume
  // (which the oracle refuses with its problem) has none: empty answers below.
  Box3 bounding_box(const Shape& s) const override {
    const auto body = surface::cached_body(of(s));
    return body ? body->box : holding_box(s);
  }
  // The box of the placed control points: with positive weights it holds the surface.
  Box3 holding_box(const Shape& s) const override {
    Box3 b{{INFINITY, INFINITY, INFINITY}, {-INFINITY, -INFINITY, -INFINITY}};
    for (const NurbsPatch& patch : of(s).patches)
      for (const Vec3& x : patch.control_points) {
        const Vec3 p = surface::place(of(s), x);
        for (int d = 0; d < 3; ++d) b.min[d] = std::min(b.min[d], p[d]), b.max[d] = std::max(b.max[d], p[d]);
      }
    return b;
  }
  double measure(const Shape& s) const override {
    const auto body = surface::cached_body(of(s));
    return body ? surface::volume(*body) : 0.0;
  }
  double boundary_measure(const Shape& s) const override {
    const auto body = surface::cached_body(of(s));
    return body ? surface::area(*body) : 0.0;
  }
  std::vector<Vec3> boundary_samples(const Shape& s, double spacing) const override {
    const auto body = surface::cached_body(of(s));
    return body ? surface::surface_points(*body, spacing) : std::vector<Vec3>{};
  }
  bool contains(const Shape& s, const Vec3& p) const override {
    const auto body = surface::cached_body(of(s));
    return body && point_in_box<3>(p, body->box) && surface::side(*body, p) >= 0;
  }
  void translate(Shape& s, const Vec3& o) const override {
    for (int k = 0; k < 3; ++k) of(s).translate[k] += o[k];
  }
  // Distances between two surfaces from their bodies' cells (levels refine like spheres'),
  // not from their boxes.
  std::optional<bool> overlap_same_family(const Shape& a, const Shape& b, double gap) const override {
    const auto ba = surface::cached_body(of(a)), bb = surface::cached_body(of(b));
    if (!ba || !bb) return std::nullopt;
    return surface::within(*ba, *bb, gap);
  }
  // Near a sphere, ellipsoid or cylinder: the body's pieces against its support function,
  // so that the level rules refine where they come close, not wherever their boxes meet.
  std::optional<bool> overlap_convex(const Shape& self, const Shape& other, double gap) const override {
    const auto body = surface::cached_body(of(self));
    if (!body) return std::nullopt;
    const ShapeFamily& f = shape_family(other);
    return surface::within_convex(
        *body, [&](const Vec3& d) { return f.support(other, d); }, [&](const Vec3& p) { return f.contains(other, p); }, gap);
  }
  std::unique_ptr<SurfaceModel> surface_model(const Shape& s, const std::string& source,
                                              const std::string& field) const override {
    return make_nurbs_surface_model(s, source, field);
  }
};

}  // namespace

const ShapeFamily& nurbs_surface_family() {
  static const NurbsSurfaceFamily family;
  return family;
}

}  // namespace cisamr::geometry
