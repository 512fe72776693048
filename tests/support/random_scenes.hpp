#pragma once
// Seeded random 2D scenes for property tests: every shape, overlapping same-phase
// inclusions, voids, inclusions crossing the box, tangent inclusions of different phases,
// interfaces through lattice nodes, inclusions smaller than a cell.
#include <algorithm>
#include <cmath>
#include <random>
#include <string>
#include <vector>

#include "core/error.hpp"
#include "geometry/oracle.hpp"
#include "geometry/scene.hpp"
#include "support/periodic_images.hpp"

namespace cisamr::testing {

struct SceneFeatures {
  bool voids = true;
  bool tangent = true;
  bool lattice_aligned = true;
  bool tiny = true;
  bool nurbs = true;
};

class RandomScene2 {
 public:
  explicit RandomScene2(unsigned seed, SceneFeatures features = {}) : rng_(seed), features_(features) {}

  geometry::SceneDesc make() {
    using namespace geometry;
    SceneDesc s;
    s.source = "random-scene";
    s.dimension = 2;
    const double h = pick({1.0, 0.5, 0.25});
    const int nx = static_cast<int>(uniform(12, 24)), ny = static_cast<int>(uniform(12, 24));
    s.h = h;
    s.domain_min = {uniform(-3, 3), uniform(-3, 3), 0};
    // Keep the domain min on a multiple of h/4 so lattice-aligned shapes stay exact.
    s.domain_min[0] = std::round(s.domain_min[0] * 4) / 4;
    s.domain_min[1] = std::round(s.domain_min[1] * 4) / 4;
    s.domain_max = {s.domain_min[0] + nx * h, s.domain_min[1] + ny * h, 0};
    s.levels = static_cast<int>(uniform(0, 2.99));
    s.phases = {{1, "matrix", false}, {2, "particle", false}, {3, "fibre", false}};
    if (features_.voids && uniform(0, 1) < 0.4) s.phases.push_back({4, "pore", true});
    s.matrix_phase = 1;
    scene_ = &s;
    placed_.clear();
    const int count = static_cast<int>(uniform(3, 10));
    for (int i = 0; i < count; ++i) add_random_inclusion();
    if (features_.tangent && uniform(0, 1) < 0.3) add_tangent_pair();
    if (features_.lattice_aligned && uniform(0, 1) < 0.4) add_lattice_aligned();
    if (features_.tiny && uniform(0, 1) < 0.3) add_tiny();
    if (uniform(0, 1) < 0.4) add_overlapping_pair();
    scene_ = nullptr;
    return s;
  }

 private:
  struct Disk {
    double x, y, r;
    int phase;
  };
  std::mt19937_64 rng_;
  SceneFeatures features_;
  geometry::SceneDesc* scene_ = nullptr;
  std::vector<Disk> placed_;

  double uniform(double a, double b) { return std::uniform_real_distribution<double>(a, b)(rng_); }
  double pick(std::initializer_list<double> v) {
    const auto i = static_cast<std::size_t>(uniform(0, static_cast<double>(v.size()) - 1e-9));
    return *(v.begin() + static_cast<std::ptrdiff_t>(i));
  }
  int random_phase() {
    std::vector<int> ids;
    for (const auto& p : scene_->phases)
      if (p.id != scene_->matrix_phase) ids.push_back(p.id);
    return ids[static_cast<std::size_t>(uniform(0, static_cast<double>(ids.size()) - 1e-9))];
  }
  // A disk that keeps clear of every placed disk of another phase (same phase may overlap).
  bool find_spot(double r, int phase, double& x, double& y) {
    const auto& s = *scene_;
    for (int attempt = 0; attempt < 200; ++attempt) {
      x = uniform(s.domain_min[0] - 0.5 * r, s.domain_max[0] + 0.5 * r);
      y = uniform(s.domain_min[1] - 0.5 * r, s.domain_max[1] + 0.5 * r);
      bool ok = true;
      for (const Disk& d : placed_)
        if (std::hypot(x - d.x, y - d.y) < r + d.r + 0.1 * s.h && (d.phase != phase || uniform(0, 1) < 0.7)) ok = false;
      if (ok) return true;
    }
    return false;
  }
  void push(geometry::Shape shape, int phase, double x, double y, double r, int levels = -1) {
    geometry::Inclusion inc;
    inc.shape = std::move(shape);
    inc.phase = phase;
    inc.levels = levels >= 0 ? levels : (uniform(0, 1) < 0.7 ? scene_->levels : static_cast<int>(uniform(0, 3.99)));
    scene_->inclusions.push_back(std::move(inc));
    placed_.push_back({x, y, r, phase});
  }

