// NURBS surfaces: the descriptor moves; everything that needs the surface's geometry
// is not implemented yet (std::logic_error), and the oracle refuses the shape.
#include "geometry/shape_nurbs_surface.hpp"

#include <algorithm>
#include <array>
#include <cmath>
#include <stdexcept>

#include "core/error.hpp"
#include "geometry/shape_fields.hpp"
#include "geometry/shape_nurbs_curve.hpp"
#include "geometry/shape_model.hpp"

namespace cisamr::geometry {
namespace {

[[noreturn]] void not_implemented() { throw std::logic_error("not implemented yet"); }

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

// The control point x placed as the body places it: rotation·(scale·x) + translate, in the
// operation order of the STL vertices (stl_mesh.cpp), so that boxes agree with the body bit
// for bit.
Vec3 placed(const NurbsSurface& s, const Vec3& x) {
  Vec3 y;
  for (int r = 0; r < 3; ++r)
    y[r] = s.rotation[r][0] * (s.scale * x[0]) + s.rotation[r][1] * (s.scale * x[1]) +
           s.rotation[r][2] * (s.scale * x[2]) + s.translate[r];
  return y;
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
    if (f.has("scale")) surface.scale = f.positive("scale");
    if (f.has("rotation")) surface.rotation = f.rotation("rotation");
    if (f.has("translate")) surface.translate = f.vec<3>("translate");
    return surface;
  }
  // The flat form (u fastest) and the placement where it is not the default, as for STL:
  // reading it back gives the same descriptor bit for bit.
  void write(const Shape& shape, FieldWriter& f) const override {
    const NurbsSurface& s = of(shape);
    if (s.scale != 1) f.number("scale", s.scale);
    if (!is_identity(s.rotation)) f.rotation("rotation", s.rotation);
    if (s.translate != Vec3{0, 0, 0}) f.vec("translate", s.translate);
    f.objects("patches", s.patches.size(), [&](FieldWriter& w, std::size_t i) {
      const NurbsPatch& p = s.patches[i];
      w.integers("degree", {p.degree[0], p.degree[1]});
      w.numbers("knots_u", p.knots_u);
      w.numbers("knots_v", p.knots_v);
      w.points("control_points", p.control_points);
      if (!p.weights.empty()) w.numbers("weights", p.weights);
    });
  }
  Box3 bounding_box(const Shape&) const override { not_implemented(); }
  // The box of the placed control points: with positive weights it holds the surface.
  Box3 holding_box(const Shape& s) const override {
    Box3 b{{INFINITY, INFINITY, INFINITY}, {-INFINITY, -INFINITY, -INFINITY}};
    for (const NurbsPatch& patch : of(s).patches)
      for (const Vec3& x : patch.control_points) {
        const Vec3 p = placed(of(s), x);
        for (int d = 0; d < 3; ++d) b.min[d] = std::min(b.min[d], p[d]), b.max[d] = std::max(b.max[d], p[d]);
      }
    return b;
  }
  double measure(const Shape&) const override { not_implemented(); }
  double boundary_measure(const Shape&) const override { not_implemented(); }
  std::vector<Vec3> boundary_samples(const Shape&, double) const override { not_implemented(); }
  bool contains(const Shape&, const Vec3&) const override { not_implemented(); }
  void translate(Shape& s, const Vec3& o) const override {
    for (int k = 0; k < 3; ++k) of(s).translate[k] += o[k];
  }
  bool judged_by_box() const override { return true; }
  std::unique_ptr<SurfaceModel> surface_model(const Shape&, const std::string& source,
                                              const std::string& field) const override {
    throw InputError(source, field + ".shape", "nurbs_surface: not supported yet");
  }
};

}  // namespace

const ShapeFamily& nurbs_surface_family() {
  static const NurbsSurfaceFamily family;
  return family;
}

}  // namespace cisamr::geometry
