// Packing: zero overlaps by exact pairwise checks (independent of the packer's own GJK),
// fraction targets, determinism, periodic images, error paths.
#include <gtest/gtest.h>

#include <chrono>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <string>

#include <sys/stat.h>
#include <unistd.h>

#include "core/error.hpp"
#include "io/scene_io.hpp"
#include "pack/convex.hpp"
#include "pack/pack.hpp"
#include "pack/particles.hpp"
#include "pack/random.hpp"

using namespace cisamr;
using namespace cisamr::geometry;

namespace {

pack::PackResult run(const std::string& json) { return pack::pack(pack::parse_pack_spec(json, "test.json")); }

std::string spec2d(const std::string& population, const std::string& domain_extra = "",
                   const std::string& top = "") {
  return R"({"format": "cisamr-pack/1", "dimension": 2, "seed": 7, )" + top +
         R"("domain": {"min": [0, 0], "max": [100, 100])" + domain_extra + R"(},
            "mesh": {"h": 1, "levels": 2}, "populations": [)" + population + "]}";
}

// Eberly's robust distance from (y0, y1) ≥ 0 to the axis-aligned ellipse with e0 ≥ e1.
double distance_point_ellipse(double e0, double e1, double y0, double y1) {
  if (y1 > 0) {
    if (y0 > 0) {
      const double z0 = y0 / e0, z1 = y1 / e1, g = z0 * z0 + z1 * z1 - 1;
      if (g == 0) return 0;
      const double r0 = (e0 / e1) * (e0 / e1), n0 = r0 * z0;
      double s0 = z1 - 1, s1 = g < 0 ? 0 : std::hypot(n0, z1) - 1, s = 0;
      for (int i = 0; i < 2000; ++i) {
        s = 0.5 * (s0 + s1);
        if (s == s0 || s == s1) break;
        const double ratio0 = n0 / (s + r0), ratio1 = z1 / (s + 1);
        const double f = ratio0 * ratio0 + ratio1 * ratio1 - 1;
        if (f > 0) s0 = s; else if (f < 0) s1 = s; else break;
      }
      const double x0 = r0 * y0 / (s + r0), x1 = y1 / (s + 1);
      return std::hypot(x0 - y0, x1 - y1);
    }
    return std::abs(y1 - e1);
  }
  const double numer0 = e0 * y0, denom0 = e0 * e0 - e1 * e1;
  if (numer0 < denom0) {
    const double xde0 = numer0 / denom0, x0 = e0 * xde0, x1 = e1 * std::sqrt(1 - xde0 * xde0);
    return std::hypot(x0 - y0, x1);
  }
  return std::abs(y0 - e0);
}

// Exact intersection test of two closed ellipses: map A to the unit disk; B becomes an
// ellipse B' (SVD of the 2×2 map); they meet iff the origin is in B' or within 1 of it.
bool ellipses_intersect(const Ellipse& a, const Ellipse& b) {
  auto rot = [](double t) { return std::array<double, 4>{std::cos(t), -std::sin(t), std::sin(t), std::cos(t)}; };
  const auto ra = rot(a.angle), rb = rot(b.angle);
  // T(x) = D_A^{-1} R_A^T (x − c_A); M = D_A^{-1} R_A^T R_B D_B.
  const double dx = b.center[0] - a.center[0], dy = b.center[1] - a.center[1];
  const double cx = (ra[0] * dx + ra[2] * dy) / a.semi_axes[0], cy = (ra[1] * dx + ra[3] * dy) / a.semi_axes[1];
  double rr[4];  // R_A^T R_B
  rr[0] = ra[0] * rb[0] + ra[2] * rb[2]; rr[1] = ra[0] * rb[1] + ra[2] * rb[3];
  rr[2] = ra[1] * rb[0] + ra[3] * rb[2]; rr[3] = ra[1] * rb[1] + ra[3] * rb[3];
  const double m[4] = {rr[0] * b.semi_axes[0] / a.semi_axes[0], rr[1] * b.semi_axes[1] / a.semi_axes[0],
                       rr[2] * b.semi_axes[0] / a.semi_axes[1], rr[3] * b.semi_axes[1] / a.semi_axes[1]};
  // M Mᵀ = U Σ² Uᵀ.
  const double p = m[0] * m[0] + m[1] * m[1], q = m[0] * m[2] + m[1] * m[3], r = m[2] * m[2] + m[3] * m[3];
  const double mean = 0.5 * (p + r), diff = std::sqrt(0.25 * (p - r) * (p - r) + q * q);
  const double l0 = mean + diff, l1 = mean - diff;
  const double theta = 0.5 * std::atan2(2 * q, p - r);  // direction of the l0 eigenvector
  const double e0 = std::sqrt(l0), e1 = std::sqrt(std::max(l1, 0.0));
  // The origin in B' body coordinates.
  const double ox = -cx, oy = -cy;
  const double u = std::cos(theta) * ox + std::sin(theta) * oy, v = -std::sin(theta) * ox + std::cos(theta) * oy;
  if ((u / e0) * (u / e0) + (v / e1) * (v / e1) <= 1) return true;
  return distance_point_ellipse(e0, e1, std::abs(u), std::abs(v)) <= 1;
}

