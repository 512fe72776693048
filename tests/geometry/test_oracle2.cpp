// Oracle2: exact classification, crossings vs sampling, candidates vs brute force,
// validation errors, areas and distances.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <numeric>
#include <cstring>
#include <random>

#include "core/error.hpp"
#include "geometry/oracle.hpp"

using namespace cisamr;
using namespace cisamr::geometry;

namespace {
SceneDesc base_scene() {
  SceneDesc s;
  s.domain_min = {0, 0, 0};
  s.domain_max = {1, 1, 0};
  s.phases = {{1, "matrix", false}, {2, "fiber", false}, {3, "pore", true}};
  s.matrix_phase = 1;
  return s;
}
Inclusion circle(double x, double y, double r, int phase = 2) { return {Circle{{x, y}, r}, phase, 1}; }
Inclusion polygon(std::vector<Vec2> v, int phase = 2) { return {Polygon{std::move(v)}, phase, 1}; }
std::vector<std::int32_t> all(const Oracle2& o) {
  std::vector<std::int32_t> v(o.inclusion_count());
  std::iota(v.begin(), v.end(), 0);
  return v;
}
constexpr PhaseMask bit(int p) { return PhaseMask(1) << p; }

// Expect an InputError whose field and problem contain the given words.
template <class F>
void expect_input_error(F&& f, const std::string& field, const std::string& words) {
  try {
    f();
    ADD_FAILURE() << "no InputError for " << field;
  } catch (const InputError& e) {
    EXPECT_EQ(e.field(), field) << e.what();
    EXPECT_NE(e.problem().find(words), std::string::npos) << e.what();
  }
}
}  // namespace

TEST(Oracle2Circle, LatticePointsOnTheCircleAreExactlyOn) {
  SceneDesc s = base_scene();
  s.inclusions = {circle(0.5, 0.5, 0.25), circle(0.5, 0.5 + 0.0, 0.3125, 2)};
  s.inclusions.resize(1);
  Oracle2 o(s);
  auto c = all(o);
  EXPECT_EQ(o.closure_phases({0.75, 0.5}, c), bit(0) | bit(1));
  EXPECT_EQ(o.closure_phases({0.5, 0.25}, c), bit(0) | bit(1));
  EXPECT_EQ(o.closure_phases({std::nextafter(0.75, 0.0), 0.5}, c), bit(1));
  EXPECT_EQ(o.closure_phases({std::nextafter(0.75, 1.0), 0.5}, c), bit(0));
  EXPECT_EQ(o.phase_at({0.75, 0.5}, c), 1);  // on the interface: the inclusion's phase
  EXPECT_EQ(o.phase_at({0.9, 0.5}, c), 0);
  // 3-4-5 triangle scaled by 1/16: (0.5+3/16, 0.5+4/16) lies exactly on r = 5/16.
  SceneDesc s2 = base_scene();
  s2.inclusions = {circle(0.5, 0.5, 0.3125)};
  Oracle2 o2(s2);
  EXPECT_EQ(o2.closure_phases({0.6875, 0.75}, all(o2)), bit(0) | bit(1));
  EXPECT_EQ(o2.closure_phases({0.6875, std::nextafter(0.75, 0.0)}, all(o2)), bit(1));
  // Not representable: 0.65, 0.7 are rounded, so the point is strictly on one side and
  // the answer must agree with exact rational arithmetic (here: slightly inside).
  SceneDesc s3 = base_scene();
  s3.inclusions = {circle(0.5, 0.5, 0.25)};
  Oracle2 o3(s3);
  const PhaseMask m = o3.closure_phases({0.5 + 0.15, 0.5 + 0.2}, all(o3));
  EXPECT_TRUE(m == bit(0) || m == bit(1));
}

