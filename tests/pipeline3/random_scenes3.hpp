#pragma once
// Seeded random 3D scenes for the property suite of the 3D mesher (test_properties3.cpp).
// The seed picks a scene kind (so every kind gets its share and the summary can say which
// kinds produce bad tets), then the shapes. Inclusions of different phases are kept apart
// through conservative capsules (segment + radius) unless a kind makes them tangent on
// purpose; same-phase inclusions may overlap.
#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <random>
#include <string>
#include <vector>

#include "geometry/scene.hpp"
#include "support/periodic_images.hpp"

namespace cisamr::testing {

// Closed STL surfaces in their file coordinates (data/shapes: cube [-0.5,0.5]³,
// octahedron |x|+|y|+|z| ≤ 1, torus R 1 r 0.4 about z), with their bounding radius.
struct StlShapes {
  std::vector<std::array<Vec3, 3>> cube, octahedron, torus;
};

enum class SceneKind {
  spheres,     // a few spheres, some overlapping within one phase
  ellipsoids,  // up to 5:1, random rotation
  fibres,      // cylinders, some through the box (clipped)
  stl,         // cube, octahedron, torus: scaled, rotated, translated
  voids,       // a void phase among mixed shapes
  clipped,     // inclusions crossing the domain boundary
  tangent,     // spheres of different phases touching at a point
  lattice,     // interfaces through lattice nodes: sphere, STL vertex, edge, face (dyadic h)
  overlapping, // overlapping same-phase unions of every analytic shape
  mixed,       // everything at once
};
inline constexpr int kSceneKinds = 10;

inline const char* kind_name(SceneKind k) {
  static const char* const names[] = {"spheres", "ellipsoids", "fibres",  "stl",         "voids",
                                      "clipped", "tangent",    "lattice", "overlapping", "mixed"};
  return names[static_cast<int>(k)];
}

class RandomScene3 {
 public:
  RandomScene3(std::uint64_t seed, const StlShapes& stl) : seed_(seed), rng_(seed * 0x9E3779B97F4A7C15ull + 1), stl_(stl) {}

  SceneKind kind() const { return static_cast<SceneKind>(seed_ % kSceneKinds); }

  // After make(): the smallest feature of the scene in cells of its inclusion's finest
  // level (sphere and cylinder radius, an ellipsoid's smallest curvature radius c²/a, the
  // STL cube's side, octahedron's edge or torus' tube radius), and whether every interface
  // is smooth (spheres and ellipsoids only, none clipped by the box or touching another
  // phase). Volume and centroid checks only make sense on resolved (and smooth) scenes.
  double min_feature_cells() const { return min_feature_cells_; }
  bool smooth() const { return smooth_; }

  geometry::SceneDesc make() {
    using namespace geometry;
    SceneDesc s;
    s.source = "random-scene-3d-" + std::to_string(seed_);
    s.dimension = 3;
    s.phases = {{1, "matrix", false}, {2, "particle", false}, {3, "fibre", false}};
    s.matrix_phase = 1;
    scene_ = &s;
    placed_.clear();
    smooth_ = true;
    const SceneKind k = kind();
    if (k == SceneKind::lattice) {
      make_lattice(s);
      scene_ = nullptr;
      measure_features(s);
      return s;
    }
    // Small boxes of 0.1-cubes: 6-10 cells per side, the origin anywhere.
    s.h = 0.1;
    for (int d = 0; d < 3; ++d) {
      s.domain_min[d] = std::round(uniform(-2, 2) * 10) / 10;
      s.domain_max[d] = s.domain_min[d] + 0.1 * std::floor(uniform(6, 10.999));
    }
    s.levels = uniform(0, 1) < 0.5 ? 0 : 1;
    if (k == SceneKind::voids || (k == SceneKind::mixed && uniform(0, 1) < 0.5)) s.phases.push_back({4, "pore", true});
    switch (k) {
      case SceneKind::spheres:
        for (int i = 0, n = int(uniform(1, 4.99)); i < n; ++i) add_sphere(random_phase(), uniform(0.12, 0.3));
        if (uniform(0, 1) < 0.5) add_overlapping_pair(0);
        break;
      case SceneKind::ellipsoids:
        for (int i = 0, n = int(uniform(1, 3.99)); i < n; ++i) add_ellipsoid(random_phase());
        break;
      case SceneKind::fibres:
        for (int i = 0, n = int(uniform(1, 3.99)); i < n; ++i) add_cylinder(random_phase(), uniform(0, 1) < 0.5);
        break;
      case SceneKind::stl:
        for (int i = 0, n = int(uniform(1, 3.99)); i < n; ++i) add_stl(random_phase());
        break;
      case SceneKind::voids:
        add_sphere(4, uniform(0.12, 0.25));
        add_any(4);
        for (int i = 0, n = int(uniform(1, 2.99)); i < n; ++i) add_any(random_phase());
        break;
      case SceneKind::clipped:
        for (int i = 0, n = int(uniform(1, 3.99)); i < n; ++i) add_clipped(random_phase());
        break;
      case SceneKind::tangent:
        s.levels = 0;  // R2 refines the whole contact region to Lmax: keep it small
        add_tangent_pair();
        if (uniform(0, 1) < 0.5) add_any(random_phase());
        break;
      case SceneKind::overlapping:
        for (int shape = 0, n = int(uniform(1, 2.99)); shape < n; ++shape) add_overlapping_pair(int(uniform(0, 2.99)));
        break;
      case SceneKind::mixed:
      default:
        for (int i = 0, n = int(uniform(2, 5.99)); i < n; ++i) add_any(random_phase());
        if (uniform(0, 1) < 0.4) add_tangent_pair();
        if (uniform(0, 1) < 0.4) add_clipped(random_phase());
        break;
    }
    scene_ = nullptr;
    measure_features(s);
    return s;
  }

