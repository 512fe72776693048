#pragma once
// Closed triangulated surfaces read from STL files (exact on the transformed vertices;
// the machinery is stl_mesh.cpp).
#include "geometry/shape_model.hpp"
#include "geometry/stl_mesh.hpp"

namespace cisamr::geometry {

class StlModel final : public SurfaceModel {
 public:
  // Throws for a bad transform and, at field ".file", for a surface that is open,
  // non-manifold, self-intersecting or inconsistently oriented (naming the first bad face).
  StlModel(const Shape& shape, const std::string& source, const std::string& field);

  int side(const Vec3& p) const override;
  bool segment_events(const Vec3& a, const Vec3& b, const Box3& seg, EventSink& sink,
                      std::vector<double>& scratch) const override;
  double boundary_distance(const Vec3& p) const override;
  bool boundary_touches(const Box3& box) const override;
  double measure() const override;
  void x_breakpoints(std::vector<double>& out) const override;
  void y_breakpoints_at(double x, std::vector<double>& out) const override;
  std::optional<bool> regions_intersect(const ShapeModel<3>& other, bool interiors, double depth_tol) const override;
  void nearest_boundary_points(const Vec3& p, std::vector<Vec3>& out) const override;
  // The vertices and face centroids (whatever per_axis).
  std::vector<Vec3> boundary_points(int per_axis) const override;

 private:
  stl::Mesh mesh_;
};

}  // namespace cisamr::geometry