TEST(Oracle2Polygon, EdgesAndVerticesAreExactlyOn) {
  for (bool reversed : {false, true}) {
    SceneDesc s = base_scene();
    std::vector<Vec2> v{{0.25, 0.25}, {0.75, 0.25}, {0.75, 0.5}, {0.5, 0.75}, {0.25, 0.5}};
    if (reversed) std::reverse(v.begin(), v.end());
    s.inclusions = {polygon(v)};
    Oracle2 o(s);
    auto c = all(o);
    for (const Vec2& p : v) EXPECT_EQ(o.closure_phases(p, c), bit(0) | bit(1));
    EXPECT_EQ(o.closure_phases({0.5, 0.25}, c), bit(0) | bit(1));
    EXPECT_EQ(o.closure_phases({0.625, 0.625}, c), bit(0) | bit(1));  // on the slanted edge
    EXPECT_EQ(o.closure_phases({0.375, 0.625}, c), bit(0) | bit(1));
    EXPECT_EQ(o.closure_phases({0.625, std::nextafter(0.625, 0.0)}, c), bit(1));
    EXPECT_EQ(o.closure_phases({0.625, std::nextafter(0.625, 1.0)}, c), bit(0));
    EXPECT_EQ(o.closure_phases({0.5, 0.5}, c), bit(1));
    EXPECT_EQ(o.closure_phases({0.1, 0.5}, c), bit(0));
    EXPECT_EQ(o.closure_phases({0.8, 0.5}, c), bit(0));  // level with a vertex, outside
    EXPECT_EQ(o.closure_phases({0.1, 0.75}, c), bit(0));  // level with the apex, outside
  }
}

TEST(Oracle2, SamePhaseUnionHasNoInnerInterface) {
  SceneDesc s = base_scene();
  s.inclusions = {circle(0.4, 0.5, 0.25), circle(0.6, 0.5, 0.25)};
  Oracle2 o(s);
  auto c = all(o);
  EXPECT_EQ(o.closure_phases({0.65, 0.5}, c), bit(1));  // on A's circle, inside B
  EXPECT_EQ(o.closure_phases({0.35, 0.5}, c), bit(1));
  EXPECT_EQ(o.interface_group(0), 0);
  EXPECT_EQ(o.interface_group(1), 0);
  std::vector<Crossing> cr;
  o.crossings({0.0, 0.5}, {1.0, 0.5}, c, cr);
  ASSERT_EQ(cr.size(), 2u);
  EXPECT_NEAR(cr[0].t, 0.15, 1e-15);
  EXPECT_NEAR(cr[1].t, 0.85, 1e-15);
  EXPECT_EQ(cr[0].inclusion, 0);
  EXPECT_EQ(cr[1].inclusion, 1);
  EXPECT_EQ(cr[0].from_phase, 0);
  EXPECT_EQ(cr[0].to_phase, 1);
  EXPECT_EQ(cr[1].to_phase, 0);
  // A segment inside the union crossing A's boundary: no crossing.
  o.crossings({0.5, 0.5}, {0.7, 0.5}, c, cr);
  EXPECT_TRUE(cr.empty());
}

TEST(Oracle2, TouchingDifferentPhasesMeetAtOnePoint) {
  SceneDesc s = base_scene();
  s.inclusions = {circle(0.25, 0.5, 0.25, 2), circle(0.75, 0.5, 0.25, 3)};
  Oracle2 o(s);
  auto c = all(o);
  EXPECT_EQ(o.closure_phases({0.5, 0.5}, c), bit(0) | bit(1) | bit(2));
  EXPECT_NE(o.interface_group(0), o.interface_group(1));
  std::vector<Crossing> cr;
  o.crossings({0.0, 0.5}, {1.0, 0.5}, c, cr);
  ASSERT_EQ(cr.size(), 1u);
  EXPECT_EQ(cr[0].t, 0.5);
  EXPECT_EQ(cr[0].from_phase, 1);
  EXPECT_EQ(cr[0].to_phase, 2);
  // Polygons sharing an edge: the matrix does not reach the shared edge.
  SceneDesc s2 = base_scene();
  s2.inclusions = {polygon({{0.25, 0.25}, {0.5, 0.25}, {0.5, 0.75}, {0.25, 0.75}}, 2),
                   polygon({{0.5, 0.25}, {0.75, 0.25}, {0.75, 0.75}, {0.5, 0.75}}, 3)};
  Oracle2 o2(s2);
  EXPECT_EQ(o2.closure_phases({0.5, 0.5}, all(o2)), bit(1) | bit(2));
  EXPECT_EQ(o2.closure_phases({0.5, 0.75}, all(o2)), bit(0) | bit(1) | bit(2));
}

