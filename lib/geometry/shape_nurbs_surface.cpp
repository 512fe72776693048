// NURBS surfaces: the descriptor moves; everything that needs the surface's geometry
// is not implemented yet (std::logic_error), and the oracle refuses the shape.
#include "geometry/shape_nurbs_surface.hpp"

#include <algorithm>
#include <cmath>
#include <stdexcept>

#include "core/error.hpp"
#include "geometry/shape_model.hpp"

namespace cisamr::geometry {
namespace {

[[noreturn]] void not_implemented() { throw std::logic_error("not implemented yet"); }

class NurbsSurfaceFamily final : public FamilyOf<NurbsSurface> {
 public:
  std::string_view name() const override { return "nurbs_surface"; }
  int dimension() const override { return 3; }
  Box3 bounding_box(const Shape&) const override { not_implemented(); }
  Box3 holding_box(const Shape& s) const override {
    Box3 b{{INFINITY, INFINITY, INFINITY}, {-INFINITY, -INFINITY, -INFINITY}};
    for (const NurbsPatch& patch : of(s).patches)
      for (const Vec3& p : patch.control_points)
        for (int d = 0; d < 3; ++d) b.min[d] = std::min(b.min[d], p[d]), b.max[d] = std::max(b.max[d], p[d]);
    return b;
  }
  double measure(const Shape&) const override { not_implemented(); }
  double boundary_measure(const Shape&) const override { not_implemented(); }
  std::vector<Vec3> boundary_samples(const Shape&, double) const override { not_implemented(); }
  bool contains(const Shape&, const Vec3&) const override { not_implemented(); }
  void translate(Shape& s, const Vec3& o) const override {
    for (NurbsPatch& p : of(s).patches)
      for (Vec3& v : p.control_points)
        for (int k = 0; k < 3; ++k) v[k] += o[k];
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