  void add_random_inclusion() {
    using namespace geometry;
    const double h = scene_->h;
    const double r = uniform(1.2, 4.5) * h;
    const int phase = random_phase();
    double x, y;
    if (!find_spot(r, phase, x, y)) return;
    const int kind = static_cast<int>(uniform(0, features_.nurbs ? 5.99 : 3.99));
    switch (kind) {
      case 0:
      case 1:
        push(Circle{{x, y}, r}, phase, x, y, r);
        break;
      case 2: {
        const double b = r * uniform(0.2, 1.0);  // up to 5:1
        push(Ellipse{{x, y}, {r, b}, uniform(0, M_PI)}, phase, x, y, r);
        break;
      }
      case 3: {  // convex or star-shaped polygon
        Polygon p;
        const int n = static_cast<int>(uniform(3, 9.99));
        const bool star = uniform(0, 1) < 0.4 && n >= 5;
        const double t0 = uniform(0, 2 * M_PI);
        for (int k = 0; k < n; ++k) {
          const double rr = star && (k % 2) ? r * uniform(0.4, 0.7) : r * uniform(0.85, 1.0);
          const double t = t0 + 2 * M_PI * k / n;
          p.vertices.push_back({x + rr * std::cos(t), y + rr * std::sin(t)});
        }
        if (uniform(0, 1) < 0.5) std::reverse(p.vertices.begin(), p.vertices.end());
        push(p, phase, x, y, r);
        break;
      }
      case 4: {  // a circle written as a rational quadratic NURBS
        const double w = std::sqrt(0.5);
        NurbsCurve c;
        c.degree = 2;
        c.knots = {0, 0, 0, 0.25, 0.25, 0.5, 0.5, 0.75, 0.75, 1, 1, 1};
        c.control_points = {{x + r, y}, {x + r, y + r}, {x, y + r}, {x - r, y + r}, {x - r, y},
                            {x - r, y - r}, {x, y - r}, {x + r, y - r}, {x + r, y}};
        c.weights = {1, w, 1, w, 1, w, 1, w, 1};
        push(c, phase, x, y, r);
        break;
      }
      default: {  // a smooth closed cubic B-spline blob (clamped, first = last point)
        NurbsCurve c;
        c.degree = 3;
        const int n = 8;
        std::vector<Vec2> ring;
        for (int k = 0; k < n; ++k) {
          const double t = 2 * M_PI * k / n, rr = r * uniform(0.75, 1.0);
          ring.push_back({x + rr * std::cos(t), y + rr * std::sin(t)});
        }
        // Periodic cubic made closed and clamped: repeat the first 3 points, uniform knots.
        for (int k = 0; k < n + 3; ++k) c.control_points.push_back(ring[static_cast<std::size_t>(k % n)]);
        const int m = static_cast<int>(c.control_points.size());
        for (int k = 0; k < m + 4; ++k) c.knots.push_back(k);
        push(c, phase, x, y, r);
        break;
      }
    }
  }