TEST(Oracle2Circle, TangentsAndEndpointsOnTheCircle) {
  SceneDesc s = base_scene();
  s.inclusions = {circle(0.5, 0.5, 0.25)};
  Oracle2 o(s);
  auto c = all(o);
  std::vector<Crossing> cr;
  o.crossings({0.0, 0.75}, {1.0, 0.75}, c, cr);  // tangent at (0.5, 0.75)
  EXPECT_TRUE(cr.empty());
  o.crossings({0.75, 0.5}, {1.0, 0.5}, c, cr);  // starts on the circle, leaves
  EXPECT_TRUE(cr.empty());
  o.crossings({0.75, 0.5}, {0.0, 0.5}, c, cr);  // starts on it, goes through
  ASSERT_EQ(cr.size(), 1u);
  EXPECT_EQ(cr[0].t, 2.0 / 3.0);
  EXPECT_EQ(cr[0].from_phase, 1);
  o.crossings({0.75, 0.5}, {0.25, 0.5}, c, cr);  // a diameter: both ends on it
  EXPECT_TRUE(cr.empty());
  o.crossings({0.5, 0.5}, {0.5, 0.75}, c, cr);  // ends on it
  EXPECT_TRUE(cr.empty());
  o.crossings({0.75, 0.0}, {0.75, 1.0}, c, cr);  // vertical tangent
  EXPECT_TRUE(cr.empty());
}

TEST(Oracle2Polygon, CrossingsThroughVerticesAndAlongEdges) {
  SceneDesc s = base_scene();
  s.inclusions = {polygon({{0.25, 0.25}, {0.75, 0.25}, {0.75, 0.75}, {0.25, 0.75}})};
  Oracle2 o(s);
  auto c = all(o);
  std::vector<Crossing> cr;
  o.crossings({0.0, 0.0}, {1.0, 1.0}, c, cr);  // the diagonal through two vertices
  ASSERT_EQ(cr.size(), 2u);
  EXPECT_EQ(cr[0].t, 0.25);
  EXPECT_EQ(cr[1].t, 0.75);
  o.crossings({0.0, 0.5}, {0.5, 0.0}, c, cr);  // touches the corner (0.25, 0.25) only
  EXPECT_TRUE(cr.empty());
  o.crossings({0.25, 0.0}, {0.25, 1.0}, c, cr);  // along an edge: the edge is ON (phase 2)
  ASSERT_EQ(cr.size(), 2u);
  EXPECT_EQ(cr[0].t, 0.25);
  EXPECT_EQ(cr[1].t, 0.75);
  o.crossings({0.25, 0.25}, {0.25, 0.75}, c, cr);  // exactly one edge
  EXPECT_TRUE(cr.empty());
}

namespace {
// Scene with overlapping same-phase circles, polygons of phase 3 and a clipped circle.
SceneDesc mixed_scene() {
  SceneDesc s = base_scene();
  s.inclusions = {circle(0.3, 0.3, 0.12), circle(0.4, 0.35, 0.1), circle(0.33, 0.2, 0.05),
                  polygon({{0.6, 0.6}, {0.9, 0.62}, {0.8, 0.9}, {0.7, 0.75}, {0.62, 0.85}}, 3),
                  circle(0.98, 0.2, 0.1), polygon({{0.1, 0.7}, {0.3, 0.7}, {0.2, 0.9}}, 2)};
  return s;
}
}  // namespace

