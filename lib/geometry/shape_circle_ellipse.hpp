#pragma once
// Circles (exact) and ellipses (tolerant: the unit circle in a rotated, scaled frame).
#include "geometry/shape_model.hpp"

namespace cisamr::geometry {

class CircleModel final : public CurveModel {
 public:
  CircleModel(const Circle& c, const std::string& source, const std::string& field);
  const Vec2& center() const { return c_; }
  double radius() const { return r_; }

  int side(const Vec2& p) const override;
  bool segment_events(const Vec2& a, const Vec2& b, const Box2& seg, EventSink& sink,
                      std::vector<double>& scratch) const override;
  double boundary_distance(const Vec2& p) const override;
  bool boundary_touches(const Box2& box) const override;
  double measure() const override;
  bool outward_normal(const Vec2& p, Vec2& n) const override;
  std::optional<bool> regions_intersect(const ShapeModel<2>& other, bool interiors, double depth_tol) const override;
  void nearest_boundary_points(const Vec2& p, std::vector<Vec2>& out) const override;
  void boundary_meetings(const ShapeModel<2>& other, const Vec2& p, std::vector<Vec2>& out) const override;
  Vec2 curve_point(int piece, double s) const override;
  std::vector<Vec2> boundary_polyline() const override;

 private:
  Vec2 c_;
  double r_;
};

// The ellipse as the unit circle in the frame u = ((x−c)·e1)/a, v = ((x−c)·e2)/b.
class EllipseModel final : public CurveModel {
 public:
  EllipseModel(const Ellipse& e, const std::string& source, const std::string& field);

  int side(const Vec2& p) const override;
  bool segment_events(const Vec2& a, const Vec2& b, const Box2& seg, EventSink& sink,
                      std::vector<double>& scratch) const override;
  double boundary_distance(const Vec2& p) const override;
  bool boundary_touches(const Box2& box) const override;
  double measure() const override;
  bool outward_normal(const Vec2& p, Vec2& n) const override;
  void nearest_boundary_points(const Vec2& p, std::vector<Vec2>& out) const override;
  Vec2 curve_point(int piece, double s) const override;
  std::vector<Vec2> boundary_polyline() const override;
  int meeting_samples() const override { return 1024; }

 private:
  Vec2 to_unit_frame(const Vec2& p) const;
  // Tolerant side: F = 1 − u² − v², |F| below the rounding bound is ON (f_out: F or 0).
  int tolerant_side(const Vec2& p, double* f_out = nullptr) const;

  Vec2 c_;
  double a_, b_, cs_, sn_;
};

}  // namespace cisamr::geometry
