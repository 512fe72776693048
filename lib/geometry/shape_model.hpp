#pragma once
// The shape interface behind the generic Oracle<Dim> (private to lib/geometry). One
// implementation per shape family (shape_*.cpp), created from a scene's inclusion
// descriptor by make_shape_model (shape_registry.cpp, the one place that lists the
// families). What each function must guarantee is written down in README.md
// ("Shape concept"); the oracle combines the answers of single shapes into phases.
#include <algorithm>
#include <cmath>
#include <cstdint>
#include <limits>
#include <memory>
#include <optional>
#include <span>
#include <string>
#include <type_traits>
#include <vector>

#include "core/types.hpp"
#include "core/vec_math.hpp"
#include "geometry/predicates2.hpp"
#include "geometry/scene.hpp"

namespace cisamr::geometry {

constexpr double kUnitRoundoff = std::numeric_limits<double>::epsilon() * 0.5;
// Crossings closer than this (in t) are merged: a sub-interval that short is rounding.
constexpr double kMergeT = 64 * std::numeric_limits<double>::epsilon();

template <int Dim>
bool point_in_box(const std::type_identity_t<Vec<Dim>>& p, const Box<Dim>& b) {
  for (int d = 0; d < Dim; ++d)
    if (!(p[d] >= b.min[d] && p[d] <= b.max[d])) return false;
  return true;
}

// Distance from p to the closed box (the 2D form rounds through hypot, kept as it was:
// node positions depend on it bit for bit).
inline double box_distance(const Box2& b, const Vec2& p) {
  const double dx = std::max({b.min[0] - p[0], 0.0, p[0] - b.max[0]});
  const double dy = std::max({b.min[1] - p[1], 0.0, p[1] - b.max[1]});
  return std::hypot(dx, dy);
}
inline double box_distance(const Box3& b, const Vec3& p) {
  double d2 = 0;
  for (int k = 0; k < 3; ++k) {
    const double e = std::max({b.min[k] - p[k], 0.0, p[k] - b.max[k]});
    d2 += e * e;
  }
  return std::sqrt(d2);
}

// Length of the box diagonal (the scale of tolerances relative to a shape).
inline double box_diagonal(const Box2& b) { return std::hypot(b.max[0] - b.min[0], b.max[1] - b.min[1]); }
inline double box_diagonal(const Box3& b) { return norm(sub(b.max, b.min)); }

// One change of "inside" along a segment a→b, as the crossing sweep sorts them.
struct SegmentEvent {
  double t;
  std::int32_t inclusion;
  std::int32_t slot;   // position of the inclusion in the candidate list
  std::int32_t order;  // rank among this inclusion's events (ties in t)
  bool inside_after;
};

// Where a shape appends its events for one segment.
class EventSink {
 public:
  EventSink(std::vector<SegmentEvent>& events, std::int32_t inclusion, std::int32_t slot)
      : events_(events), inclusion_(inclusion), slot_(slot) {}
  void push(double t, bool inside_after) { events_.push_back({t, inclusion_, slot_, order_++, inside_after}); }
  // The roots of a circle/sphere-like quadric, alternating the state; returns the start state.
  bool push_hits(const exact::CircleSegmentHits& h) {
    bool state = h.start_inside;
    for (int i = 0; i < h.count; ++i) {
      state = !state;
      push(h.t[i], state);
    }
    return h.start_inside;
  }

 private:
  std::vector<SegmentEvent>& events_;
  std::int32_t inclusion_, slot_;
  std::int32_t order_ = 0;
};

// For shapes whose crossings come as a list of hit parameters `ts` along a + t·d: sorts
// and deduplicates them, classifies each open sub-interval at its midpoint with
// inside(point) and appends the changes. Returns the state at t = 0⁺.
template <int Dim, class Inside>
bool events_from_hits(const Vec<Dim>& a, const Vec<Dim>& d, std::vector<double>& ts, EventSink& sink,
                      Inside&& inside) {
  std::sort(ts.begin(), ts.end());
  ts.erase(std::unique(ts.begin(), ts.end()), ts.end());
  auto state_at = [&](double t0, double t1) {
    const double tm = 0.5 * (t0 + t1);
    Vec<Dim> q;
    for (int k = 0; k < Dim; ++k) q[k] = a[k] + tm * d[k];
    return inside(q);
  };
  const bool start = state_at(0, ts.empty() ? 1.0 : ts[0]);
  bool state = start;
  for (std::size_t i = 0; i < ts.size(); ++i) {
    const double next = i + 1 < ts.size() ? ts[i + 1] : 1.0;
    const bool after = state_at(ts[i], next);
    if (after != state) sink.push(ts[i], after);
    state = after;
  }
  return start;
}

// The questions the generic oracle asks about one inclusion (README: shape concept).
template <int Dim>
class ShapeModel {
 public:
  using Point = Vec<Dim>;
  virtual ~ShapeModel() = default;

  // Contains the closed region (rounding-level loose where needed); computed once.
  const Box<Dim>& box() const { return box_; }
  // +1 inside, 0 on the boundary, -1 outside; any p.
  int classify(const Point& p) const { return point_in_box(p, box_) ? side(p) : -1; }