TEST(Oracle2, CrossingsAgreeWithDenseSampling) {
  Oracle2 o(mixed_scene());
  auto c = all(o);
  std::mt19937_64 rng(7);
  std::uniform_real_distribution<double> u(0.0, 1.0);
  std::vector<Crossing> cr, cr2;
  std::vector<std::int32_t> sub;
  int total = 0;
  for (int trial = 0; trial < 400; ++trial) {
    const Vec2 a{u(rng), u(rng)}, b{u(rng), u(rng)};
    o.crossings(a, b, c, cr);
    total += static_cast<int>(cr.size());
    for (std::size_t i = 1; i < cr.size(); ++i) {
      EXPECT_LT(cr[i - 1].t, cr[i].t);
      EXPECT_EQ(cr[i - 1].to_phase, cr[i].from_phase);
    }
    for (const Crossing& x : cr) EXPECT_NE(x.from_phase, x.to_phase);
    auto at = [&](double t) { return o.phase_at({a[0] + t * (b[0] - a[0]), a[1] + t * (b[1] - a[1])}, c); };
    // Between crossings the phase is constant and as reported.
    const int n = 2000;
    for (int k = 1; k < n; ++k) {
      const double t = double(k) / n;
      bool near = false;
      int expected = cr.empty() ? at(0.5) : cr[0].from_phase;
      for (const Crossing& x : cr) {
        if (std::abs(t - x.t) < 1e-9) near = true;
        if (x.t < t) expected = x.to_phase;
      }
      if (!near) {
        EXPECT_EQ(at(t), expected) << "trial " << trial << " t " << t;
      }
    }
    // Each crossing is accurate: the phase flips within 1e-12 around t.
    const double len = std::hypot(b[0] - a[0], b[1] - a[1]);
    for (const Crossing& x : cr) {
      const double d = 1e-12 / len;
      EXPECT_EQ(at(x.t - d), x.from_phase);
      EXPECT_EQ(at(x.t + d), x.to_phase);
    }
    // Determinism: only the inclusions whose box meets the segment.
    Box2 sb{{std::min(a[0], b[0]), std::min(a[1], b[1])}, {std::max(a[0], b[0]), std::max(a[1], b[1])}};
    o.candidates(sb, sub);
    o.crossings(a, b, sub, cr2);
    ASSERT_EQ(cr.size(), cr2.size());
    for (std::size_t i = 0; i < cr.size(); ++i) {
      EXPECT_EQ(std::memcmp(&cr[i].t, &cr2[i].t, sizeof(double)), 0);
      EXPECT_EQ(cr[i].inclusion, cr2[i].inclusion);
    }
  }
  EXPECT_GT(total, 100);
}

TEST(Oracle2, CandidatesMatchBruteForce) {
  SceneDesc s = base_scene();
  std::mt19937_64 rng(3);
  std::uniform_real_distribution<double> u(0.0, 1.0);
  for (int i = 0; i < 600; ++i) s.inclusions.push_back(circle(u(rng), u(rng), 0.002 + 0.02 * u(rng)));
  Oracle2 o(s);
  std::vector<std::int32_t> got;
  for (int q = 0; q < 500; ++q) {
    const double x = u(rng), y = u(rng), w = 0.1 * u(rng), h = 0.1 * u(rng);
    const Box2 box{{x, y}, {x + w, y + h}};
    o.candidates(box, got);
    std::vector<std::int32_t> want;
    for (int k = 0; k < o.inclusion_count(); ++k)
      if (boxes_overlap(box, o.bounding_box(k))) want.push_back(k);
    EXPECT_EQ(got, want);
  }
  // A box touching a bounding box at one corner counts (closed boxes).
  const Box2 bb = o.bounding_box(0);
  o.candidates(Box2{bb.max, {bb.max[0] + 1, bb.max[1] + 1}}, got);
  EXPECT_NE(std::find(got.begin(), got.end(), 0), got.end());
}