template <class T>
std::vector<T> all_of(const SceneDesc& s) {
  std::vector<T> out;
  for (const auto& inc : s.inclusions) out.push_back(std::get<T>(inc.shape));
  return out;
}

}  // namespace

TEST(PackCircles, NoOverlapWithGapExact) {
  const auto r = run(spec2d(R"({"shape": "circle", "count": 400, "min_gap": 0.4,
      "size": {"law": "uniform", "min": 1.0, "max": 2.5}})"));
  const auto c = all_of<Circle>(r.scene);
  ASSERT_EQ(c.size(), 400u);
  int close_pairs = 0;
  for (std::size_t i = 0; i < c.size(); ++i) {
    for (int d = 0; d < 2; ++d) {  // inside the domain, a gap away from its faces
      EXPECT_GE(c[i].center[d] - c[i].radius, 0.4 - 1e-12);
      EXPECT_LE(c[i].center[d] + c[i].radius, 100 - 0.4 + 1e-12);
    }
    for (std::size_t j = i + 1; j < c.size(); ++j) {
      const double d = std::hypot(c[i].center[0] - c[j].center[0], c[i].center[1] - c[j].center[1]);
      EXPECT_GE(d, c[i].radius + c[j].radius + 0.4 * (1 - 1e-9)) << i << " " << j;
      close_pairs += d < c[i].radius + c[j].radius + 1.0;
    }
  }
  EXPECT_GT(close_pairs, 0);  // the check is not vacuous: neighbours do come close
}

TEST(PackEllipses, NoOverlapExactAndGapSampled) {
  const auto r = run(spec2d(R"({"shape": "ellipse", "count": 350, "min_gap": 0.3,
      "size": {"law": "normal", "mean": 1.8, "std": 0.4, "min": 1.0},
      "aspect": {"law": "uniform", "min": 1.0, "max": 3.0}})"));
  const auto e = all_of<Ellipse>(r.scene);
  ASSERT_EQ(e.size(), 350u);
  int checked = 0;
  for (std::size_t i = 0; i < e.size(); ++i)
    for (std::size_t j = i + 1; j < e.size(); ++j) {
      const double reach = e[i].semi_axes[0] + e[j].semi_axes[0] + 0.3;
      if (std::hypot(e[i].center[0] - e[j].center[0], e[i].center[1] - e[j].center[1]) > reach) continue;
      ++checked;
      ASSERT_FALSE(ellipses_intersect(e[i], e[j])) << i << " " << j;
      // The gap, sampled: any two boundary points closer than the gap would be a violation.
      double best = INFINITY;
      for (int a = 0; a < 256; ++a)
        for (int b = 0; b < 256; ++b) {
          auto point = [](const Ellipse& el, int k) {
            const double t = 2 * M_PI * k / 256, x = el.semi_axes[0] * std::cos(t), y = el.semi_axes[1] * std::sin(t);
            return std::array<double, 2>{el.center[0] + std::cos(el.angle) * x - std::sin(el.angle) * y,
                                         el.center[1] + std::sin(el.angle) * x + std::cos(el.angle) * y};
          };
          const auto p = point(e[i], a), q = point(e[j], b);
          best = std::min(best, std::hypot(p[0] - q[0], p[1] - q[1]));
        }
      EXPECT_GE(best, 0.3 * (1 - 1e-9)) << i << " " << j;
    }
  EXPECT_GT(checked, 100);
}

