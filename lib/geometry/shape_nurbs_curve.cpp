// NURBS curves (README: classification, crossings, distances of each; the piece
// machinery is nurbs2.cpp).
#include "geometry/shape_nurbs_curve.hpp"

#include <algorithm>
#include <cmath>

#include "core/error.hpp"
#include "geometry/nurbs2.hpp"

namespace cisamr::geometry {

namespace {

class NurbsCurveModel final : public CurveModel {
 public:
  NurbsCurveModel(const NurbsCurve& c, const std::string& src, const std::string& field) {
    const std::string problem = nurbs::build_region(c, region_);
    if (!problem.empty()) {
      const auto colon = problem.find(": ");
      throw InputError(src, field + problem.substr(0, colon), problem.substr(colon + 2));
    }
    box_ = region_.box;
  }

  int side(const Vec2& p) const override { return nurbs::side(region_, p); }

  bool segment_events(const Vec2& a, const Vec2& b, const Box2&, EventSink& sink,
                      std::vector<double>& ts) const override {
    ts.clear();
    const Vec2 d{b[0] - a[0], b[1] - a[1]};
    const double dd = d[0] * d[0] + d[1] * d[1];
    if (dd == 0) return classify(a) >= 0;
    nurbs::segment_hits(region_, a, b, ts);
    // Hits within the ON tolerance of an endpoint that is ON belong to that endpoint.
    const double len = std::sqrt(dd);
    const double tol_t = 4 * region_.on_tolerance / len;
    const bool a_on = classify(a) == 0, b_on = classify(b) == 0;
    ts.erase(std::remove_if(ts.begin(), ts.end(),
                            [&](double t) { return (a_on && t <= tol_t) || (b_on && t >= 1 - tol_t); }),
             ts.end());
    return events_from_hits<2>(a, d, ts, sink, [&](const Vec2& q) { return classify(q) >= 0; });
  }

  double boundary_distance(const Vec2& p) const override { return nurbs::distance_to_curve(region_, p); }
  bool boundary_touches(const Box2& box) const override { return nurbs::touches_box(region_, box); }
  double measure() const override { return nurbs::area(region_); }
  void x_breakpoints(std::vector<double>& out) const override { nurbs::x_breakpoints(region_, out); }

  void nearest_boundary_points(const Vec2& p, std::vector<Vec2>& out) const override {
    sampled_nearest_points(p, 32, out);
  }

  int piece_count() const override { return static_cast<int>(region_.pieces.size()); }

  Vec2 curve_point(int piece, double s) const override {
    return nurbs::point(region_.pieces[piece], region_.degree, s);
  }

  std::vector<Vec2> boundary_polyline() const override { return nurbs::flatten(region_, 1e-9 * region_.size); }

 private:
  nurbs::Region region_;
};

}  // namespace

std::unique_ptr<CurveModel> make_nurbs_curve_model(const NurbsCurve& curve, const std::string& source,
                                                   const std::string& field) {
  return std::make_unique<NurbsCurveModel>(curve, source, field);
}

}  // namespace cisamr::geometry