TEST(Oracle2, BoundaryTouchesIsConservative) {
  Oracle2 o(mixed_scene());
  std::mt19937_64 rng(11);
  std::uniform_real_distribution<double> u(0.0, 1.0);
  int touching = 0, exact_false = 0;
  for (int q = 0; q < 3000; ++q) {
    const double x = u(rng), y = u(rng), w = 0.05 * u(rng);
    const Box2 box{{x, y}, {x + w, y + w}};
    for (int k = 0; k < o.inclusion_count(); ++k) {
      // Sample the boundary: boundary points in the box force `true`.
      auto c = std::vector<std::int32_t>{k};
      bool in = false, out = false;
      for (int i = 0; i <= 8; ++i)
        for (int j = 0; j <= 8; ++j) {
          const PhaseMask m = o.closure_phases({x + w * i / 8, y + w * j / 8}, c);
          (m & bit(0) ? out : in) = true;
        }
      const bool t = o.boundary_touches(k, box);
      if (in && out) {
        EXPECT_TRUE(t) << k;
        ++touching;
      }
      if (!in && !t) ++exact_false;
    }
  }
  EXPECT_GT(touching, 50);
  EXPECT_GT(exact_false, 1000);
}

TEST(Oracle2, ValidationErrors) {
  auto build = [](std::vector<Inclusion> inc) {
    SceneDesc s = base_scene();
    s.source = "scene.json";
    s.inclusions = std::move(inc);
    return [s] { Oracle2 o(s); };
  };
  expect_input_error(build({circle(0.5, 0.5, 0)}), "inclusions[0].radius", "positive");
  expect_input_error(build({circle(0.5, 0.5, 0.1), circle(0.5, 0.5, -1)}), "inclusions[1].radius", "positive");
  expect_input_error(build({{Ellipse{{0.5, 0.5}, {0.1, 0}, 0}, 2, 0}}), "inclusions[0].semi_axes", "positive");
  expect_input_error(build({polygon({{0, 0}, {1, 0}, {1, 0}})}), "inclusions[0].vertices", "3 distinct");
  expect_input_error(build({polygon({{0, 0}, {0.5, 0.5}, {1, 1}})}), "inclusions[0].vertices", "zero area");
  expect_input_error(build({polygon({{0.1, 0.1}, {0.9, 0.9}, {0.9, 0.1}, {0.1, 0.9}})}),
                     "inclusions[0].vertices", "self-intersecting (edges 0 and 2)");
  expect_input_error(build({polygon({{0.1, 0.1}, {0.9, 0.1}, {0.5, 0.1}, {0.5, 0.9}})}),
                     "inclusions[0].vertices", "self-intersecting");
  expect_input_error(build({circle(0.3, 0.5, 0.2, 2), circle(0.5, 0.5, 0.2, 3)}), "inclusions[1]",
                     "inclusions[0]");
  expect_input_error(build({circle(0.5, 0.5, 0.1, 2), polygon({{0.55, 0.55}, {0.9, 0.55}, {0.9, 0.9}}, 3)}),
                     "inclusions[1]", "inclusions[0]");
  // A polygon strictly inside a circle of another phase (no boundary contact).
  expect_input_error(build({circle(0.5, 0.5, 0.3, 2), polygon({{0.45, 0.45}, {0.55, 0.45}, {0.5, 0.55}}, 3)}),
                     "inclusions[1]", "inclusions[0]");
  expect_input_error(build({circle(0.5, 0.5, 0.1, 7)}), "inclusions[0].phase", "no phase");
  // Allowed: tangent circles of different phases, same-phase overlaps.
  EXPECT_NO_THROW(build({circle(0.25, 0.5, 0.25, 2), circle(0.75, 0.5, 0.25, 3)})());
  EXPECT_NO_THROW(build({circle(0.3, 0.5, 0.2, 2), circle(0.5, 0.5, 0.2, 2)})());
}

TEST(Oracle2, ManyInclusionsValidateQuickly) {
  SceneDesc s = base_scene();
  for (int i = 0; i < 100; ++i)
    for (int j = 0; j < 100; ++j)
      s.inclusions.push_back(circle((i + 0.5) / 100, (j + 0.5) / 100, 0.004, 2 + (i + j) % 2));
  Oracle2 o(s);
  EXPECT_EQ(o.inclusion_count(), 10000);
  EXPECT_EQ(o.interface_group(5), 5);
}