TEST(PackEllipses, ExactTestSeesOverlaps) {  // the checker itself can fail
  Ellipse a{{0, 0}, {3, 1}, 0.3}, b{{3.5, 1.2}, {2, 0.5}, 1.2}, c{{10, 0}, {1, 1}, 0};
  EXPECT_TRUE(ellipses_intersect(a, b));
  EXPECT_FALSE(ellipses_intersect(a, c));
  Ellipse flat{{0, 0}, {3, 1}, 0}, touching{{4, 0}, {1, 1}, 0}, near{{4.001, 0}, {1, 1}, 0};
  EXPECT_TRUE(ellipses_intersect(flat, touching));
  EXPECT_FALSE(ellipses_intersect(flat, near));
}

TEST(PackConvex, GjkMatchesAnalyticDistances) {
  pack::Random rng(3);
  for (int k = 0; k < 2000; ++k) {
    Sphere a{{rng.uniform(0, 10), rng.uniform(0, 10), rng.uniform(0, 10)}, rng.uniform(0.5, 3)};
    Sphere b{{rng.uniform(0, 10), rng.uniform(0, 10), rng.uniform(0, 10)}, rng.uniform(0.5, 3)};
    const double d = std::sqrt(std::pow(a.center[0] - b.center[0], 2) + std::pow(a.center[1] - b.center[1], 2) +
                               std::pow(a.center[2] - b.center[2], 2)) - a.radius - b.radius;
    const double gap = rng.uniform(0, 2);
    const auto ba = pack::particle_body(a), bb = pack::particle_body(b);
    if (std::abs(d - gap) > 1e-8) EXPECT_EQ(pack::convex_within(ba, {}, bb, {}, gap), d < gap) << k;
    // Ellipses against the exact test (gap 0).
    Ellipse ea{{rng.uniform(0, 6), rng.uniform(0, 6)}, {rng.uniform(1, 3), rng.uniform(0.3, 1)}, rng.uniform(0, 3)};
    Ellipse eb{{rng.uniform(0, 6), rng.uniform(0, 6)}, {rng.uniform(1, 3), rng.uniform(0.3, 1)}, rng.uniform(0, 3)};
    const bool exact = ellipses_intersect(ea, eb);
    const bool gjk = pack::convex_within(pack::particle_body(ea), {}, pack::particle_body(eb), {}, 0);
    if (exact) EXPECT_TRUE(gjk) << k;  // never misses an overlap
    if (gjk && !exact) {              // false alarms only at touching distance
      const auto d2 = pack::convex_distance(pack::particle_body(ea), {}, pack::particle_body(eb), {}, 1e-12);
      EXPECT_LT(d2.lower, 1e-8) << k;
    }
  }
}

TEST(PackSpheres, VolumeFractionWithinToleranceAndNoOverlap) {
  const auto r = run(R"({"format": "cisamr-pack/1", "dimension": 3, "seed": 11,
      "domain": {"min": [0, 0, 0], "max": [40, 40, 40]}, "mesh": {"h": 1, "levels": 1},
      "populations": [{"shape": "sphere", "volume_fraction": 0.25, "tolerance": 0.005, "min_gap": 0.5,
                       "size": {"law": "lognormal", "mean": 2.5, "std": 0.6, "min": 1.2}}]})");
  const auto s = all_of<Sphere>(r.scene);
  double volume = 0;
  for (const auto& x : s) volume += 4.0 / 3.0 * M_PI * std::pow(x.radius, 3);
  const double fraction = volume / (40.0 * 40 * 40);
  EXPECT_NEAR(fraction, 0.25, 0.005);
  EXPECT_NEAR(r.report.populations[0].achieved_fraction, fraction, 1e-12);
  for (std::size_t i = 0; i < s.size(); ++i)
    for (std::size_t j = i + 1; j < s.size(); ++j) {
      const double d = std::sqrt(std::pow(s[i].center[0] - s[j].center[0], 2) +
                                 std::pow(s[i].center[1] - s[j].center[1], 2) +
                                 std::pow(s[i].center[2] - s[j].center[2], 2));
      ASSERT_GE(d, s[i].radius + s[j].radius + 0.5 * (1 - 1e-9)) << i << " " << j;
    }
}

