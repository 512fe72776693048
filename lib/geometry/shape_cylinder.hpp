#pragma once
// Finite cylinders with flat caps (exact side; convex).
#include "geometry/shape_model.hpp"

namespace cisamr::geometry {

class CylinderModel final : public SurfaceModel {
 public:
  CylinderModel(const Shape& shape, const std::string& source, const std::string& field);

  int side(const Vec3& p) const override;
  bool segment_events(const Vec3& a, const Vec3& b, const Box3& seg, EventSink& sink,
                      std::vector<double>& scratch) const override;
  double boundary_distance(const Vec3& p) const override;
  bool boundary_touches(const Box3& box) const override;
  double measure() const override;
  void nearest_boundary_points(const Vec3& p, std::vector<Vec3>& out) const override;
  bool convex() const override { return true; }
  void y_breakpoints_at(double x, std::vector<double>& out) const override;

 private:
  Vec3 s_, e_;
  double r_;
  Vec3 u_;      // unit axis
  double len_;  // |e − s|
};

}  // namespace cisamr::geometry
