#pragma once
// Spheres (exact) and ellipsoids (tolerant: the unit sphere in a rotated, scaled frame).
#include "geometry/shape_model.hpp"

namespace cisamr::geometry {

// Half the extent of the ellipsoid along world axis d (its box is center ± this).
double ellipsoid_half_extent(const Ellipsoid& e, int d);

class SphereModel final : public SurfaceModel {
 public:
  SphereModel(const Shape& shape, const std::string& source, const std::string& field);

  int side(const Vec3& p) const override;
  bool segment_events(const Vec3& a, const Vec3& b, const Box3& seg, EventSink& sink,
                      std::vector<double>& scratch) const override;
  double boundary_distance(const Vec3& p) const override;
  bool boundary_touches(const Box3& box) const override;
  double measure() const override;
  bool outward_normal(const Vec3& p, Vec3& n) const override;
  void x_breakpoints(std::vector<double>& out) const override;
  std::optional<bool> regions_intersect(const ShapeModel<3>& other, bool interiors, double depth_tol) const override;
  void nearest_boundary_points(const Vec3& p, std::vector<Vec3>& out) const override;
  void boundary_meetings(const ShapeModel<3>& other, const Vec3& p, std::vector<Vec3>& out) const override;
  bool convex() const override { return true; }
  void y_breakpoints_at(double x, std::vector<double>& out) const override;
  void pair_x_breakpoints(const SurfaceModel& other, std::vector<double>& out) const override;
  void pair_y_breakpoints_at(const SurfaceModel& other, double x, std::vector<double>& out) const override;
  void triple_meetings(const SurfaceModel& b, const SurfaceModel& c, std::vector<Vec3>& out) const override;

 private:
  // The circle where this sphere meets `other` (center o, unit normal n, radius h), if any.
  bool meeting_circle(const SphereModel& other, Vec3& o, Vec3& n, double& h) const;

  Vec3 c_;
  double r_;
};

// Body coordinate j of p is Σ_i rot[i][j]·(p − c)_i; divided by axis[j] it lands on the
// unit sphere.
class EllipsoidModel final : public SurfaceModel {
 public:
  EllipsoidModel(const Shape& shape, const std::string& source, const std::string& field);

  int side(const Vec3& p) const override;
  bool segment_events(const Vec3& a, const Vec3& b, const Box3& seg, EventSink& sink,
                      std::vector<double>& scratch) const override;
  double boundary_distance(const Vec3& p) const override;
  bool boundary_touches(const Box3& box) const override;
  double measure() const override;
  bool outward_normal(const Vec3& p, Vec3& n) const override;
  void nearest_boundary_points(const Vec3& p, std::vector<Vec3>& out) const override;
  bool convex() const override { return true; }
  void y_breakpoints_at(double x, std::vector<double>& out) const override;

 private:
  Vec3 to_body(const Vec3& p) const;
  Vec3 unit_frame(const Vec3& p) const;
  // Tolerant side: F = 1 − |u|², ON within the rounding bound of its evaluation.
  int tolerant_side(const Vec3& p, double* f_out = nullptr) const;

  Vec3 c_;
  Vec3 axis_;
  Rotation3 rot_;
};

}  // namespace cisamr::geometry