TEST(Oracle2, InterfaceGroupsAreTransitive) {
  SceneDesc s = base_scene();
  s.inclusions = {circle(0.2, 0.5, 0.1), circle(0.8, 0.5, 0.1), circle(0.4, 0.5, 0.1),
                  circle(0.5, 0.8, 0.05), circle(0.5, 0.5, 0.05)};
  Oracle2 o(s);
  EXPECT_EQ(o.interface_group(0), 0);
  EXPECT_EQ(o.interface_group(2), 0);  // touches 0 at (0.3, 0.5)
  EXPECT_EQ(o.interface_group(4), 0);  // overlaps 2
  EXPECT_EQ(o.interface_group(1), 1);
  EXPECT_EQ(o.interface_group(3), 3);
}

TEST(Oracle2, AreasMatchAnalyticFormulas) {
  SceneDesc s = base_scene();
  s.inclusions = {circle(0.3, 0.3, 0.1),
                  polygon({{0.6, 0.6}, {0.9, 0.6}, {0.9, 0.8}, {0.7, 0.9}}, 3),
                  circle(1.0, 0.3, 0.1),                          // half inside the domain
                  circle(0.2, 0.75, 0.1), circle(0.3, 0.75, 0.1)};  // a lens pair
  Oracle2 o(s);
  const auto a = o.phase_measures();
  const double r = 0.1, d = 0.1;
  const double lens = 2 * r * r * std::acos(d / (2 * r)) - 0.5 * d * std::sqrt(4 * r * r - d * d);
  const double fiber = M_PI * r * r + 0.5 * M_PI * r * r + (2 * M_PI * r * r - lens);
  const double poly = 0.5 * std::abs((0.6 * 0.6 - 0.9 * 0.6) + (0.9 * 0.8 - 0.9 * 0.6) +
                                     (0.9 * 0.9 - 0.7 * 0.8) + (0.7 * 0.6 - 0.6 * 0.9));
  EXPECT_NEAR(a[1], fiber, 1e-11);
  EXPECT_NEAR(a[2], poly, 1e-12);
  EXPECT_NEAR(a[0], 1 - fiber - poly, 1e-11);
}

TEST(Oracle2, DistanceToPhase) {
  SceneDesc s = base_scene();
  s.inclusions = {circle(0.3, 0.3, 0.1), polygon({{0.6, 0.6}, {0.9, 0.6}, {0.9, 0.9}, {0.6, 0.9}}, 3)};
  Oracle2 o(s);
  EXPECT_DOUBLE_EQ(o.distance_to_phase({0.3, 0.6}, 1), 0.2);
  EXPECT_EQ(o.distance_to_phase({0.3, 0.35}, 1), 0.0);
  EXPECT_DOUBLE_EQ(o.distance_to_phase({0.3, 0.35}, 0), 0.05);
  EXPECT_DOUBLE_EQ(o.distance_to_phase({0.5, 0.7}, 2), 0.1);
  EXPECT_DOUBLE_EQ(o.distance_to_phase({1.0, 1.0}, 2), std::hypot(0.1, 0.1));
  EXPECT_NEAR(o.distance_to_phase({0.7, 0.65}, 0), 0.05, 1e-15);
  EXPECT_EQ(o.distance_to_phase({0.5, 0.5}, 0), 0.0);
}

