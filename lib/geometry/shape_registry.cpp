// The one place that lists the shape families, one per alternative of the Shape variant
// (scene.hpp), in the variant's order. Adding a shape means adding its
// shape_<family>.{hpp,cpp} (with CMakeLists.txt), its alternative in scene.hpp and one
// line here; the scene reader and writer find it here by name.
#include <array>
#include <stdexcept>

#include "core/error.hpp"
#include "geometry/shape_circle_ellipse.hpp"
#include "geometry/shape_cylinder.hpp"
#include "geometry/shape_model.hpp"
#include "geometry/shape_nurbs_curve.hpp"
#include "geometry/shape_nurbs_surface.hpp"
#include "geometry/shape_polygon.hpp"
#include "geometry/shape_sphere_ellipsoid.hpp"
#include "geometry/shape_stl.hpp"
#include "geometry/shape_step.hpp"

namespace cisamr::geometry {

namespace {

const std::array<const ShapeFamily*, std::variant_size_v<Shape>>& families() {
  static const std::array<const ShapeFamily*, std::variant_size_v<Shape>> all{
      &circle_family(),     // Circle
      &ellipse_family(),    // Ellipse
      &polygon_family(),    // Polygon
      &nurbs_curve_family(),  // NurbsCurve
      &sphere_family(),     // Sphere
      &ellipsoid_family(),  // Ellipsoid
      &cylinder_family(),   // Cylinder
      &stl_family(),        // StlSurface
      &nurbs_surface_family(),  // NurbsSurface
      &step_family(),           // StepSolids
  };
  return all;
}

}  // namespace

const ShapeFamily& shape_family(const Shape& s) { return *families()[s.index()]; }

const ShapeFamily* shape_family_named(std::string_view name) {
  for (const ShapeFamily* family : families())
    if (family->name() == name) return family;
  return nullptr;
}

std::vector<std::string_view> shape_family_names(int dimension) {
  std::vector<std::string_view> names;
  for (const ShapeFamily* family : families())
    if (family->dimension() == dimension) names.push_back(family->name());
  return names;
}

// Defaults of ShapeFamily (shape_family.hpp).

void ShapeFamily::boundary_samples_within(const Shape& s, double spacing, const Box3& clip, std::vector<Vec3>& points,
                                          std::vector<double>& areas) const {
  points.clear();
  areas.clear();
  const std::vector<Vec3> all = boundary_samples(s, spacing);
  const double share = all.empty() ? 0 : boundary_measure(s) / static_cast<double>(all.size());
  for (const Vec3& p : all)
    if (point_in_box<3>(p, clip)) points.push_back(p), areas.push_back(share);
}

double ShapeFamily::support(const Shape&, const Vec3&) const {
  throw std::logic_error(std::string(name()) + ": no support function (not convex)");
}

std::unique_ptr<CurveModel> ShapeFamily::curve_model(const Shape&, const std::string& source,
                                                     const std::string& field) const {
  throw InputError(source, field + ".shape", "a 3D shape in a 2D scene");
}

std::unique_ptr<SurfaceModel> ShapeFamily::surface_model(const Shape&, const std::string& source,
                                                         const std::string& field) const {
  throw InputError(source, field + ".shape", "a 2D shape in a 3D scene");
}

template <>
std::unique_ptr<CurveModel> make_shape_model<2>(const Shape& shape, const std::string& src, const std::string& field) {
  return shape_family(shape).curve_model(shape, src, field);
}

template <>
std::unique_ptr<SurfaceModel> make_shape_model<3>(const Shape& shape, const std::string& src, const std::string& field) {
  return shape_family(shape).surface_model(shape, src, field);
}

}  // namespace cisamr::geometry