TEST(PackFibres, CrossPlyNoOverlap) {
  const auto r = run(R"({"format": "cisamr-pack/1", "dimension": 3, "seed": 5,
      "domain": {"min": [0, 0, 0], "max": [30, 30, 30]}, "mesh": {"h": 0.5, "levels": 1},
      "populations": [
        {"shape": "fibre", "axis": "x", "count": 15, "size": 1.5, "min_gap": 0.5,
         "region": {"min": [0, 0, 0], "max": [30, 30, 15]}},
        {"shape": "fibre", "axis": "y", "count": 15, "size": 1.5, "min_gap": 0.5,
         "region": {"min": [0, 0, 15], "max": [30, 30, 30]}}]})");
  const auto f = all_of<Cylinder>(r.scene);
  ASSERT_EQ(f.size(), 30u);
  for (std::size_t i = 0; i < f.size(); ++i) {
    const int axis = f[i].end[0] - f[i].start[0] > 0 ? 0 : 1;
    EXPECT_LT(f[i].start[axis], 0);  // extended beyond the domain for clean clipping
    EXPECT_GT(f[i].end[axis], 30);
    // Ply membership: the cross-section stays in its ply, a gap from the ply faces.
    if (axis == 0) EXPECT_LE(f[i].start[2] + 1.5, 15 - 0.5 + 1e-12);
    else EXPECT_GE(f[i].start[2] - 1.5, 15 + 0.5 - 1e-12);
    for (std::size_t j = i + 1; j < f.size(); ++j) {
      const int axis_j = f[j].end[0] - f[j].start[0] > 0 ? 0 : 1;
      if (axis != axis_j) continue;  // different plies: separated in z (checked above)
      const int other = 1 - axis;
      const double d = std::hypot(f[i].start[other] - f[j].start[other], f[i].start[2] - f[j].start[2]);
      EXPECT_GE(d, f[i].radius + f[j].radius + 0.5 * (1 - 1e-9));
    }
  }
}

TEST(PackFraction, CountAndFractionTogether) {
  const auto r = run(spec2d(R"({"shape": "ellipse", "count": 500, "volume_fraction": 0.3, "min_gap": 0.2,
      "size": {"law": "lognormal", "mean": 1.0, "std": 0.3}, "aspect": {"law": "uniform", "min": 1, "max": 2}})"));
  ASSERT_EQ(r.scene.inclusions.size(), 500u);
  double area = 0;
  for (const auto& e : all_of<Ellipse>(r.scene)) area += M_PI * e.semi_axes[0] * e.semi_axes[1];
  EXPECT_NEAR(area / 1e4, 0.3, 1e-9);
  EXPECT_NE(r.report.populations[0].size_scale, 1.0);
}

TEST(PackFraction, FractionOnlyWithinTolerance) {
  const auto r = run(spec2d(R"({"shape": "circle", "volume_fraction": 0.4, "tolerance": 0.004, "min_gap": 0.2,
      "size": {"law": "normal", "mean": 1.5, "std": 0.3, "min": 0.8}})"));
  double area = 0;
  for (const auto& c : all_of<Circle>(r.scene)) area += M_PI * c.radius * c.radius;
  EXPECT_NEAR(area / 1e4, 0.4, 0.004);
}

TEST(PackDeterminism, SameSeedSameBytesOtherSeedOtherScene) {
  const std::string pop = R"({"shape": "polygon", "count": 150, "min_gap": 0.3, "vertices": 7, "size": 2.0,
      "spatial": {"law": "clustered", "clusters": 3, "cluster_radius": 10, "in_clusters": 0.5}},
      {"shape": "nurbs", "phase": 3, "count": 60, "size": 1.5, "min_gap": 0.3})";
  const std::string top = R"("phases": [{"id": 1}, {"id": 2}, {"id": 3}], )";
  const auto a = run(spec2d(pop, "", top)), b = run(spec2d(pop, "", top));
  const std::string ja = io::scene_to_json(a.scene, ""), jb = io::scene_to_json(b.scene, "");
  EXPECT_EQ(ja, jb);
  std::string other = spec2d(pop, "", top);
  other.replace(other.find("\"seed\": 7"), 9, "\"seed\": 8");
  EXPECT_NE(io::scene_to_json(run(other).scene, ""), ja);
  EXPECT_EQ(a.scene.inclusions.size(), 210u);
}

