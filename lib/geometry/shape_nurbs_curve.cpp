// NURBS curves (README: classification, crossings, distances of each; the piece
// machinery is nurbs2.cpp).
#include "geometry/shape_nurbs_curve.hpp"

#include <algorithm>
#include <cmath>
#include <stdexcept>

#include "core/error.hpp"
#include "geometry/nurbs2.hpp"
#include "geometry/shape_fields.hpp"
#include "geometry/shape_model.hpp"
#include "geometry/shape_family.hpp"
#include "geometry/shapes_detail.hpp"

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

// ---------------------------------------------------------------- scene descriptors

namespace {

nurbs::Region region_of(const NurbsCurve& n) {
  nurbs::Region r;
  const std::string problem = nurbs::build_region(n, r);
  if (!problem.empty()) throw std::invalid_argument("invalid NURBS curve" + problem);
  return r;
}

class NurbsCurveFamily final : public FamilyOf<NurbsCurve> {
 public:
  std::string_view name() const override { return "nurbs"; }
  int dimension() const override { return 2; }
  Shape read(const FieldReader& f) const override {
    f.allow_keys({"degree", "knots", "control_points", "weights"});
    NurbsCurve n;
    n.degree = f.integer_in("degree", 1, 30);
    n.control_points = f.points2("control_points");
    const std::size_t count = n.control_points.size();
    if (count < static_cast<std::size_t>(n.degree) + 1)
      f.fail("control_points", "a degree-" + std::to_string(n.degree) + " curve needs at least " +
                                   std::to_string(n.degree + 1) + " control points, got " + std::to_string(count));
    n.knots = read_knots(f, "knots", n.degree, count + n.degree + 1);
    n.weights = read_weights(f, "weights", count);
    return n;
  }
  void write(const Shape& s, FieldWriter& f) const override {
    const NurbsCurve& n = of(s);
    f.integer("degree", n.degree);
    f.numbers("knots", n.knots);
    f.points("control_points", n.control_points);
    if (!n.weights.empty()) f.numbers("weights", n.weights);
  }
  Box3 bounding_box(const Shape& s) const override {
    const nurbs::Region r = region_of(of(s));
    const Box2 b = nurbs::tight_box(r, 1e-12 * r.size);
    return Box3{{b.min[0], b.min[1], 0}, {b.max[0], b.max[1], 0}};
  }
  Box3 holding_box(const Shape& s) const override {
    Box3 b{{INFINITY, INFINITY, 0}, {-INFINITY, -INFINITY, 0}};
    for (const Vec2& p : of(s).control_points)
      for (int d = 0; d < 2; ++d) b.min[d] = std::min(b.min[d], p[d]), b.max[d] = std::max(b.max[d], p[d]);
    return b;
  }
  double measure(const Shape& s) const override { return nurbs::area(region_of(of(s))); }
  double boundary_measure(const Shape& s) const override { return nurbs::length(region_of(of(s))); }
  std::vector<Vec3> boundary_samples(const Shape& s, double spacing) const override {
    const nurbs::Region r = region_of(of(s));
    return detail::resampled_ring(nurbs::flatten(r, 1e-6 * r.size), spacing);
  }
  bool contains(const Shape& s, const Vec3& p) const override {
    return nurbs::side(region_of(of(s)), {p[0], p[1]}) >= 0;
  }
  void translate(Shape& s, const Vec3& o) const override {
    for (Vec2& v : of(s).control_points) v[0] += o[0], v[1] += o[1];
  }
  // The level rules judge a curve by its control points' box (holding_box), which holds
  // the curve without any subdivision.
  bool judged_by_box() const override { return true; }
  std::unique_ptr<CurveModel> curve_model(const Shape& s, const std::string& source,
                                          const std::string& field) const override {
    return std::make_unique<NurbsCurveModel>(of(s), source, field);
  }
};

}  // namespace

std::vector<double> read_knots(const FieldReader& fields, std::string_view key, int degree,
                               std::size_t expected_count) {
  const std::string field(key);
  std::vector<double> k = fields.numbers(key);
  if (expected_count != 0 && k.size() != expected_count)
    fields.fail(field, "expected " + std::to_string(expected_count) + " knots (control points + degree + 1), got " +
                           std::to_string(k.size()));
  for (std::size_t i = 1; i < k.size(); ++i)
    if (k[i] < k[i - 1])
      fields.fail(field + "[" + std::to_string(i) + "]",
                  "knots decrease (" + number_text(k[i]) + " after " + number_text(k[i - 1]) + ")");
  const std::size_t first = static_cast<std::size_t>(degree);
  const std::size_t last = k.size() - 1 - static_cast<std::size_t>(degree);
  if (!(k[first] < k[last])) fields.fail(field, "the knots leave an empty parameter range");
  return k;
}

std::vector<double> read_weights(const FieldReader& fields, std::string_view key, std::size_t expected_count) {
  if (!fields.has(key)) return {};
  const std::string field(key);
  std::vector<double> w = fields.numbers(key);
  if (w.size() != expected_count)
    fields.fail(field, "expected " + std::to_string(expected_count) + " weights (one per control point), got " +
                           std::to_string(w.size()));
  for (std::size_t i = 0; i < w.size(); ++i)
    if (!(w[i] > 0)) fields.fail(field + "[" + std::to_string(i) + "]", "must be positive (got " + number_text(w[i]) + ")");
  return w;
}

const ShapeFamily& nurbs_curve_family() {
  static const NurbsCurveFamily family;
  return family;
}

}  // namespace cisamr::geometry
