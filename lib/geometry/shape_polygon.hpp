#pragma once
// Simple polygons, either orientation (exact predicates throughout).
#include <span>

#include "geometry/shape_model.hpp"

namespace cisamr::geometry {

class PolygonModel final : public CurveModel {
 public:
  // Drops repeated consecutive vertices; throws for < 3 distinct vertices, zero area or
  // self-intersection ("edges x and y").
  PolygonModel(const Polygon& p, const std::string& source, const std::string& field);
  std::span<const Vec2> vertices() const { return v_; }

  int side(const Vec2& p) const override;
  bool segment_events(const Vec2& a, const Vec2& b, const Box2& seg, EventSink& sink,
                      std::vector<double>& scratch) const override;
  double boundary_distance(const Vec2& p) const override;
  bool boundary_touches(const Box2& box) const override;
  double measure() const override;
  void x_breakpoints(std::vector<double>& out) const override;
  void nearest_boundary_points(const Vec2& p, std::vector<Vec2>& out) const override;
  void boundary_meetings(const ShapeModel<2>& other, const Vec2& p, std::vector<Vec2>& out) const override;
  int piece_count() const override { return static_cast<int>(v_.size()); }
  Vec2 curve_point(int piece, double s) const override;
  std::vector<Vec2> boundary_polyline() const override { return v_; }

 private:
  std::vector<Vec2> v_;
};

}  // namespace cisamr::geometry