// Overlapping same-phase clusters: the distance to the matrix is the distance to the
// boundary of the union, exact for circles and polygons (no boundary sampling).
TEST(Oracle2, DistanceToMatrixInsideOverlappingCircles) {
  SceneDesc s = base_scene();
  // Circles of radius 0.25 at x = 0.375 and 0.625 (y = 0.5): corners at x = 0.5,
  // y = 0.5 ± sqrt(0.0625 − 0.015625) = 0.5 ± 0.2165…
  s.inclusions = {circle(0.375, 0.5, 0.25), circle(0.625, 0.5, 0.25)};
  Oracle2 o(s);
  // On the union boundary (outside the other circle): exactly on circle 0.
  EXPECT_LE(o.distance_to_phase({0.125, 0.5}, 0), 1e-12);
  EXPECT_LE(o.distance_to_phase({0.375, 0.75}, 0), 1e-12);
  // The same points moved inside by one ulp: still ~0.
  EXPECT_LE(o.distance_to_phase({std::nextafter(0.125, 1.0), 0.5}, 0), 1e-12);
  EXPECT_LE(o.distance_to_phase({0.375, std::nextafter(0.75, 0.0)}, 0), 1e-12);
  // A rounded point on the union boundary (cos/sin): within rounding of 0.
  const double th = 2.0;
  EXPECT_LE(o.distance_to_phase({0.375 + 0.25 * std::cos(th), 0.5 + 0.25 * std::sin(th)}, 0), 1e-12);
  // Known depth: (0.2, 0.5) is 0.075 inside circle 0, far from circle 1's boundary.
  EXPECT_NEAR(o.distance_to_phase({0.2, 0.5}, 0), 0.075, 1e-15);
  // Near the upper corner (0.5, 0.5 + h): the nearest uncovered boundary point is the
  // corner itself (the nearest points of both circles are covered by the other one).
  const double h = std::sqrt(0.0625 - 0.015625);
  const Vec2 q{0.5, 0.5 + h - 0.01};
  EXPECT_NEAR(o.distance_to_phase(q, 0), 0.01, 1e-14);
  const Vec2 q2{0.49, 0.5 + h - 0.02};
  EXPECT_NEAR(o.distance_to_phase(q2, 0), std::hypot(0.01, 0.02), 1e-14);
  // At the center of the lens the answer is the corner distance h... or the nearer arc.
  EXPECT_NEAR(o.distance_to_phase({0.5, 0.5}, 0), h, 1e-14);
  // Crossings along y = 0.5: enter at 0.125, leave at 0.875, nothing at the inner arcs.
  std::vector<Crossing> cr;
  o.crossings({0, 0.5}, {1, 0.5}, all(o), cr);
  ASSERT_EQ(cr.size(), 2u);
  EXPECT_NEAR(cr[0].t, 0.125, 1e-15);
  EXPECT_NEAR(cr[1].t, 0.875, 1e-15);
  // Union area = 2πr² − lens.
  const double r = 0.25, d = 0.25;
  const double lens = 2 * r * r * std::acos(d / (2 * r)) - 0.5 * d * std::sqrt(4 * r * r - d * d);
  const auto areas = o.phase_measures();
  EXPECT_NEAR(areas[1], 2 * M_PI * r * r - lens, 1e-11);
  EXPECT_NEAR(areas[0], 1 - (2 * M_PI * r * r - lens), 1e-11);
}

TEST(Oracle2, DistanceToMatrixInsidePolygonClusters) {
  SceneDesc s = base_scene();
  // Two same-phase squares sharing the edge x = 0.5: the shared edge is not a boundary.
  s.inclusions = {polygon({{0.25, 0.25}, {0.5, 0.25}, {0.5, 0.75}, {0.25, 0.75}}),
                  polygon({{0.5, 0.25}, {0.75, 0.25}, {0.75, 0.75}, {0.5, 0.75}}),
                  // A circle overlapping the right square's corner region.
                  circle(0.8, 0.8, 0.1)};
  Oracle2 o(s);
  EXPECT_NEAR(o.distance_to_phase({0.5, 0.5}, 0), 0.25, 1e-15);
  EXPECT_NEAR(o.distance_to_phase({0.49, 0.3}, 0), 0.05, 1e-15);
  // (0.7, 0.7): inside the square, its nearest edges (x = 0.75, y = 0.75) are covered
  // near there by the circle; distance to x=0.75 at (0.75, 0.7) which the circle holds
  // ((0.05)² + (0.1)² > 0.01: not held). So 0.05 exactly.
  EXPECT_NEAR(o.distance_to_phase({0.7, 0.7}, 0), 0.05, 1e-15);
  // (0.74, 0.74): the points (0.75, 0.74) and (0.74, 0.75) are inside the circle; the
  // nearest uncovered point is a circle/edge corner: x = 0.75, y = 0.8 − sqrt(0.01 − 0.0025).
  const double yc = 0.8 - std::sqrt(0.01 - 0.0025);
  EXPECT_NEAR(o.distance_to_phase({0.74, 0.74}, 0), std::hypot(0.01, 0.74 - yc), 1e-14);
}