 private:
  double min_feature_cells_ = 0;
  bool smooth_ = true;

  void measure_features(const geometry::SceneDesc& s) {
    min_feature_cells_ = 1e300;
    for (const auto& inc : s.inclusions) {
      double feature = 0;
      if (const auto* p = std::get_if<geometry::Sphere>(&inc.shape)) {
        feature = p->radius;
      } else if (const auto* e = std::get_if<geometry::Ellipsoid>(&inc.shape)) {
        const double a = std::max({e->semi_axes[0], e->semi_axes[1], e->semi_axes[2]});
        const double c = std::min({e->semi_axes[0], e->semi_axes[1], e->semi_axes[2]});
        feature = c * c / a;
      } else if (const auto* c = std::get_if<geometry::Cylinder>(&inc.shape)) {
        feature = c->radius, smooth_ = false;
      } else if (const auto* t = std::get_if<geometry::StlSurface>(&inc.shape)) {
        const double size = t->file == "cube.stl" ? 1.0 : t->file == "octahedron.stl" ? std::sqrt(2.0) : 0.4;
        feature = t->scale * size, smooth_ = false;
      }
      const double cell = s.h / double(1 << std::max(0, inc.levels));
      min_feature_cells_ = std::min(min_feature_cells_, feature / cell);
    }
    const Box3 box{{s.domain_min[0], s.domain_min[1], s.domain_min[2]}, {s.domain_max[0], s.domain_max[1], s.domain_max[2]}};
    for (const Capsule& c : placed_)  // inclusions reaching the box boundary are clipped: a crease
      for (int d = 0; d < 3; ++d)
        if (std::min(c.a[d], c.b[d]) - c.radius <= box.min[d] || std::max(c.a[d], c.b[d]) + c.radius >= box.max[d])
          smooth_ = false;
  }

  // A conservative hull of an inclusion: every point within `radius` of segment [a, b].
  struct Capsule {
    Vec3 a, b;
    double radius;
    int phase;
  };

  std::uint64_t seed_;
  std::mt19937_64 rng_;
  const StlShapes& stl_;
  geometry::SceneDesc* scene_ = nullptr;
  std::vector<Capsule> placed_;

  double uniform(double a, double b) { return std::uniform_real_distribution<double>(a, b)(rng_); }
  int random_phase() {
    std::vector<int> ids;
    for (const auto& p : scene_->phases)
      if (p.id != scene_->matrix_phase) ids.push_back(p.id);
    return ids[static_cast<std::size_t>(uniform(0, double(ids.size()) - 1e-9))];
  }
  int levels() { return uniform(0, 1) < 0.8 ? scene_->levels : int(uniform(0, 1.999)); }

  static Vec3 add(Vec3 a, Vec3 b, double t = 1) { return {a[0] + t * b[0], a[1] + t * b[1], a[2] + t * b[2]}; }
  static double dot(Vec3 a, Vec3 b) { return a[0] * b[0] + a[1] * b[1] + a[2] * b[2]; }
  static Vec3 sub(Vec3 a, Vec3 b) { return {a[0] - b[0], a[1] - b[1], a[2] - b[2]}; }

