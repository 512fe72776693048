#pragma once
// Closed rational NURBS curves, as the chain of rational Bézier pieces of nurbs2.hpp.
#include "geometry/nurbs2.hpp"
#include "geometry/shape_model.hpp"

namespace cisamr::geometry {

class NurbsCurveModel final : public CurveModel {
 public:
  NurbsCurveModel(const NurbsCurve& c, const std::string& source, const std::string& field);

  int side(const Vec2& p) const override;
  bool segment_events(const Vec2& a, const Vec2& b, const Box2& seg, EventSink& sink,
                      std::vector<double>& scratch) const override;
  double boundary_distance(const Vec2& p) const override;
  bool boundary_touches(const Box2& box) const override;
  double measure() const override;
  void x_breakpoints(std::vector<double>& out) const override;
  void nearest_boundary_points(const Vec2& p, std::vector<Vec2>& out) const override;
  int piece_count() const override { return static_cast<int>(region_.pieces.size()); }
  Vec2 curve_point(int piece, double s) const override;
  std::vector<Vec2> boundary_polyline() const override;

 private:
  nurbs::Region region_;
};

}  // namespace cisamr::geometry