  // classify() for p inside box().
  virtual int side(const Point& p) const = 0;
  // Appends (t, inside after t) where the open segment a→b enters or leaves the shape and
  // returns whether it starts inside (ON counts as inside). `seg` is the box of a and b
  // and meets box(); `scratch` is reusable memory. The answer depends only on (a, b).
  virtual bool segment_events(const Point& a, const Point& b, const Box<Dim>& seg, EventSink& sink,
                              std::vector<double>& scratch) const = 0;
  // Distance from p to the boundary.
  virtual double boundary_distance(const Point& p) const = 0;
  // Does the boundary meet the closed box (already inflated by the caller's slack)?
  // Conservative: never false when it does.
  virtual bool boundary_touches(const Box<Dim>& box) const = 0;
  // Area (2D) or volume (3D) of the region.
  virtual double measure() const = 0;
  // Gradient direction of a curved boundary at p (not normalised); false for flat pieces.
  // Used to probe the cusp between touching shapes.
  virtual bool outward_normal(const Point& /*p*/, Point& /*n*/) const { return false; }
  // Crossings of near-tangent lines carry more than analytic rounding (measures are
  // integrated to a looser tolerance over such shapes).
  virtual bool approximate_sections() const { return false; }
  // x coordinates where the phase length on a line x = const has a kink (beyond box()).
  virtual void x_breakpoints(std::vector<double>& /*out*/) const {}
  // An exact or analytic answer to "do the regions meet" for this pair of families, if
  // there is one; otherwise the oracle samples boundaries.
  virtual std::optional<bool> regions_intersect(const ShapeModel& /*other*/, bool /*interiors*/,
                                                double /*depth_tol*/) const {
    return std::nullopt;
  }
  // Points of the boundary where |q − p| is locally minimal (or a dense enough sample).
  virtual void nearest_boundary_points(const Point& p, std::vector<Point>& out) const = 0;
  // Points where this boundary meets other's (2D: all of them; 3D: the one of the meeting
  // curve nearest to p). Candidates for the distance to a union.
  virtual void boundary_meetings(const ShapeModel& /*other*/, const Point& /*p*/,
                                 std::vector<Point>& /*out*/) const {}

 protected:
  Box<Dim> box_{};
};

// 2D shapes: boundaries are closed curves made of pieces parametrised by s ∈ [0, 1].
class CurveModel : public ShapeModel<2> {
 public:
  virtual int piece_count() const { return 1; }
  virtual Vec2 curve_point(int piece, double s) const = 0;
  // A closed polyline on (or within rounding of) the boundary, for overlap tests.
  virtual std::vector<Vec2> boundary_polyline() const = 0;
  // Samples per piece when walking the boundary through another shape's classifier.
  virtual int meeting_samples() const { return 64; }
  // A polygon's vertices (empty for curved families) and, for a family that can, the
  // points where its boundary meets such a polygon: a circle and a polygon meet
  // analytically whichever of the two is asked.
  virtual std::span<const Vec2> polygon_vertices() const { return {}; }
  virtual bool polygon_meetings(std::span<const Vec2> /*poly*/, std::vector<Vec2>& /*out*/) const { return false; }
  // Default: walk this boundary, bisect every sign change of other's classifier.
  void boundary_meetings(const ShapeModel<2>& other, const Vec2& p, std::vector<Vec2>& out) const override;

 protected:
  // Every discrete local minimum of |q − p| over `samples` points per piece, refined by
  // golden section (with the sample itself).
  void sampled_nearest_points(const Vec2& p, int samples, std::vector<Vec2>& out) const;
};

// 3D shapes.
class SurfaceModel : public ShapeModel<3> {
 public:
  // Convex bodies answer overlap questions through shapes_overlap's support functions.
  virtual bool convex() const { return false; }
  // Boundary points at about box diagonal / per_axis spacing, for overlap tests.
  virtual std::vector<Vec3> boundary_points(int per_axis) const;
  // y coordinates where the phase length on the line (x, y, ·) has a kink, at this x.
  virtual void y_breakpoints_at(double /*x*/, std::vector<double>& /*out*/) const {}
  // Kinks caused by this pair meeting (sphere pairs).
  virtual void pair_x_breakpoints(const SurfaceModel& /*other*/, std::vector<double>& /*out*/) const {}
  virtual void pair_y_breakpoints_at(const SurfaceModel& /*other*/, double /*x*/,
                                     std::vector<double>& /*out*/) const {}
  // Points where three boundaries meet (sphere triples), distance candidates.
  virtual void triple_meetings(const SurfaceModel& /*b*/, const SurfaceModel& /*c*/,
                               std::vector<Vec3>& /*out*/) const {}

  const Shape& descriptor() const { return *descriptor_; }

 protected:
  explicit SurfaceModel(const Shape& descriptor) : descriptor_(&descriptor) {}

 private:
  const Shape* descriptor_;  // the scene's inclusion, owned by the oracle
};

template <int Dim>
using DimensionModel = std::conditional_t<Dim == 2, CurveModel, SurfaceModel>;

// The one place that maps a scene descriptor to its family (shape_registry.cpp). Throws
// InputError(source, field + ".<member>", ...) for invalid shapes. `shape` must outlive
// the model.
template <int Dim>
std::unique_ptr<DimensionModel<Dim>> make_shape_model(const Shape& shape, const std::string& source,
                                                      const std::string& field);

// Helpers shared by several families.
bool finite(const Vec2& v);
bool finite(const Vec3& v);
bool orthonormal(const Rotation3& r);
// y extent of the section at x of the quadric region (p − c)ᵀM(p − c) ≤ rhs, minimised
// over z (both ends appended when it is not empty).
void quadric_y_extent(const double (&M)[3][3], const Vec3& c, double rhs, double x, std::vector<double>& out);

}  // namespace cisamr::geometry