TEST(PackPeriodic, ImagesAreCheckedAcrossFaces) {
  const auto r = run(spec2d(R"({"shape": "circle", "count": 500, "min_gap": 0.3, "size": 1.5})",
                            R"(, "periodic": true)"));
  ASSERT_TRUE(r.scene.any_periodic());
  const auto c = all_of<Circle>(r.scene);
  int crossing = 0, close_images = 0;
  for (const auto& x : c) crossing += x.center[0] < 1.5 || x.center[0] > 98.5 || x.center[1] < 1.5 || x.center[1] > 98.5;
  EXPECT_GT(crossing, 5);
  for (std::size_t i = 0; i < c.size(); ++i)
    for (std::size_t j = 0; j < c.size(); ++j)
      for (int sx = -1; sx <= 1; ++sx)
        for (int sy = -1; sy <= 1; ++sy) {
          if (i == j && sx == 0 && sy == 0) continue;
          if (j < i && sx == 0 && sy == 0) continue;
          const double d = std::hypot(c[i].center[0] - c[j].center[0] - 100 * sx, c[i].center[1] - c[j].center[1] - 100 * sy);
          ASSERT_GE(d, 3.0 + 0.3 * (1 - 1e-9)) << i << " " << j << " shift " << sx << "," << sy;
          close_images += (sx || sy) && d < 4.0;
        }
  EXPECT_GT(close_images, 0);  // some neighbours are only neighbours through a face
}

TEST(PackOverlap, PitsOverlapButNeverNearMiss) {
  const auto r = run(spec2d(R"({"shape": "circle", "count": 600, "overlap": true, "min_gap": 0.4,
      "size": {"law": "uniform", "min": 1.0, "max": 3.0}})"));
  const auto c = all_of<Circle>(r.scene);
  int overlapping = 0;
  for (std::size_t i = 0; i < c.size(); ++i)
    for (std::size_t j = i + 1; j < c.size(); ++j) {
      const double d = std::hypot(c[i].center[0] - c[j].center[0], c[i].center[1] - c[j].center[1]);
      const double rs = c[i].radius + c[j].radius;
      EXPECT_TRUE(d <= rs || d >= rs + 0.4 * (1 - 1e-9)) << i << " " << j;
      overlapping += d < rs;
    }
  EXPECT_GT(overlapping, 10);
  EXPECT_TRUE(r.report.populations[0].fraction_is_estimate);
  double sum = 0;
  for (const auto& x : c) sum += M_PI * x.radius * x.radius;
  EXPECT_LT(r.report.populations[0].achieved_fraction, sum / 1e4);  // a union is less than the sum
  EXPECT_GT(r.report.populations[0].achieved_fraction, 0.5 * sum / 1e4);
}