  // Distance between segments [p1,q1] and [p2,q2] (Ericson, Real-Time Collision Detection 5.1.9).
  static double segment_distance(Vec3 p1, Vec3 q1, Vec3 p2, Vec3 q2) {
    const Vec3 d1 = sub(q1, p1), d2 = sub(q2, p2), r = sub(p1, p2);
    const double a = dot(d1, d1), e = dot(d2, d2), f = dot(d2, r);
    double s = 0, t = 0;
    if (a <= 1e-300 && e <= 1e-300) {
      s = t = 0;
    } else if (a <= 1e-300) {
      t = std::clamp(f / e, 0.0, 1.0);
    } else {
      const double c = dot(d1, r);
      if (e <= 1e-300) {
        s = std::clamp(-c / a, 0.0, 1.0);
      } else {
        const double b = dot(d1, d2), denom = a * e - b * b;
        s = denom > 0 ? std::clamp((b * f - c * e) / denom, 0.0, 1.0) : 0.0;
        t = (b * s + f) / e;
        if (t < 0) t = 0, s = std::clamp(-c / a, 0.0, 1.0);
        else if (t > 1) t = 1, s = std::clamp((b - c) / a, 0.0, 1.0);
      }
    }
    const Vec3 x = add(p1, d1, s), y = add(p2, d2, t);
    const Vec3 w = sub(x, y);
    return std::sqrt(dot(w, w));
  }

  // Clear of every placed inclusion of another phase by a tenth of h.
  bool clear(const Capsule& c) const {
    for (const Capsule& o : placed_)
      if (o.phase != c.phase && segment_distance(c.a, c.b, o.a, o.b) < c.radius + o.radius + 0.1 * scene_->h) return false;
    return true;
  }

  static geometry::Rotation3 random_rotation(std::mt19937_64& rng) {
    std::normal_distribution<double> n(0, 1);
    double q[4], len = 0;
    for (double& x : q) x = n(rng), len += x * x;
    len = std::sqrt(len);
    for (double& x : q) x /= len;
    const double w = q[0], x = q[1], y = q[2], z = q[3];
    return geometry::quaternion_rotation(w, x, y, z);
  }

  // A point in the domain, at least `margin` inside it (negative: may stick out).
  Vec3 random_point(double margin) {
    Vec3 p;
    for (int d = 0; d < 3; ++d) {
      const double lo = scene_->domain_min[d] + margin, hi = scene_->domain_max[d] - margin;
      p[d] = lo < hi ? uniform(lo, hi) : 0.5 * (scene_->domain_min[d] + scene_->domain_max[d]);
    }
    return p;
  }

  void push(geometry::Shape shape, int phase, Capsule hull) {
    scene_->inclusions.push_back({std::move(shape), phase, levels()});
    hull.phase = phase;
    placed_.push_back(hull);
  }

  // Tries a few centres; `build(center)` returns the shape and its hull.
  template <class Build>
  bool place(int phase, double margin, Build build) {
    for (int attempt = 0; attempt < 60; ++attempt) {
      const Vec3 c = random_point(margin);
      auto [shape, hull] = build(c);
      hull.phase = phase;
      if (!clear(hull)) continue;
      push(std::move(shape), phase, hull);
      return true;
    }
    return false;
  }

  bool add_sphere(int phase, double r, double margin = -1) {
    return place(phase, margin >= 0 ? margin : r, [&](Vec3 c) {
      return std::pair<geometry::Shape, Capsule>{geometry::Sphere{c, r}, {c, c, r, phase}};
    });
  }

  bool add_ellipsoid(int phase, double margin = -1) {
    const double a = uniform(0.12, 0.3);
    std::array<double, 3> axes{a, a / uniform(1, 5), a / uniform(1, 5)};  // up to 5:1
    std::shuffle(axes.begin(), axes.end(), rng_);
    const geometry::Rotation3 rot = random_rotation(rng_);
    return place(phase, margin >= 0 ? margin : a, [&](Vec3 c) {
      // Capsule along the longest body axis (a column of rot), radius the middle axis.
      int longest = 0;
      for (int i = 1; i < 3; ++i)
        if (axes[i] > axes[longest]) longest = i;
      std::array<double, 3> sorted = axes;
      std::sort(sorted.begin(), sorted.end());
      const Vec3 u{rot[0][longest], rot[1][longest], rot[2][longest]};
      return std::pair<geometry::Shape, Capsule>{geometry::Ellipsoid{c, {axes[0], axes[1], axes[2]}, rot},
                                                 {add(c, u, -axes[longest]), add(c, u, axes[longest]), sorted[1], phase}};
    });
  }

