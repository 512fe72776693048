// STEP import through OpenCASCADE (step_import, docs/nurbs-step-design.md §3.2, §4.2, §6):
// data/shapes/parts.step (written by data/shapes/make_step.cpp: the unit sphere at the
// origin, the torus R = 1, r = 0.3 about z at (4, 0, 0), the box [7, 9] × [−1, 1]² with
// every edge filleted at r = 0.3) read into BrepData and checked against the analytic
// shapes: volumes, the converted B-spline faces on the exact surfaces, the mesh on the
// faces at its corner (u, v), closed and outward, the trimming loops closed and
// counter-clockwise, the import deterministic; and the file errors, each naming the file.
// data/shapes/trimmed.step does the same for faces with holes and curved trims.
// Skipped when built with CISAMR_WITH_OCCT=OFF.
#include <gtest/gtest.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <random>
#include <functional>
#include <cstdint>
#include <cstdio>
#include <cstring>
#include <fstream>
#include <map>
#include <sstream>
#include <string>
#include <thread>

#include "core/vec_math.hpp"
#include "geometry/nurbs3.hpp"
#include "geometry/step_import.hpp"
#include "geometry/surface_body.hpp"

namespace cisamr::geometry {
namespace {

constexpr double kPi = 3.14159265358979323846;

#define SKIP_WITHOUT_OCCT() \
  if (!step_import_available()) GTEST_SKIP() << "built with CISAMR_WITH_OCCT=OFF"

std::string read_bytes(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  EXPECT_TRUE(in.good()) << path;
  std::ostringstream s;
  s << in.rdbuf();
  return s.str();
}

std::string shape_file(const char* name) { return read_bytes(std::string(CISAMR_SOURCE_DIR "/data/shapes/") + name); }

// parts.step imported once per process (and timed).
const BrepData& parts() {
  static const BrepData data = [] {
    BrepData d;
    const std::string bytes = shape_file("parts.step");
    const auto t0 = std::chrono::steady_clock::now();
    const std::string problem = import_step(bytes, "parts.step", d);
    const double s = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
    EXPECT_EQ(problem, "");
    std::printf("[ import   ] parts.step (%zu bytes): %.3f s\n", bytes.size(), s);
    return d;
  }();
  return data;
}

// Rational de Boor on one open curve, independent of lib/geometry.
Vec2 curve_point(const BrepCurve2& c, double t) {
  const int p = c.degree;
  const int n = static_cast<int>(c.control_points.size());
  int k = p;
  while (k < n - 1 && t >= c.knots[static_cast<std::size_t>(k + 1)]) ++k;
  std::vector<std::array<double, 3>> d(static_cast<std::size_t>(p + 1));
  for (int j = 0; j <= p; ++j) {
    const std::size_t i = static_cast<std::size_t>(j + k - p);
    const double w = c.weights[i];
    d[static_cast<std::size_t>(j)] = {c.control_points[i][0] * w, c.control_points[i][1] * w, w};
  }
  for (int r = 1; r <= p; ++r)
    for (int j = p; j >= r; --j) {
      const double lo = c.knots[static_cast<std::size_t>(j + k - p)];
      const double hi = c.knots[static_cast<std::size_t>(j + 1 + k - r)];
      const double a = hi > lo ? (t - lo) / (hi - lo) : 0.0;
      for (int e = 0; e < 3; ++e)
        d[static_cast<std::size_t>(j)][static_cast<std::size_t>(e)] =
            (1 - a) * d[static_cast<std::size_t>(j - 1)][static_cast<std::size_t>(e)] +
            a * d[static_cast<std::size_t>(j)][static_cast<std::size_t>(e)];
    }
  const auto& h = d[static_cast<std::size_t>(p)];
  return {h[0] / h[2], h[1] / h[2]};
}
Vec2 curve_start(const BrepCurve2& c) { return curve_point(c, c.knots.front()); }
Vec2 curve_end(const BrepCurve2& c) { return curve_point(c, c.knots.back()); }

bool clamped(const std::vector<double>& knots, int degree) {
  const std::size_t m = static_cast<std::size_t>(degree) + 1;
  if (knots.size() < 2 * m) return false;
  for (std::size_t i = 1; i < m; ++i)
    if (knots[i] != knots[0] || knots[knots.size() - 1 - i] != knots.back()) return false;
  return true;
}

// Signed area enclosed by a loop, from 64 samples per curve (the loops here are
// rectangles in (u, v), so this is their area to rounding).
double loop_area(const std::vector<BrepCurve2>& loop) {
  double area = 0;
  for (const BrepCurve2& c : loop) {
    const double t0 = c.knots.front(), t1 = c.knots.back();
    Vec2 a = curve_point(c, t0);
    for (int i = 1; i <= 64; ++i) {
      const Vec2 b = curve_point(c, t0 + (t1 - t0) * i / 64);
      area += 0.5 * (a[0] * b[1] - a[1] * b[0]);
      a = b;
    }
  }
  return area;
}

std::array<double, 4> loops_box(const BrepFace& f) {  // u0, u1, v0, v1
  std::array<double, 4> b{1e300, -1e300, 1e300, -1e300};
  for (const auto& loop : f.loops)
    for (const BrepCurve2& c : loop)
      for (int i = 0; i <= 64; ++i) {
        const Vec2 x = curve_point(c, c.knots.front() + (c.knots.back() - c.knots.front()) * i / 64);
        b = {std::min(b[0], x[0]), std::max(b[1], x[0]), std::min(b[2], x[1]), std::max(b[3], x[1])};
      }
  return b;
}

// Distance from x to the box [lo, hi]³ (0 inside).
double box_distance(const Vec3& x, const Vec3& lo, const Vec3& hi) {
  double s = 0;
  for (int d = 0; d < 3; ++d) {
    const double e = std::max({lo[d] - x[d], 0.0, x[d] - hi[d]});
    s += e * e;
  }
  return std::sqrt(s);
}

// How far from the analytic surface of solid k of parts.step a point is.
double analytic_error(std::size_t k, const Vec3& x) {
  if (k == 0) return std::abs(norm(x) - 1.0);
  if (k == 1) {
    const double rho = std::hypot(x[0] - 4.0, x[1]);
    return std::abs(std::hypot(rho - 1.0, x[2]) - 0.3);
  }
  return std::abs(box_distance(x, {7.3, -0.7, -0.7}, {8.7, 0.7, 0.7}) - 0.3);
}

TEST(StepImport, PartsSolidsVolumesAndBoxes) {
  SKIP_WITHOUT_OCCT();
  const BrepData& d = parts();
  ASSERT_EQ(d.solids.size(), 3u);
  EXPECT_EQ(d.solids[0].faces.size(), 1u);   // sphere: one face, seam and two poles
  EXPECT_EQ(d.solids[1].faces.size(), 1u);   // torus: one face, two seams
  EXPECT_EQ(d.solids[2].faces.size(), 26u);  // 6 planes, 12 cylinders, 8 sphere corners
  const double r = 0.3, p = 2 - 2 * r;
  const double expected[3] = {4 * kPi / 3, 2 * kPi * kPi * 1.0 * r * r,
                              p * p * p + 2 * (3 * p * p) * r + kPi * (3 * p) * r * r + 4 * kPi * r * r * r / 3};
  const Box3 boxes[3] = {{{-1, -1, -1}, {1, 1, 1}}, {{2.7, -1.3, -0.3}, {5.3, 1.3, 0.3}}, {{7, -1, -1}, {9, 1, 1}}};
  for (std::size_t k = 0; k < 3; ++k) {
    const BrepSolid& s = d.solids[k];
    EXPECT_NEAR(s.volume, expected[k], 1e-9 * expected[k]) << "solid " << k;
    for (int a = 0; a < 3; ++a) {
      EXPECT_NEAR(s.box.min[a], boxes[k].min[a], 1e-6) << "solid " << k << " axis " << a;
      EXPECT_NEAR(s.box.max[a], boxes[k].max[a], 1e-6) << "solid " << k << " axis " << a;
    }
    for (const Vec3& v : s.vertices)
      for (int a = 0; a < 3; ++a) ASSERT_TRUE(v[a] >= s.box.min[a] && v[a] <= s.box.max[a]);
    EXPECT_EQ(s.triangle_face.size(), s.triangles.size());
    EXPECT_EQ(s.triangle_uv.size(), s.triangles.size());
  }
  // Every face is a clamped B-spline surface (planes too: degree 1 × 1 after NurbsConvert).
  int planes = 0;
  for (const BrepFace& f : d.solids[2].faces) planes += f.surface.degree == std::array<int, 2>{1, 1};
  EXPECT_EQ(planes, 6);
}

TEST(StepImport, FacesAreClampedPatchesWithClosedCounterClockwiseLoops) {
  SKIP_WITHOUT_OCCT();
  for (std::size_t k = 0; k < parts().solids.size(); ++k)
    for (std::size_t j = 0; j < parts().solids[k].faces.size(); ++j) {
      const BrepFace& f = parts().solids[k].faces[j];
      SCOPED_TRACE("solid " + std::to_string(k) + " face " + std::to_string(j));
      nurbs::PatchPieces pieces;
      EXPECT_EQ(nurbs::extract_patch(f.surface, pieces), "");
      EXPECT_TRUE(clamped(f.surface.knots_u, f.surface.degree[0]));
      EXPECT_TRUE(clamped(f.surface.knots_v, f.surface.degree[1]));
      EXPECT_EQ(f.surface.weights.size(), f.surface.control_points.size());
      EXPECT_GT(f.tolerance, 0.0);
      EXPECT_LE(f.edge_tolerance, 1e-6);
      ASSERT_EQ(f.loops.size(), 1u);  // no holes in these shapes
      double area = 0;
      for (const auto& loop : f.loops) {
        ASSERT_FALSE(loop.empty());
        for (std::size_t c = 0; c < loop.size(); ++c) {
          const BrepCurve2& curve = loop[c];
          EXPECT_TRUE(clamped(curve.knots, curve.degree));
          EXPECT_EQ(curve.knots.size(), curve.control_points.size() + static_cast<std::size_t>(curve.degree) + 1);
          EXPECT_EQ(curve.weights.size(), curve.control_points.size());
          const Vec2 gap = sub(curve_start(loop[(c + 1) % loop.size()]), curve_end(curve));
          EXPECT_LT(norm(gap), 1e-9) << "curve " << c;
        }
        area += loop_area(loop);
      }
      // The loops lie in the patch's parameter rectangle and, for these shapes, fill it.
      const std::array<double, 4> b = loops_box(f);
      EXPECT_NEAR(b[0], f.surface.knots_u.front(), 1e-9);
      EXPECT_NEAR(b[1], f.surface.knots_u.back(), 1e-9);
      EXPECT_NEAR(b[2], f.surface.knots_v.front(), 1e-9);
      EXPECT_NEAR(b[3], f.surface.knots_v.back(), 1e-9);
      EXPECT_NEAR(area, (b[1] - b[0]) * (b[3] - b[2]), 1e-9) << "counter-clockwise, the face inside";
    }
}

TEST(StepImport, SphereLoopHasTheSeamTwiceAndBothPoles) {
  SKIP_WITHOUT_OCCT();
  const BrepFace& f = parts().solids[0].faces[0];
  ASSERT_EQ(f.loops.size(), 1u);
  const auto& loop = f.loops[0];
  ASSERT_EQ(loop.size(), 4u);
  const double u0 = f.surface.knots_u.front(), u1 = f.surface.knots_u.back();
  const double v0 = f.surface.knots_v.front(), v1 = f.surface.knots_v.back();
  EXPECT_NEAR(u1 - u0, 2 * kPi, 1e-12);
  EXPECT_NEAR(v1 - v0, kPi, 1e-12);
  int seams = 0, poles = 0;
  for (const BrepCurve2& c : loop) {
    const Vec2 a = curve_start(c), b = curve_end(c);
    if (a[0] == b[0] && (a[0] == u0 || a[0] == u1)) ++seams;  // iso-u on the seam
    if (a[1] == b[1] && (a[1] == v0 || a[1] == v1)) {         // iso-v at a pole
      ++poles;
      nurbs::PatchPieces pieces;
      ASSERT_EQ(nurbs::extract_patch(f.surface, pieces), "");
      const Vec3 x = nurbs::evaluate(pieces, 0.5 * (u0 + u1), a[1]);
      EXPECT_NEAR(std::abs(x[2]), 1.0, 1e-15);
    }
  }
  EXPECT_EQ(seams, 2);
  EXPECT_EQ(poles, 2);
}

TEST(StepImport, ConvertedFacesLieOnTheAnalyticSurfaces) {
  SKIP_WITHOUT_OCCT();
  for (std::size_t k = 0; k < 3; ++k) {
    double worst = 0;
    for (const BrepFace& f : parts().solids[k].faces) {
      nurbs::PatchPieces pieces;
      ASSERT_EQ(nurbs::extract_patch(f.surface, pieces), "");
      const std::array<double, 4> b = loops_box(f);  // the trim here is the whole rectangle
      for (int i = 0; i <= 40; ++i)
        for (int j = 0; j <= 40; ++j) {
          const double u = std::clamp(b[0] + (b[1] - b[0]) * i / 40, f.surface.knots_u.front(), f.surface.knots_u.back());
          const double v = std::clamp(b[2] + (b[3] - b[2]) * j / 40, f.surface.knots_v.front(), f.surface.knots_v.back());
          worst = std::max(worst, analytic_error(k, nurbs::evaluate(pieces, u, v)));
        }
    }
    EXPECT_LT(worst, 1e-9) << "solid " << k;
    std::printf("[ exact    ] solid %zu: converted faces within %.2e of the analytic surface\n", k, worst);
  }
}

TEST(StepImport, MeshCornersLieOnTheirFaces) {
  SKIP_WITHOUT_OCCT();
  for (std::size_t k = 0; k < 3; ++k) {
    const BrepSolid& s = parts().solids[k];
    std::vector<nurbs::PatchPieces> pieces(s.faces.size());
    for (std::size_t j = 0; j < s.faces.size(); ++j) ASSERT_EQ(nurbs::extract_patch(s.faces[j].surface, pieces[j]), "");
    double worst = 0, worst_analytic = 0;
    for (std::size_t t = 0; t < s.triangles.size(); ++t) {
      const std::size_t j = static_cast<std::size_t>(s.triangle_face[t]);
      ASSERT_LT(j, s.faces.size());
      const NurbsPatch& patch = s.faces[j].surface;
      for (int c = 0; c < 3; ++c) {
        const Vec2 uv = s.triangle_uv[t][static_cast<std::size_t>(c)];
        ASSERT_TRUE(uv[0] >= patch.knots_u.front() - 1e-12 && uv[0] <= patch.knots_u.back() + 1e-12);
        ASSERT_TRUE(uv[1] >= patch.knots_v.front() - 1e-12 && uv[1] <= patch.knots_v.back() + 1e-12);
        const Vec3& x = s.vertices[static_cast<std::size_t>(s.triangles[t][static_cast<std::size_t>(c)])];
        worst = std::max(worst, norm(sub(nurbs::evaluate(pieces[j], uv[0], uv[1]), x)));
        worst_analytic = std::max(worst_analytic, analytic_error(k, x));
      }
    }
    EXPECT_LT(worst, 1e-6) << "solid " << k;
    EXPECT_LT(worst_analytic, 1e-6) << "solid " << k;
    std::printf("[ mesh     ] solid %zu: %zu vertices, %zu triangles; corners within %.2e of their face at "
                "their (u, v), %.2e of the analytic surface\n",
                k, s.vertices.size(), s.triangles.size(), worst, worst_analytic);
  }
}

TEST(StepImport, MeshIsClosedOutwardAndHoldsTheVolume) {
  SKIP_WITHOUT_OCCT();
  for (std::size_t k = 0; k < 3; ++k) {
    const BrepSolid& s = parts().solids[k];
    SCOPED_TRACE("solid " + std::to_string(k));
    std::map<std::pair<std::int32_t, std::int32_t>, int> directed;
    double six_volume = 0, area = 0, sag = 0;
    for (const auto& t : s.triangles) {
      ASSERT_TRUE(t[0] != t[1] && t[1] != t[2] && t[2] != t[0]);
      for (int c = 0; c < 3; ++c) ++directed[{t[static_cast<std::size_t>(c)], t[static_cast<std::size_t>((c + 1) % 3)]}];
      const Vec3 &a = s.vertices[static_cast<std::size_t>(t[0])], &b = s.vertices[static_cast<std::size_t>(t[1])],
                 &c = s.vertices[static_cast<std::size_t>(t[2])];
      six_volume += dot(a, cross(b, c));
      area += 0.5 * norm(cross(sub(b, a), sub(c, a)));
      sag = std::max(sag, analytic_error(k, scale(add(add(a, b), c), 1.0 / 3)));
    }
    std::size_t bad = 0;
    for (const auto& [e, n] : directed) {
      const auto back = directed.find({e.second, e.first});
      if (n != 1 || back == directed.end() || back->second != 1) ++bad;
    }
    EXPECT_EQ(bad, 0u) << "every edge in exactly two triangles, once each way";
    // BRepMesh's linear deflection, 2e-3 of the box diagonal: the centroids sag less,
    // and the mesh misses less volume than its area times the deflection. That is within
    // 1 % of the volume for the sphere and the box, not for the thin torus (1.4 %).
    const double deflection = 2e-3 * norm(sub(s.box.max, s.box.min));
    const double volume = six_volume / 6;
    EXPECT_GT(volume, 0.0);
    EXPECT_LE(sag, deflection);
    EXPECT_NEAR(volume, s.volume, area * deflection);
    if (k != 1) {
      EXPECT_NEAR(volume, s.volume, 0.01 * s.volume);
    }
    std::printf("[ mesh     ] solid %zu: mesh volume %.6f, solid %.6f (%.2e relative); centroids within %.2e of the "
                "surface (deflection %.2e)\n",
                k, volume, s.volume, volume / s.volume - 1, sag, deflection);
  }
}

std::uint64_t hash_of(const BrepData& d) {
  std::uint64_t h = 1469598103934665603ull;
  const auto mix = [&h](std::uint64_t x) {
    for (int i = 0; i < 8; ++i) h = (h ^ ((x >> (8 * i)) & 0xff)) * 1099511628211ull;
  };
  const auto real = [&mix](double x) {
    std::uint64_t b;
    std::memcpy(&b, &x, sizeof b);
    mix(b);
  };
  for (const BrepSolid& s : d.solids) {
    mix(s.faces.size());
    for (const BrepFace& f : s.faces) {
      mix(static_cast<std::uint64_t>(f.surface.degree[0]) * 64 + static_cast<std::uint64_t>(f.surface.degree[1]));
      for (double x : f.surface.knots_u) real(x);
      for (double x : f.surface.knots_v) real(x);
      for (const Vec3& p : f.surface.control_points) real(p[0]), real(p[1]), real(p[2]);
      for (double w : f.surface.weights) real(w);
      for (const auto& loop : f.loops) {
        mix(loop.size());
        for (const BrepCurve2& c : loop) {
          mix(static_cast<std::uint64_t>(c.degree));
          for (double x : c.knots) real(x);
          for (const Vec2& p : c.control_points) real(p[0]), real(p[1]);
          for (double w : c.weights) real(w);
        }
      }
      real(f.tolerance), real(f.edge_tolerance), mix(f.reversed);
    }
    for (const Vec3& v : s.vertices) real(v[0]), real(v[1]), real(v[2]);
    for (const auto& t : s.triangles) mix(static_cast<std::uint64_t>(t[0])), mix(static_cast<std::uint64_t>(t[1])), mix(static_cast<std::uint64_t>(t[2]));
    for (std::int32_t f : s.triangle_face) mix(static_cast<std::uint64_t>(f));
    for (const auto& t : s.triangle_uv)
      for (const Vec2& uv : t) real(uv[0]), real(uv[1]);
    real(s.volume);
    for (int a = 0; a < 3; ++a) real(s.box.min[a]), real(s.box.max[a]);
  }
  return h;
}

TEST(StepImport, Deterministic) {
  SKIP_WITHOUT_OCCT();
  BrepData again;
  ASSERT_EQ(import_step(shape_file("parts.step"), "parts.step", again), "");
  EXPECT_EQ(hash_of(again), hash_of(parts()));
  std::printf("[ hash     ] parts.step: %016llx\n", static_cast<unsigned long long>(hash_of(again)));
  // Imports from two threads at once (serialised inside) give the same data.
  BrepData t1, t2;
  std::string e1, e2;
  std::thread a([&] { e1 = import_step(shape_file("parts.step"), "parts.step", t1); });
  std::thread b([&] { e2 = import_step(shape_file("parts.step"), "parts.step", t2); });
  a.join();
  b.join();
  EXPECT_EQ(e1, "");
  EXPECT_EQ(e2, "");
  EXPECT_EQ(hash_of(t1), hash_of(parts()));
  EXPECT_EQ(hash_of(t2), hash_of(parts()));
  // A solid alone in its file imports as the same data as in parts.step.
  BrepData sphere;
  ASSERT_EQ(import_step(shape_file("sphere.step"), "sphere.step", sphere), "");
  ASSERT_EQ(sphere.solids.size(), 1u);
  BrepData first;
  first.solids = {parts().solids[0]};
  EXPECT_EQ(hash_of(sphere), hash_of(first));
}

TEST(StepImport, SingleShapeFiles) {
  SKIP_WITHOUT_OCCT();
  for (const char* name : {"sphere.step", "torus.step", "filleted_box.step"}) {
    BrepData d;
    EXPECT_EQ(import_step(shape_file(name), name, d), "");
    EXPECT_EQ(d.solids.size(), 1u) << name;
  }
}

// The problem for these bytes, checked to start with the file name.
std::string problem_of(const std::string& bytes, const std::string& name) {
  BrepData d;
  d.solids.resize(1);
  const std::string problem = import_step(bytes, name, d);
  EXPECT_TRUE(d.solids.empty()) << "out is cleared on failure";
  EXPECT_EQ(problem.rfind(name + ": ", 0), 0u) << problem;
  EXPECT_EQ(problem.find('\n'), std::string::npos) << problem;
  return problem;
}

bool has(const std::string& text, const char* part) { return text.find(part) != std::string::npos; }

TEST(StepImport, ErrorsNameTheFile) {
  SKIP_WITHOUT_OCCT();
  const std::string parts_bytes = shape_file("parts.step");

  std::string garbage(3000, '\0');
  std::uint64_t x = 88172645463325252ull;
  for (char& c : garbage) {
    x ^= x << 13, x ^= x >> 7, x ^= x << 17;
    c = static_cast<char>(x & 0xff);
  }
  std::string e = problem_of(garbage, "garbage.step");
  EXPECT_TRUE(has(e, "not a readable STEP file")) << e;
  EXPECT_TRUE(has(e, "Line ")) << e;
  e = problem_of("solid cube\nendsolid cube\n", "cube.step");
  EXPECT_TRUE(has(e, "not a readable STEP file")) << e;
  e = problem_of("", "empty.step");
  EXPECT_TRUE(has(e, "empty file")) << e;

  // Truncated in the middle of an entity, and after a whole entity (references dangle).
  e = problem_of(parts_bytes.substr(0, parts_bytes.size() / 2), "half.step");
  EXPECT_TRUE(has(e, "not a readable STEP file")) << e;
  const std::size_t cut = parts_bytes.find(";\n#1000 =");
  ASSERT_NE(cut, std::string::npos);
  e = problem_of(parts_bytes.substr(0, cut + 2), "cut.step");
  std::printf("[ errors   ] %s\n", e.c_str());

  // An entity missing: the reference to it dangles.
  std::string dangling = shape_file("sphere.step");
  const std::string surface = "#22 = SPHERICAL_SURFACE('',#23,1.);\n";
  ASSERT_NE(dangling.find(surface), std::string::npos);
  dangling.erase(dangling.find(surface), surface.size());
  e = problem_of(dangling, "dangling.step");
  EXPECT_TRUE(has(e, "#17") && has(e, "#22")) << e;
  std::printf("[ errors   ] %s\n", e.c_str());

  // An ADVANCED_FACE whose face_geometry is a FACE_BOUND.
  std::string bad = parts_bytes;
  const std::string face = "#17 = ADVANCED_FACE('',(#18),#22,.T.);";
  ASSERT_NE(bad.find(face), std::string::npos);
  bad.replace(bad.find(face), face.size(), "#17 = ADVANCED_FACE('',(#18),#18,.T.);");
  e = problem_of(bad, "bad.step");
  EXPECT_TRUE(has(e, "entity #17 (ADVANCED_FACE)")) << e;
  EXPECT_TRUE(has(e, "face_geometry")) << e;

  // A lone face, and a MANIFOLD_SOLID_BREP whose shell misses a face: no solid, open shell.
  e = problem_of(shape_file("open_shell.step"), "open_shell.step");
  EXPECT_TRUE(has(e, "no solid") && has(e, "open shell") && has(e, "1 face")) << e;
  e = problem_of(shape_file("open_solid.step"), "open_solid.step");
  EXPECT_TRUE(has(e, "no solid") && has(e, "open shell") && has(e, "5 faces")) << e;
  std::printf("[ errors   ] %s\n[ errors   ] %s\n", problem_of(garbage, "garbage.step").c_str(), e.c_str());

  // The filleted box's CLOSED_SHELL without its first face: the box is no solid any more.
  std::string open = parts_bytes;
  const std::string shell = "#114 = CLOSED_SHELL('',(#115,#235,";
  ASSERT_NE(open.find(shell), std::string::npos);
  open.replace(open.find(shell), shell.size(), "#114 = CLOSED_SHELL('',(#235,");
  e = problem_of(open, "open.step");
  EXPECT_TRUE(has(e, "open shell") && has(e, "25 faces")) << e;
  std::printf("[ errors   ] %s\n", e.c_str());
}

TEST(StepImport, CoordinatesInMillimetres) {
  SKIP_WITHOUT_OCCT();
  std::string metres = shape_file("sphere.step");
  const std::string mm = "SI_UNIT(.MILLI.,.METRE.)";
  ASSERT_NE(metres.find(mm), std::string::npos);
  metres.replace(metres.find(mm), mm.size(), "SI_UNIT($,.METRE.)");
  BrepData d;
  ASSERT_EQ(import_step(metres, "metres.step", d), "");
  ASSERT_EQ(d.solids.size(), 1u);
  EXPECT_NEAR(d.solids[0].volume, 4e9 * kPi / 3, 1e-9 * 4e9 * kPi / 3);
  EXPECT_NEAR(d.solids[0].box.max[2], 1000.0, 1e-6);
}

// The body of solid `si` (surface_body::build_brep) against f, its analytic form (negative
// inside): 20,000 points of its box on the right side wherever |f| > 1e-9, and 3,000
// segments whose exact roots lie on the surface (|f| ≤ 1e-9) and whose parity agrees with
// the sides of their ends.
void expect_body_like(const BrepData& data, int si, const std::function<double(const Vec3&)>& f, std::mt19937_64& rng) {
  SCOPED_TRACE("solid " + std::to_string(si));
  surface::Body body;
  ASSERT_EQ(surface::build_brep(data, {si}, surface::Placement{}, body), "");
  EXPECT_NEAR(surface::volume(body), data.solids[static_cast<std::size_t>(si)].volume, 1e-12);
  const Box3& b = body.box;
  auto random_point = [&] {
    Vec3 p;
    for (int k = 0; k < 3; ++k) p[k] = b.min[k] + (b.max[k] - b.min[k]) * (static_cast<double>(rng() >> 11) * 0x1.0p-53);
    return p;
  };
  int checked = 0;
  for (int i = 0; i < 20000; ++i) {
    const Vec3 p = random_point();
    const double fp = f(p);
    if (std::abs(fp) < 1e-9) continue;
    ASSERT_EQ(surface::side(body, p), fp < 0 ? 1 : -1) << "at " << p[0] << " " << p[1] << " " << p[2];
    ++checked;
  }
  EXPECT_GT(checked, 19000);
  std::vector<double> ts;
  for (int i = 0; i < 3000; ++i) {
    const Vec3 a = random_point(), c = random_point();
    const double fa = f(a), fc = f(c);
    if (std::abs(fa) < 1e-6 || std::abs(fc) < 1e-6) continue;
    ts.clear();
    surface::segment_roots(body, a, c, ts);
    for (double t : ts) {
      const Vec3 x{a[0] + t * (c[0] - a[0]), a[1] + t * (c[1] - a[1]), a[2] + t * (c[2] - a[2])};
      EXPECT_LE(std::abs(f(x)), 1e-9);
    }
    if (ts.size() % 2 != static_cast<std::size_t>((fa < 0) != (fc < 0))) {
      // A tangency can give a double root: only a mismatch far from tangency is wrong.
      ADD_FAILURE() << ts.size() << " roots, ends " << fa << " " << fc;
    }
  }
}

// The bodies of the imported solids (surface_body::build_brep) classify and cross like the
// analytic sphere, torus and filleted box, on the exact converted faces.
TEST(StepBody, SolidsClassifyAndCrossLikeTheirAnalyticForms) {
  SKIP_WITHOUT_OCCT();
  const BrepData& data = parts();
  ASSERT_EQ(data.solids.size(), 3u);
  const auto sphere_f = [](const Vec3& x) { return std::sqrt(x[0] * x[0] + x[1] * x[1] + x[2] * x[2]) - 1; };
  const auto torus_f = [](const Vec3& x) {
    return std::hypot(std::hypot(x[0] - 4, x[1]) - 1, x[2]) - 0.3;
  };
  const auto box_f = [](const Vec3& x) {  // distance to the inner box [7.3, 8.7] × [−0.7, 0.7]² minus 0.3
    const double dx = std::max(std::abs(x[0] - 8) - 0.7, 0.0), dy = std::max(std::abs(x[1]) - 0.7, 0.0),
                 dz = std::max(std::abs(x[2]) - 0.7, 0.0);
    const double outside = std::sqrt(dx * dx + dy * dy + dz * dz);
    const double inside = std::min(0.0, std::max({std::abs(x[0] - 8) - 0.7, std::abs(x[1]) - 0.7, std::abs(x[2]) - 0.7}));
    return outside + inside - 0.3;
  };
  const std::function<double(const Vec3&)> fs[3] = {sphere_f, torus_f, box_f};
  std::mt19937_64 rng(21);
  for (int si = 0; si < 3; ++si) expect_body_like(data, si, fs[si], rng);
  // All three as one body, placed: scale 0.1, translated.
  surface::Body all;
  surface::Placement pl;
  pl.scale = 0.1;
  pl.translate = {0.1, 0.5, 0.5};
  ASSERT_EQ(surface::build_brep(data, {}, pl, all), "");
  EXPECT_NEAR(surface::volume(all), 1e-3 * (data.solids[0].volume + data.solids[1].volume + data.solids[2].volume), 1e-14);
  EXPECT_EQ(surface::side(all, {0.1, 0.5, 0.5}), 1);                // the sphere's centre
  EXPECT_EQ(surface::side(all, {0.1 + 0.4, 0.5, 0.5}), -1);         // the torus's hole
  EXPECT_EQ(surface::side(all, {0.1 + 0.4 + 0.1, 0.5, 0.5}), 1);    // in its tube
  EXPECT_EQ(surface::side(all, {0.1 + 0.8, 0.5 + 0.099, 0.5}), 1);  // the box, near a face
}

// ---- trimmed.step (data/shapes/make_step.cpp): faces trimmed for real. A slab with a
// through hole (planar faces with a circular inner loop), a cylinder (planar faces bounded
// by circles) and a sphere cut by an oblique plane (a spherical face trimmed by a circle
// that is no parameter line, and a disc).

const BrepData& trimmed() {
  static const BrepData data = [] {
    BrepData d;
    EXPECT_EQ(import_step(shape_file("trimmed.step"), "trimmed.step", d), "");
    return d;
  }();
  return data;
}

// Their analytic forms in the file's coordinates, negative inside: maxima of exact signed
// distances, so zero exactly on the surface and no larger than the distance elsewhere.
const Vec3 kCutNormal{1 / std::sqrt(3.0), 1 / std::sqrt(3.0), 1 / std::sqrt(3.0)};
double holed_slab_f(const Vec3& x) {
  return std::max({std::abs(x[0]) - 1, std::abs(x[1]) - 1, std::abs(x[2]) - 0.5, 0.5 - std::hypot(x[0], x[1])});
}
double cylinder_f(const Vec3& x) { return std::max(std::hypot(x[0] - 4, x[1]) - 0.5, std::abs(x[2]) - 0.5); }
double cut_sphere_f(const Vec3& x) {
  const Vec3 d{x[0] - 8, x[1], x[2]};
  return std::max(norm(d) - 1, dot(d, kCutNormal) - 0.4);
}
const double kTrimmedVolumes[3] = {4 - kPi / 4, kPi / 4, 4 * kPi / 3 - kPi * 0.36 * (3 - 0.6) / 3};

TEST(StepImport, TrimmedFacesKeepTheirHolesAndCurvedBounds) {
  SKIP_WITHOUT_OCCT();
  const BrepData& d = trimmed();
  ASSERT_EQ(d.solids.size(), 3u);
  int holed = 0, trimmed_faces = 0;
  for (std::size_t k = 0; k < 3; ++k) {
    EXPECT_NEAR(d.solids[k].volume, kTrimmedVolumes[k], 1e-9 * kTrimmedVolumes[k]) << "solid " << k;
    for (const BrepFace& f : d.solids[k].faces) {
      holed += f.loops.size() == 2;
      double area = 0;
      for (const auto& loop : f.loops) area += loop_area(loop);
      const double rect = (f.surface.knots_u.back() - f.surface.knots_u.front()) *
                          (f.surface.knots_v.back() - f.surface.knots_v.front());
      EXPECT_GT(area, 0) << "solid " << k << ": the loops run with the face on their left";
      trimmed_faces += area < 0.999 * rect;  // the loops cut part of the parameter rectangle away
    }
  }
  EXPECT_EQ(holed, 2);           // the slab's top and bottom
  EXPECT_GE(trimmed_faces, 6);   // and the cylinder's caps, the cut sphere's sphere and disc
  const Vec3 probes[3][2] = {{{0, 0, 0}, {0.75, 0.75, 0}}, {{4, 0, 0.45}, {4.45, 0.2, 0}}, {{8, 0, 0}, {7.2, -0.3, 0}}};
  const std::function<double(const Vec3&)> fs[3] = {holed_slab_f, cylinder_f, cut_sphere_f};
  for (int k = 0; k < 3; ++k) {  // the analytic forms themselves: a point out, a point in
    EXPECT_GT(fs[k](probes[k][0]) * (k == 0 ? 1 : -1), 0) << k;
    EXPECT_LT(fs[k](probes[k][1]), 0) << k;
  }
}

TEST(StepBody, TrimmedSolidsClassifyAndCrossLikeTheirAnalyticForms) {
  SKIP_WITHOUT_OCCT();
  const BrepData& data = trimmed();
  ASSERT_EQ(data.solids.size(), 3u);
  const std::function<double(const Vec3&)> fs[3] = {holed_slab_f, cylinder_f, cut_sphere_f};
  std::mt19937_64 rng(22);
  for (int si = 0; si < 3; ++si) expect_body_like(data, si, fs[si], rng);

  // Next to a curved trim: segments through the cut sphere's disc just inside its rim
  // (between the rim and any chord of it) cross it, and points there are inside. A root
  // lost between a trimming polygon's chord and its arc would show here.
  surface::Body body;
  ASSERT_EQ(surface::build_brep(data, {2}, surface::Placement{}, body), "");
  const Vec3 n = kCutNormal, centre{8 + 0.4 * n[0], 0.4 * n[1], 0.4 * n[2]};
  const Vec3 c1 = cross(n, Vec3{0, 0, 1});
  const Vec3 e1 = scale(c1, 1 / norm(c1)), e2 = cross(n, e1);
  const double rim = std::sqrt(1 - 0.4 * 0.4);
  int lost = 0, wrong = 0, tried = 0;
  std::vector<double> ts;
  for (int i = 0; i < 720; ++i)
    for (double inset : {1e-6, 1e-5, 1e-4, 1e-3}) {
      const double angle = 2 * kPi * (i + 0.37) / 720;
      const Vec3 x = add(centre, add(scale(e1, (rim - inset) * std::cos(angle)), scale(e2, (rim - inset) * std::sin(angle))));
      ts.clear();
      surface::segment_roots(body, sub(x, scale(n, 1e-3)), add(x, scale(n, 1e-3)), ts);
      // The disc's root at the middle (a second one within the trim slack of the rim, on
      // the sphere just beyond the cut, is allowed: classification decides the events).
      lost += std::none_of(ts.begin(), ts.end(), [](double t) { return std::abs(t - 0.5) <= 1e-9; });
      wrong += surface::side(body, sub(x, scale(n, 1e-7))) != 1;
      ++tried;
    }
  EXPECT_EQ(lost, 0) << "of " << tried << " segments through the disc next to its rim";
  EXPECT_EQ(wrong, 0) << "of " << tried << " points just inside the disc next to its rim";
}

TEST(StepImport, WithoutOcctRefuses) {
  if (step_import_available()) GTEST_SKIP() << "built with CISAMR_WITH_OCCT=ON";
  BrepData d;
  EXPECT_EQ(import_step("ISO-10303-21;", "a.step", d), "step: this cisamr was built with CISAMR_WITH_OCCT=OFF");
}

}  // namespace
}  // namespace cisamr::geometry