TEST(PackStl, GrainsFromFileRandomRotations) {
  const auto dir = std::filesystem::temp_directory_path() / "cisamr_test_pack_stl";
  std::filesystem::create_directories(dir);
  {
    std::ofstream f(dir / "tet.stl");
    f << "solid t\n";
    const double v[4][3] = {{0, 0, 0}, {1, 0, 0}, {0, 1, 0}, {0, 0, 1}};
    const int faces[4][3] = {{0, 2, 1}, {0, 1, 3}, {0, 3, 2}, {1, 2, 3}};
    for (auto& fc : faces) {
      f << "facet normal 0 0 0\nouter loop\n";
      for (int k : fc) f << "vertex " << v[k][0] << " " << v[k][1] << " " << v[k][2] << "\n";
      f << "endloop\nendfacet\n";
    }
    f << "endsolid t\n";
  }
  const std::string spec = R"({"format": "cisamr-pack/1", "dimension": 3, "seed": 1,
      "domain": {"min": [0, 0, 0], "max": [20, 20, 20]}, "mesh": {"h": 1},
      "populations": [{"shape": "stl", "file": "tet.stl", "count": 40, "size": {"law": "uniform", "min": 2, "max": 4},
                       "min_gap": 0.2}]})";
  const auto r = pack::pack(pack::parse_pack_spec(spec, (dir / "spec.json").string()));
  ASSERT_EQ(r.scene.inclusions.size(), 40u);
  const auto g = all_of<StlSurface>(r.scene);
  EXPECT_NE(g[0].rotation, g[1].rotation);
  EXPECT_NEAR(r.report.populations[0].achieved_fraction * 8000,
              [&] { double v = 0; for (const auto& x : g) v += std::pow(x.scale, 3) / 6; return v; }(), 1e-9);
}

TEST(PackErrors, ImpossibleFractionStopsWithBestReached) {
  try {
    run(spec2d(R"({"shape": "circle", "volume_fraction": 0.85, "size": 2.0, "min_gap": 0.2})", "",
               R"("max_trials": 500, "max_failures": 50, )"));
    FAIL() << "no error";
  } catch (const InputError& e) {
    EXPECT_EQ(e.field(), "populations[0].volume_fraction");
    EXPECT_NE(e.problem().find("best"), std::string::npos) << e.problem();
  }
}

TEST(PackErrors, BadFieldsAreNamed) {
  auto field_of = [](const std::string& json) -> std::string {
    try {
      run(json);
    } catch (const InputError& e) {
      return e.field();
    }
    return "<no error>";
  };
  EXPECT_EQ(field_of(spec2d(R"({"shape": "circle", "count": 3, "size": {"law": "gamma", "mean": 1}})")),
            "populations[0].size.law");
  EXPECT_EQ(field_of(spec2d(R"({"shape": "circle", "count": 3, "size": 1, "colour": "red"})")),
            "populations[0].colour");
  EXPECT_EQ(field_of(spec2d(R"({"shape": "sphere", "count": 3, "size": 1})")), "populations[0].shape");
  EXPECT_EQ(field_of(spec2d(R"({"shape": "circle", "size": 1})")), "populations[0].count");
  EXPECT_EQ(field_of(spec2d(R"({"shape": "circle", "count": 3, "size": -1})")), "populations[0].size");
  EXPECT_EQ(field_of(spec2d(R"({"shape": "circle", "count": 3, "size": 1, "volume_fraction": 1.5})")),
            "populations[0].volume_fraction");
  EXPECT_EQ(field_of(R"({"format": "cisamr-pack/1", "dimension": 2, "domain": {"min": [0, 0], "max": [10, 10]},
      "mesh": {"h": 3}, "populations": [{"shape": "circle", "count": 1, "size": 1}]})"), "mesh.h");
  EXPECT_EQ(field_of(spec2d(R"({"shape": "circle", "count": 3000, "size": 2.0})", "", R"("max_trials": 50, "max_failures": 5, )")),
            "populations[0].count");
}

// ---- input that must be refused, not followed (found by fuzzing) ----

namespace {

std::string problem_of(const std::string& json) {
  try {
    pack::parse_pack_spec(json, "test.json");
  } catch (const InputError& e) {
    return std::string(e.what());
  }
  return "no error";
}

}  // namespace

TEST(PackSpec, NumbersBeyondTheDoubleRangeAreInputErrors) {
  const std::string what = problem_of(spec2d(R"({"shape": "circle", "count": 3, "size": 1e400})"));
  EXPECT_NE(what.find("not valid JSON: number overflow"), std::string::npos) << what;
}

TEST(PackSpec, JsonErrorsDoNotEchoRawBytes) {
  const std::string what = problem_of(std::string(9000, '[') + "\x01\xff");
  EXPECT_EQ(what.find('\x01'), std::string::npos) << what;
  EXPECT_EQ(what.find('\xff'), std::string::npos) << what;
  EXPECT_LT(what.size(), 400u) << what;
}

