// The one place that knows every shape family: scene descriptor → ShapeModel. Adding
// a shape means adding its shape_<family>.{hpp,cpp} and one line here.
#include "core/error.hpp"
#include "geometry/shape_circle_ellipse.hpp"
#include "geometry/shape_cylinder.hpp"
#include "geometry/shape_nurbs_curve.hpp"
#include "geometry/shape_polygon.hpp"
#include "geometry/shape_sphere_ellipsoid.hpp"
#include "geometry/shape_stl.hpp"

namespace cisamr::geometry {

template <>
std::unique_ptr<CurveModel> make_shape_model<2>(const Shape& shape, const std::string& src, const std::string& field) {
  if (const auto* c = std::get_if<Circle>(&shape)) return make_circle_model(*c, src, field);
  if (const auto* e = std::get_if<Ellipse>(&shape)) return make_ellipse_model(*e, src, field);
  if (const auto* p = std::get_if<Polygon>(&shape)) return make_polygon_model(*p, src, field);
  if (const auto* n = std::get_if<NurbsCurve>(&shape)) return make_nurbs_curve_model(*n, src, field);
  throw InputError(src, field + ".shape", "a 3D shape in a 2D scene");
}

template <>
std::unique_ptr<SurfaceModel> make_shape_model<3>(const Shape& shape, const std::string& src, const std::string& field) {
  if (std::holds_alternative<Sphere>(shape)) return make_sphere_model(shape, src, field);
  if (std::holds_alternative<Ellipsoid>(shape)) return make_ellipsoid_model(shape, src, field);
  if (std::holds_alternative<Cylinder>(shape)) return make_cylinder_model(shape, src, field);
  if (std::holds_alternative<StlSurface>(shape)) return make_stl_model(shape, src, field);
  if (std::holds_alternative<NurbsSurface>(shape))
    throw InputError(src, field + ".shape", "nurbs_surface: not supported yet");
  throw InputError(src, field + ".shape", "a 2D shape in a 3D scene");
}

}  // namespace cisamr::geometry