  bool add_cylinder(int phase, bool through) {
    const double r = uniform(0.04, 0.1);
    return place(phase, through ? 0.0 : 0.2, [&](Vec3 c) {
      Vec3 u{uniform(-1, 1), uniform(-1, 1), uniform(-1, 1)};
      const double n = std::sqrt(dot(u, u)) + 1e-300;
      for (double& x : u) x /= n;
      const double half = through ? 1.5 : uniform(0.1, 0.3);  // through: longer than the box
      const Vec3 a = add(c, u, -half), b = add(c, u, half);
      return std::pair<geometry::Shape, Capsule>{geometry::Cylinder{a, b, r}, {a, b, r, phase}};
    });
  }

  bool add_stl(int phase, double margin = -1) {
    const int which = int(uniform(0, 2.999));
    const auto& tris = which == 0 ? stl_.cube : which == 1 ? stl_.octahedron : stl_.torus;
    const double bound = which == 0 ? std::sqrt(0.75) : which == 1 ? 1.0 : 1.4;  // bounding radius in the file
    const double size = uniform(0.15, 0.3);  // bounding radius in the scene
    const geometry::Rotation3 rot = random_rotation(rng_);
    return place(phase, margin >= 0 ? margin : size, [&](Vec3 c) {
      geometry::StlSurface s;
      s.file = which == 0 ? "cube.stl" : which == 1 ? "octahedron.stl" : "torus.stl";
      s.scale = size / bound;
      s.rotation = rot;
      s.translate = c;
      s.triangles = tris;
      return std::pair<geometry::Shape, Capsule>{s, {c, c, size, phase}};
    });
  }

  void add_any(int phase) {
    switch (int(uniform(0, 3.999))) {
      case 0: add_sphere(phase, uniform(0.1, 0.25)); break;
      case 1: add_ellipsoid(phase); break;
      case 2: add_cylinder(phase, uniform(0, 1) < 0.3); break;
      default: add_stl(phase); break;
    }
  }

  // Crossing a face of the box: the centre near a face, within the inclusion's size.
  void add_clipped(int phase) {
    switch (int(uniform(0, 3.999))) {
      case 0: add_sphere(phase, uniform(0.12, 0.3), 0.0); break;
      case 1: add_ellipsoid(phase, 0.0); break;
      case 2: add_cylinder(phase, true); break;
      default: add_stl(phase, 0.0); break;
    }
  }

  // Two spheres of different phases touching at one point (exactly, along an axis with
  // dyadic radii, or up to rounding along a random direction).
  void add_tangent_pair() {
    const double r1 = std::round(uniform(0.1, 0.2) * 64) / 64, r2 = std::round(uniform(0.1, 0.2) * 64) / 64;
    for (int attempt = 0; attempt < 60; ++attempt) {
      const Vec3 c1 = random_point(r1);
      Vec3 u{0, 0, 0};
      if (uniform(0, 1) < 0.5) {
        u[int(uniform(0, 2.999))] = uniform(0, 1) < 0.5 ? -1 : 1;
      } else {
        u = {uniform(-1, 1), uniform(-1, 1), uniform(-1, 1)};
        const double n = std::sqrt(dot(u, u)) + 1e-300;
        for (double& x : u) x /= n;
      }
      const Vec3 c2 = add(c1, u, r1 + r2);
      const Capsule h1{c1, c1, r1, 2}, h2{c2, c2, r2, 3};
      if (!clear(h1) || !clear(h2)) continue;
      smooth_ = false;  // the contact point
      scene_->inclusions.push_back({geometry::Sphere{c1, r1}, 2, 0});
      scene_->inclusions.push_back({geometry::Sphere{c2, r2}, 3, 0});
      placed_.push_back(h1);
      placed_.push_back(h2);
      return;
    }
  }