TEST(PackSpec, TrialsAndCountsAreBounded) {
  EXPECT_NE(problem_of(spec2d(R"({"shape": "circle", "count": 3, "size": 1})", "", R"("max_trials": 1000000000000, )"))
                .find("max_trials: must be between 1 and"),
            std::string::npos);
  EXPECT_NE(problem_of(spec2d(R"({"shape": "circle", "count": 1000000000000, "size": 1})")).find("count: must be between 0 and"),
            std::string::npos);
}

TEST(PackSpec, CountsTheRegionOrTheMachineCannotHoldAreRefusedBeforeDrawing) {
  auto refusal = [](const pack::PackSpec& spec) -> std::string {
    try {
      pack::pack(spec);
    } catch (const InputError& e) {
      return e.what();
    }
    return "no error";
  };
  // 10^7 circles of radius 1 in a 100 x 100 square (allowed by the count bound of 10^8):
  // all 10^7 templates were drawn first (about 7 GB) before the first placement failed.
  const auto start = std::chrono::steady_clock::now();
  const std::string full =
      refusal(pack::parse_pack_spec(spec2d(R"({"shape": "circle", "count": 10000000, "size": 1})"), "test.json"));
  EXPECT_LT(std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count(), 5.0);
  EXPECT_NE(full.find("test.json: populations[0].count: cannot place 10000000 particles: the first "), std::string::npos)
      << full;
  EXPECT_NE(full.find("more than their region's 1e+04"), std::string::npos) << full;
  // Tiny particles that fit by measure, but not in memory: refused up front with an estimate.
  pack::PackSpec tiny = pack::parse_pack_spec(
      spec2d(R"({"shape": "circle", "count": 60000000, "size": 0.001}, {"shape": "circle", "count": 50000000, "size": 0.001})"),
      "test.json");
  tiny.max_particles = 100'000'000;
  const std::string memory = refusal(tiny);
  EXPECT_NE(memory.find("test.json: populations[1].count: the pack would hold about 1.1e+08 particles (about 1.1e+02 GB), "
                        "more than the limit of 1e+08"),
            std::string::npos)
      << memory;
}

TEST(PackSpec, TinyParticlesInAHugeDomainKeepTheSearchGridSmall) {
  // A 3D domain of side 1e5 with particles of radius 0.05 asked for a search grid of 1024³
  // cell lists (24 GB): bad_alloc at once. The grid is bounded; the packing still holds.
  const auto r = run(R"({"format": "cisamr-pack/1", "dimension": 3, "seed": 3,
      "domain": {"min": [0, 0, 0], "max": [1e5, 1e5, 1e5]}, "mesh": {"h": 1000},
      "populations": [{"shape": "sphere", "count": 5, "size": 0.05, "min_gap": 0.01}]})");
  EXPECT_EQ(r.scene.inclusions.size(), 5u);
}

TEST(PackSpec, NonRegularFilesAreRefusedWithoutOpening) {
  const auto dir = std::filesystem::temp_directory_path() / ("cisamr_pack_fifo_" + std::to_string(::getpid()));
  std::filesystem::create_directories(dir);
  const std::string fifo = (dir / "pipe").string();
  ASSERT_EQ(::mkfifo(fifo.c_str(), 0600), 0);
  // Opening a FIFO for reading blocks until a writer comes: these must fail at once.
  for (const std::string& file : {fifo, std::string("/dev/zero"), dir.string()}) {
    try {
      pack::read_pack_spec(file);
      ADD_FAILURE() << file;
    } catch (const InputError& e) {
      EXPECT_NE(std::string(e.what()).find("cannot read"), std::string::npos) << e.what();
    }
    const std::string spec = R"({"format": "cisamr-pack/1", "dimension": 3, "domain": {"min": [0, 0, 0], "max": [1, 1, 1]},
        "mesh": {"h": 0.5}, "populations": [{"shape": "stl", "count": 1, "size": 0.2, "file": ")" + file + R"("}]})";
    try {
      pack::parse_pack_spec(spec, "test.json");
      ADD_FAILURE() << file;
    } catch (const InputError& e) {
      EXPECT_EQ(e.field(), "populations[0].file") << e.what();
    }
  }
  std::filesystem::remove_all(dir);
}
