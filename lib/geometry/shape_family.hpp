#pragma once
// What one shape family (one alternative of the Shape variant) knows about its scene
// descriptors: the operations behind shapes.hpp and the factory of its oracle model.
// One implementation per family, next to its model in shape_<family>.cpp; shape_family()
// (shape_registry.cpp, the one list of families) finds it. No CGAL here.
#include <memory>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

#include "core/types.hpp"
#include "geometry/scene.hpp"

namespace cisamr::geometry {

class CurveModel;    // shape_model.hpp (private to lib/geometry)
class SurfaceModel;
class FieldReader;   // shape_fields.hpp
class FieldWriter;

class ShapeFamily {
 public:
  virtual ~ShapeFamily() = default;

  virtual std::string_view name() const = 0;  // as the scene file names it ("circle")
  virtual int dimension() const = 0;          // 2 or 3

  // The descriptor from its object in the scene file, every field checked (InputError
  // naming the field), and back: the members after "shape", in the file's order.
  virtual Shape read(const FieldReader& fields) const = 0;
  virtual void write(const Shape& s, FieldWriter& fields) const = 0;

  // The operations of shapes.hpp on a descriptor of this family (see there).
  virtual Box3 bounding_box(const Shape& s) const = 0;
  // shape_holding_box: a box that holds the shape, cheap to compute. Default: the tight one.
  virtual Box3 holding_box(const Shape& s) const { return bounding_box(s); }
  virtual double measure(const Shape& s) const = 0;
  virtual double boundary_measure(const Shape& s) const = 0;
  virtual std::vector<Vec3> boundary_samples(const Shape& s, double spacing) const = 0;
  virtual bool contains(const Shape& s, const Vec3& p) const = 0;
  // Whether any of `points` is contained: contains() per point by default; a family whose
  // queries need a built structure (STL) builds it once for all of them.
  virtual bool contains_any(const Shape& s, const std::vector<Vec3>& points) const {
    for (const Vec3& p : points)
      if (contains(s, p)) return true;
    return false;
  }
  virtual void translate(Shape& s, const Vec3& offset) const = 0;
  // shape_boundary_samples_within (3D). Default: the boundary samples in `clip`, each an
  // equal share of the boundary measure (the cost of sampling the whole boundary).
  virtual void boundary_samples_within(const Shape& s, double spacing, const Box3& clip,
                                       std::vector<Vec3>& points, std::vector<double>& areas) const;

  // Convex regions answer overlap questions through their support function
  // h(d) = max over the region of x·d (z of d unused in 2D).
  virtual bool convex(const Shape& /*s*/) const { return false; }
  virtual double support(const Shape& s, const Vec3& d) const;  // only where convex(s)
  // An exact answer to shapes_overlap for two shapes of this family, where there is one.
  virtual std::optional<bool> overlap_same_family(const Shape& /*a*/, const Shape& /*b*/, double /*gap*/) const {
    return std::nullopt;
  }
  // An answer to shapes_overlap(self, other, gap > 0) for a convex shape `other` of
  // another family, where there is one: never false when they come within gap.
  virtual std::optional<bool> overlap_convex(const Shape& /*self*/, const Shape& /*other*/, double /*gap*/) const {
    return std::nullopt;
  }
  // Two shapes of this family on which shapes_overlap's sampled test found nothing: do
  // their boundaries still cross (an edge of one piercing the other)?
  virtual bool edges_pierce(const Shape& /*a*/, const Shape& /*b*/) const { return false; }
  // Distances to it are judged by its box (exact tests too slow or not available).
  virtual bool judged_by_box() const { return false; }

  // The oracle's model of the shape (shape_model.hpp); throws InputError(source, field +
  // ".<member>", ...) for an invalid shape. The defaults refuse a shape of the other
  // dimension.
  virtual std::unique_ptr<CurveModel> curve_model(const Shape& s, const std::string& source,
                                                  const std::string& field) const;
  virtual std::unique_ptr<SurfaceModel> surface_model(const Shape& s, const std::string& source,
                                                      const std::string& field) const;
};

// The family of a descriptor (shape_registry.cpp).
const ShapeFamily& shape_family(const Shape& s);
// The family the scene file calls `name`, or nullptr.
const ShapeFamily* shape_family_named(std::string_view name);
// The names of the families of one dimension, in the registry's order.
std::vector<std::string_view> shape_family_names(int dimension);

// Base of a family whose descriptor type is T: `of` unwraps the variant.
template <class T>
class FamilyOf : public ShapeFamily {
 protected:
  static const T& of(const Shape& s) { return std::get<T>(s); }
  static T& of(Shape& s) { return std::get<T>(s); }
};

}  // namespace cisamr::geometry