  // Two circles of different phases touching at one point (exactly representable).
  void add_tangent_pair() {
    using namespace geometry;
    const double h = scene_->h;
    const double r1 = std::round(uniform(1.5, 3.5) * 4) / 4 * h, r2 = std::round(uniform(1.5, 3.5) * 4) / 4 * h;
    const double x = scene_->domain_min[0] + std::round(uniform(0.2, 0.5) * (scene_->domain_max[0] - scene_->domain_min[0]) / h) * h;
    const double y = scene_->domain_min[1] + std::round(uniform(0.3, 0.7) * (scene_->domain_max[1] - scene_->domain_min[1]) / h) * h + 0.37 * h;
    for (const Disk& d : placed_)
      if (std::hypot(x - d.x, y - d.y) < r1 + d.r + 2 * r2 + h) return;
    push(Circle{{x, y}, r1}, 2, x, y, r1);
    push(Circle{{x + r1 + r2, y}, r2}, 3, x + r1 + r2, y, r2);
  }

  // A circle through lattice nodes and a lattice-aligned rectangle (edges on grid lines).
  void add_lattice_aligned() {
    using namespace geometry;
    const double h = scene_->h;
    const auto& s = *scene_;
    const double cx = s.domain_min[0] + std::round(uniform(0.2, 0.8) * (s.domain_max[0] - s.domain_min[0]) / h) * h;
    const double cy = s.domain_min[1] + std::round(uniform(0.2, 0.8) * (s.domain_max[1] - s.domain_min[1]) / h) * h;
    const double r = (uniform(0, 1) < 0.5 ? 2 : 5) * h;  // 3-4-5 triangles put nodes exactly on r = 5h
    bool ok = true;
    for (const Disk& d : placed_)
      if (std::hypot(cx - d.x, cy - d.y) < r + d.r + h) ok = false;
    if (ok) {
      push(Circle{{cx, cy}, r}, 2, cx, cy, r);
      return;
    }
    const double x0 = s.domain_min[0] + std::round(uniform(0.1, 0.7) * (s.domain_max[0] - s.domain_min[0]) / h) * h;
    const double y0 = s.domain_min[1] + std::round(uniform(0.1, 0.7) * (s.domain_max[1] - s.domain_min[1]) / h) * h;
    const double w = 3 * h, hh = 2 * h;
    for (const Disk& d : placed_)
      if (std::hypot(x0 + w / 2 - d.x, y0 + hh / 2 - d.y) < 2.5 * h + d.r + h) return;
    push(Polygon{{{x0, y0}, {x0 + w, y0}, {x0 + w, y0 + hh}, {x0, y0 + hh}}}, 3, x0 + w / 2, y0 + hh / 2, 2.5 * h);
  }

  void add_tiny() {
    using namespace geometry;
    const double r = uniform(0.15, 0.45) * scene_->h;
    const int phase = random_phase();
    double x, y;
    if (find_spot(r, phase, x, y)) push(Circle{{x, y}, r}, phase, x, y, r);
  }

  void add_overlapping_pair() {
    using namespace geometry;
    const double h = scene_->h;
    const double r = uniform(1.5, 3.5) * h;
    int phase = random_phase();
    if (phase == 4 && uniform(0, 1) < 0.5) phase = 2;
    double x, y;
    const double t = uniform(0, 2 * M_PI), d = r * uniform(0.4, 1.4);
    if (!find_spot(d + r, phase, x, y)) return;
    push(Circle{{x, y}, r}, phase, x, y, d + r);
    push(Ellipse{{x + d * std::cos(t), y + d * std::sin(t)}, {r, 0.6 * r}, uniform(0, M_PI)}, phase, x, y, d + r);
  }
};

// The random scene made periodic along both axes, x only or y only (by seed). Placed for a
// box, some inclusions overlap an image of one of another phase: those are dropped, one at
// a time, as the oracle names them (the error is the one a user would get).
inline geometry::SceneDesc periodic_scene(unsigned seed) {
  geometry::SceneDesc s = RandomScene2(seed).make();
  switch (seed % 5) {
    case 3: s.periodic = {true, false, false}; break;
    case 4: s.periodic = {false, true, false}; break;
    default: s.periodic = {true, true, false};
  }
  drop_refused_images(s, [](const geometry::SceneDesc& scene) { geometry::Oracle2 probe(scene); }, 20);
  return s;
}

}  // namespace cisamr::testing