  // shape 0: spheres, 1: ellipsoids, 2: cylinders; the second overlaps the first.
  void add_overlapping_pair(int shape) {
    const int phase = random_phase();
    const std::size_t before = placed_.size();
    if (shape == 0) add_sphere(phase, uniform(0.12, 0.25));
    else if (shape == 1) add_ellipsoid(phase);
    else add_cylinder(phase, false);
    if (placed_.size() == before) return;
    const Capsule first = placed_.back();
    // The second: centred within the first's hull radius of the first's axis midpoint.
    const Vec3 mid{(first.a[0] + first.b[0]) / 2, (first.a[1] + first.b[1]) / 2, (first.a[2] + first.b[2]) / 2};
    for (int attempt = 0; attempt < 60; ++attempt) {
      Vec3 c = mid;
      for (double& x : c) x += uniform(-1, 1) * first.radius;
      geometry::Shape s;
      Capsule hull;
      if (shape == 0) {
        const double r = uniform(0.1, 0.22);
        s = geometry::Sphere{c, r}, hull = {c, c, r, phase};
      } else if (shape == 1) {
        const double a = uniform(0.1, 0.25);
        const geometry::Rotation3 rot = random_rotation(rng_);
        s = geometry::Ellipsoid{c, {a, a / uniform(1, 4), a / uniform(1, 4)}, rot};
        hull = {c, c, a, phase};
      } else {
        const Vec3 u{uniform(-1, 1), uniform(-1, 1), uniform(-1, 1)};
        const double r = uniform(0.04, 0.1), half = uniform(0.1, 0.3) / (std::sqrt(dot(u, u)) + 1e-300);
        s = geometry::Cylinder{add(c, u, -half), add(c, u, half), r};
        hull = {add(c, u, -half), add(c, u, half), r, phase};
      }
      if (!clear(hull)) continue;
      push(std::move(s), phase, hull);
      return;
    }
  }

  // Dyadic h (0.125) so that lattice coordinates are exact: a sphere through lattice nodes
  // (centred on a node with radius 2h, or a Pythagorean 3-4-5 radius), a cube whose faces
  // lie on lattice planes (vertices, edges and faces through nodes), an octahedron with
  // vertices on nodes and edges through nodes, or the same touching the domain boundary.
  void make_lattice(geometry::SceneDesc& s) {
    s.h = 0.125;
    s.domain_min = {0, 0, 0};
    s.domain_max = {1, 1, 1};
    s.levels = uniform(0, 1) < 0.5 ? 0 : 1;
    const int phase = random_phase();
    const Vec3 centre{0.5, 0.5, 0.5};
    geometry::StlSurface stl;
    stl.translate = centre;
    switch (int(uniform(0, 5.999))) {
      case 0: push(geometry::Sphere{centre, 0.25}, phase, {centre, centre, 0.25, phase}); break;
      case 1: push(geometry::Sphere{{0.375, 0.5, 0.5}, 0.3125}, phase, {centre, centre, 0.45, phase}); break;
      case 2:  // faces at 0.375 and 0.625
        stl.file = "cube.stl", stl.scale = 0.25, stl.triangles = stl_.cube;
        push(stl, phase, {centre, centre, 0.25, phase});
        break;
      case 3:  // vertices at 0.5 ± 0.25 on the axes
        stl.file = "octahedron.stl", stl.scale = 0.25, stl.triangles = stl_.octahedron;
        push(stl, phase, {centre, centre, 0.25, phase});
        break;
      case 4:  // a cube with a face on the domain face x = 0, and one on a lattice plane inside
        stl.file = "cube.stl", stl.scale = 0.375, stl.triangles = stl_.cube;
        stl.translate = {0.1875, 0.5, 0.5};
        push(stl, phase, {stl.translate, stl.translate, 0.33, phase});
        break;
      default:  // a sphere tangent to the domain face z = 1 at a lattice node
        push(geometry::Sphere{{0.5, 0.5, 0.75}, 0.25}, phase, {centre, centre, 0.3, phase});
        break;
    }
  }
};

// The random scene made periodic (by seed: every axis, x only, or x and y), its box cut
// to an even number of cells of at least 4 per periodic axis (the five-tetrahedron grid
// closes on a torus only so). Placed for a box, some inclusions overlap an image of one of
// another phase: those are dropped, one at a time, as the oracle names them (the error a
// user would get); `make_oracle` builds the oracle (the caller's, so this header needs no
// geometry library).
template <class MakeOracle>
geometry::SceneDesc periodic_scene3(std::uint64_t seed, const StlShapes& stl, MakeOracle&& make_oracle) {
  geometry::SceneDesc s = RandomScene3(seed, stl).make();
  switch (seed % 3) {
    case 1: s.periodic = {true, false, false}; break;
    case 2: s.periodic = {true, true, false}; break;
    default: s.periodic = {true, true, true};
  }
  for (int d = 0; d < 3; ++d) {
    if (!s.periodic[static_cast<std::size_t>(d)]) continue;
    long cells = std::lround((s.domain_max[d] - s.domain_min[d]) / s.h);
    cells = std::max(4L, cells - cells % 2);
    s.domain_max[d] = s.domain_min[d] + s.h * static_cast<double>(cells);
  }
  drop_refused_images(s, make_oracle, 20);
  return s;
}

}  // namespace cisamr::testing
