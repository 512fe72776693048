// Property suite of the 3D mesher on NURBS surface inclusions (issue #14,
// docs/nurbs-step-design.md §6, "≥ 100 seeded free-form particles"): 120 seeded scenes in
// the unit cube (h 1/16 or 1/12, levels 0-1, one extra level for rule R2), 6 kinds × 20
// seeds (kind = seed mod 6), the particles from tests/support/random_nurbs3.hpp, randomly
// rotated:
//   sphere    one perturbed sphere (radial ±15 %, weights in [0.7, 1.4], poles and seam exact)
//   torus     one perturbed torus
//   blob      one six-patch cube-sphere blob
//   several   3-5 inclusions: NURBS particles of two or three kinds and analytic spheres, of
//             two phases, apart by at least half a cell
//   clipped   one or two particles whose centre lies near a face, an edge or a corner of the
//             box, so that the box cuts them
//   touching  a perturbed sphere or blob and an analytic sphere of another phase tangent to it
//             at an exact surface point that is a control point (a pole, a cube corner): every
//             other control point lies strictly on the particle's side of a plane through it,
//             the sphere on the other side; both at level 0 (rule R2 raises the contact)
// For every scene:
//   - the oracle accepts it and pipeline::mesh meshes it, no tet inverted;
//   - every tetrahedron's aspect ratio ≤ 5.0, none above (no exception);
//   - quality::check_conformity (shared facets, orientation, no duplicate or hanging node,
//     Σ |tet volume| = the box's);
//   - quality::check_fidelity against the oracle at max(1e-9·diagonal, the run's
//     max_collapse_deviation), no more nodes beyond 1e-9·diagonal than the guard collapsed,
//     the collapse deviation below a coarse cell diagonal (as test_properties3.cpp);
//   - every node whose cells hold two or more phases lies on the exact boundary of each
//     inclusion phase among them: its distance to the nearest boundary of an inclusion of
//     that phase (the NURBS body's surface::distance, the analytic sphere's | |x − c| − r |)
//     is ≤ 1e-9·diagonal, except at most as many nodes as the guard collapsed, which stay
//     within the collapse deviation; in touching scenes some node is shared by the
//     particle's and the sphere's tets (the contact is meshed);
//   - Σ of the meshed phase measures = the box volume (1e-9 relative);
//   - partition invariance: the mesh through parallel::mesh_distributed on SerialComm with
//     1 and 7 partitions has the sequential mesh's checksum, the same canonical tets and
//     node count, global node ids 0..n-1 once each;
//   - surface::stats(): no side() fallback (the long-ray path) and no repair over the whole
//     scene (oracle, sequential and partitioned runs, all on this thread).
// Volume errors against the exact measures (uncut scenes) are printed, not judged: features
// are 2-6 cells here. Prints a summary per shard and over every scene that ran (worst aspect
// ratio and its seed, collapses, two-phase nodes, volume errors, times by kind).
//
// One scene: CISAMR_SEED=N test_nurbs_properties3 --gtest_filter='*FromEnvironment'
// (CISAMR_VERBOSE=1 prints a line per scene; CISAMR_SCENE_DIR=dir writes each scene that
// runs as dir/nurbs_properties3_seed_N.json, for `cisamr mesh`).
#include <gtest/gtest.h>

#include <algorithm>
#include <array>
#include <chrono>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <limits>
#include <map>
#include <memory>
#include <random>
#include <set>
#include <string>
#include <variant>
#include <vector>

#include "core/comm.hpp"
#include "geometry/oracle.hpp"
#include "geometry/surface_body.hpp"
#include "io/scene_io.hpp"
#include "parallel/checksum.hpp"
#include "parallel/distributed.hpp"
#include "parallel/merge.hpp"
#include "pipeline/pipeline.hpp"
#include "quality/quality.hpp"
#include "support/random_nurbs3.hpp"

namespace cisamr {
namespace {

namespace nurbs3 = testing::nurbs3;
namespace surface = geometry::surface;

constexpr double kMaxAspect3 = 5.0;  // DESIGN.md §2.2
constexpr int kShards = 8;
constexpr int kScenesPerShard = 15;  // 120 scenes, 20 per kind
constexpr std::array<int, 2> kPartitions = {1, 7};

enum class SceneKind { sphere, torus, blob, several, clipped, touching };
constexpr int kSceneKinds = 6;
const char* kind_name(SceneKind k) {
  static const char* const names[] = {"sphere", "torus", "blob", "several", "clipped", "touching"};
  return names[static_cast<int>(k)];
}

// ------------------------------------------------------------------------ the scenes

Vec3 add(const Vec3& a, const Vec3& b, double t = 1) { return {a[0] + t * b[0], a[1] + t * b[1], a[2] + t * b[2]}; }
Vec3 sub(const Vec3& a, const Vec3& b) { return {a[0] - b[0], a[1] - b[1], a[2] - b[2]}; }
double dot(const Vec3& a, const Vec3& b) { return a[0] * b[0] + a[1] * b[1] + a[2] * b[2]; }
double norm(const Vec3& a) { return std::sqrt(dot(a, a)); }

struct NurbsScene {
  geometry::SceneDesc scene;
  pipeline::Options options;
  std::vector<std::string> labels;  // per inclusion: "perturbed_sphere r 0.21", "sphere r 0.1", ...
  bool contact = false;             // touching: the particle and the sphere meet at `contact_point`
  Vec3 contact_point{};
  bool clipped = false;  // an inclusion's surface (its body cells' boxes) reaches the domain boundary
};

// Seeded scenes; random numbers from the bits of mt19937_64 (as random_nurbs3.hpp), so a
// seed gives the same scene with every standard library.
class NurbsSceneGenerator {
 public:
  explicit NurbsSceneGenerator(std::uint64_t seed) : seed_(seed), rng_(seed * 0x9E3779B97F4A7C15ull + 0x5EED) {}

  SceneKind kind() const { return static_cast<SceneKind>(seed_ % kSceneKinds); }

  NurbsScene make() {
    NurbsScene out;
    geometry::SceneDesc& s = out.scene;
    s.source = "nurbs-properties3-" + std::to_string(seed_);
    s.dimension = 3;
    s.domain_min = {0, 0, 0};
    s.domain_max = {1, 1, 1};
    s.h = uniform(0, 1) < 0.5 ? 0.0625 : 1.0 / 12;
    s.levels = 0;
    s.phases = {{1, "matrix", false}, {2, "particle", false}, {3, "other", false}};
    s.matrix_phase = 1;
    // Lmax = the largest level + 1: rule R2 raises both sides of a contact (touching, and
    // inclusions of "several" closer than 1.8 cells) to Lmax, which at the default 3 extra
    // levels meshes a touching scene in millions of tets.
    out.options.extra_levels = 1;
    out_ = &out;
    placed_.clear();
    switch (kind()) {
      case SceneKind::sphere: add_inside(nurbs3::Kind::perturbed_sphere, uniform(0.2, 0.3), 2, level()); break;
      case SceneKind::torus: add_inside(nurbs3::Kind::perturbed_torus, uniform(0.28, 0.4), 2, 1); break;
      case SceneKind::blob: add_inside(nurbs3::Kind::cube_sphere, uniform(0.2, 0.3), 2, level()); break;
      case SceneKind::several: make_several(); break;
      case SceneKind::clipped: make_clipped(); break;
      case SceneKind::touching: make_touching(); break;
    }
    for (const auto& inc : s.inclusions) {
      const Box3 b = body_box(inc.shape);
      for (int d = 0; d < 3; ++d) out.clipped = out.clipped || b.min[d] <= s.domain_min[d] || b.max[d] >= s.domain_max[d];
    }
    out_ = nullptr;
    return out;
  }

 private:
  struct Placed {
    Vec3 centre;
    double radius;  // holds the inclusion's surface
  };
  std::uint64_t seed_;
  std::mt19937_64 rng_;
  NurbsScene* out_ = nullptr;
  std::vector<Placed> placed_;

  double uniform(double lo, double hi) { return lo + (hi - lo) * (static_cast<double>(rng_() >> 11) * 0x1.0p-53); }
  int level() { return uniform(0, 1) < 0.5 ? 0 : 1; }
  int other_phase() { return uniform(0, 1) < 0.5 ? 2 : 3; }
  nurbs3::Kind any_kind() { return nurbs3::kKinds[static_cast<std::size_t>(uniform(0, 2.999999))]; }

  geometry::Rotation3 random_rotation() {
    for (;;) {
      double q[4], n2 = 0;
      for (double& x : q) x = uniform(-1, 1), n2 += x * x;
      if (n2 > 1 || n2 < 0.01) continue;
      const double n = std::sqrt(n2);
      return geometry::quaternion_rotation(q[0] / n, q[1] / n, q[2] / n, q[3] / n);
    }
  }

  // The particle at the origin, rotated; the caller sets translate.
  geometry::NurbsSurface particle(nurbs3::Kind k, double radius) {
    geometry::NurbsSurface p = nurbs3::random_particle(rng_, k, {0, 0, 0}, radius);
    p.rotation = random_rotation();
    return p;
  }

  // The union of the body cells' boxes (each holds its piece of the exact surface; the
  // body's own box is its pieces' control boxes, looser).
  static Box3 body_box(const geometry::Shape& shape) {
    if (const auto* sp = std::get_if<geometry::Sphere>(&shape))
      return {{sp->center[0] - sp->radius, sp->center[1] - sp->radius, sp->center[2] - sp->radius},
              {sp->center[0] + sp->radius, sp->center[1] + sp->radius, sp->center[2] + sp->radius}};
    const auto body = surface::cached_body(std::get<geometry::NurbsSurface>(shape));
    if (!body) return {};
    Box3 b = body->cells.front().box;
    for (const surface::Cell& c : body->cells)
      for (int d = 0; d < 3; ++d) b.min[d] = std::min(b.min[d], c.box.min[d]), b.max[d] = std::max(b.max[d], c.box.max[d]);
    return b;
  }

  // A radius about the particle's translate holding its surface: the farthest corner of
  // its cells' boxes.
  static double holding_radius(const geometry::NurbsSurface& p) {
    std::string problem;
    const auto body = surface::cached_body(p, &problem);
    if (!body) return std::numeric_limits<double>::infinity();
    double r = 0;
    for (const surface::Cell& c : body->cells)
      for (int k = 0; k < 8; ++k) {
        const Vec3 corner{(k & 1 ? c.box.max : c.box.min)[0], (k & 2 ? c.box.max : c.box.min)[1],
                          (k & 4 ? c.box.max : c.box.min)[2]};
        r = std::max(r, norm(sub(corner, p.translate)));
      }
    return r;
  }

  bool clear(const Vec3& c, double r, double gap) const {
    for (const Placed& p : placed_)
      if (norm(sub(c, p.centre)) < r + p.radius + gap) return false;
    return true;
  }

  void push(geometry::Shape shape, int phase, int levels, const std::string& label, const Vec3& c, double r) {
    out_->scene.inclusions.push_back({std::move(shape), phase, levels});
    out_->labels.push_back(label);
    placed_.push_back({c, r});
  }

  static std::string label(nurbs3::Kind k, double radius) {
    char buf[64];
    std::snprintf(buf, sizeof buf, "%s r %.3g", nurbs3::kind_name(k), radius);
    return buf;
  }

  // One particle inside the box, a cell clear of its faces.
  void add_inside(nurbs3::Kind k, double radius, int phase, int levels) {
    geometry::NurbsSurface p = particle(k, radius);
    const double bound = holding_radius(p);
    const double slack = std::max(0.0, 0.5 - bound - out_->scene.h);
    for (int d = 0; d < 3; ++d) p.translate[d] = 0.5 + uniform(-1, 1) * slack;
    const Vec3 c = p.translate;
    push(std::move(p), phase, levels, label(k, radius), c, bound);
  }

  // Two NURBS particles of two different kinds (phase 2 and either), an analytic sphere
  // (phase 3), and up to two more of either, of either phase, all apart by half a cell or
  // more.
  void make_several() {
    const int n = 3 + static_cast<int>(uniform(0, 2.999999));
    const double gap = 0.5 * out_->scene.h;
    int first_kind = 0;
    for (int i = 0; i < n; ++i) {
      const bool sphere = i == 2 || (i > 2 && uniform(0, 1) < 0.5);
      const int phase = i == 0 ? 2 : i == 2 ? 3 : other_phase(), levels = level();
      if (sphere) {
        const double r = uniform(0.08, 0.15);
        for (int attempt = 0; attempt < 200; ++attempt) {
          Vec3 c;
          for (int d = 0; d < 3; ++d) c[d] = uniform(r + gap, 1 - r - gap);
          if (!clear(c, r, gap)) continue;
          char buf[32];
          std::snprintf(buf, sizeof buf, "sphere r %.3g", r);
          push(geometry::Sphere{c, r}, phase, levels, buf, c, r);
          break;
        }
        continue;
      }
      int kind_index = static_cast<int>(uniform(0, 2.999999));
      if (i == 0) first_kind = kind_index;
      if (i == 1) kind_index = (first_kind + 1 + static_cast<int>(uniform(0, 1.999999))) % 3;
      const nurbs3::Kind k = nurbs3::kKinds[static_cast<std::size_t>(kind_index)];
      double radius = k == nurbs3::Kind::perturbed_torus ? uniform(0.16, 0.24) : uniform(0.1, 0.17);
      bool done = false;
      for (int size = 0; size < 4 && !done; ++size, radius *= 0.8) {  // smaller when it does not fit
        geometry::NurbsSurface p = particle(k, radius);
        const double bound = holding_radius(p);
        for (int attempt = 0; attempt < 200 && !done; ++attempt) {
          Vec3 c;
          for (int d = 0; d < 3; ++d) c[d] = uniform(bound + gap, 1 - bound - gap);
          if (!clear(c, bound, gap)) continue;
          p.translate = c;
          push(std::move(p), phase, k == nurbs3::Kind::perturbed_torus ? 1 : levels, label(k, radius), c, bound);
          done = true;
        }
      }
    }
  }

  // One or two particles whose centres lie near a face, an edge or a corner of the box
  // (within half a radius of it, either side), so that the box cuts them.
  void make_clipped() {
    const int n = uniform(0, 1) < 0.5 ? 1 : 2;
    const double gap = 0.5 * out_->scene.h;
    for (int i = 0; i < n; ++i) {
      const nurbs3::Kind k = any_kind();
      const bool torus = k == nurbs3::Kind::perturbed_torus;
      const double radius = torus ? uniform(0.3, 0.4) : uniform(0.2, 0.3);
      geometry::NurbsSurface p = particle(k, radius);
      const double bound = holding_radius(p);
      const int axes = 1 + static_cast<int>(uniform(0, 2.999999));  // face, edge, corner
      for (int attempt = 0; attempt < 200; ++attempt) {
        std::array<int, 3> order{0, 1, 2};
        for (int a = 2; a > 0; --a) std::swap(order[static_cast<std::size_t>(a)], order[static_cast<std::size_t>(uniform(0, a + 0.999999))]);
        Vec3 c;
        for (int a = 0; a < 3; ++a) {
          const int d = order[static_cast<std::size_t>(a)];
          if (a < axes) {
            const double offset = uniform(-0.4, 0.5) * radius * (torus ? 0.6 : 1.0);  // > 0: inside
            c[d] = uniform(0, 1) < 0.5 ? offset : 1 - offset;
          } else {
            c[d] = uniform(0.3, 0.7);
          }
        }
        if (!clear(c, bound, gap)) continue;
        p.translate = c;
        const Box3 b = body_box(p);
        bool crosses = false;
        for (int d = 0; d < 3; ++d) crosses = crosses || b.min[d] < 0 || b.max[d] > 1;
        if (!crosses) continue;
        push(std::move(p), i == 0 ? 2 : 3, torus ? 1 : level(), label(k, radius), c, bound);
        break;
      }
    }
  }

  // The interpolated control points of the particle (patch corners: clamped knots), and
  // every control point, placed.
  static void placed_points(const geometry::NurbsSurface& p, std::vector<Vec3>& corners, std::vector<Vec3>& all) {
    corners.clear(), all.clear();
    for (const geometry::NurbsPatch& patch : p.patches) {
      const std::size_t nu = patch.knots_u.size() - static_cast<std::size_t>(patch.degree[0]) - 1;
      const std::size_t nv = patch.knots_v.size() - static_cast<std::size_t>(patch.degree[1]) - 1;
      for (const std::size_t k : {std::size_t{0}, nu - 1, (nv - 1) * nu, nv * nu - 1})
        corners.push_back(surface::place(p, patch.control_points[k]));
      for (const Vec3& x : patch.control_points) all.push_back(surface::place(p, x));
    }
  }

  // A unit n with n·(P − X) < 0 for every control point P ≠ X, by a subgradient descent
  // on the largest cosine; its largest cosine in `margin` (< 0 when found).
  static Vec3 separating_direction(const Vec3& x, const std::vector<Vec3>& all, double& margin) {
    std::vector<Vec3> u;
    for (const Vec3& p : all) {
      const Vec3 d = sub(p, x);
      const double l = norm(d);
      if (l > 0) u.push_back({d[0] / l, d[1] / l, d[2] / l});
    }
    Vec3 n{0, 0, 0};
    for (const Vec3& v : u) n = add(n, v, -1);
    auto unit = [](Vec3 v) {
      const double l = norm(v);
      return l > 0 ? Vec3{v[0] / l, v[1] / l, v[2] / l} : Vec3{1, 0, 0};
    };
    n = unit(n);
    auto worst = [&](const Vec3& m, std::size_t& at) {
      double w = -2;
      for (std::size_t i = 0; i < u.size(); ++i)
        if (dot(m, u[i]) > w) w = dot(m, u[i]), at = i;
      return w;
    };
    std::size_t at = 0;
    Vec3 best = n;
    double best_margin = worst(n, at);
    for (int it = 0; it < 400; ++it) {
      const double w = worst(n, at);
      if (w < best_margin) best_margin = w, best = n;
      n = unit(add(n, u[at], -0.05 * (1 - it / 400.0)));
    }
    margin = best_margin;
    return best;
  }

  // A perturbed sphere or a blob, and an analytic sphere of the other phase touching it at
  // a pole or a cube corner (an exact surface point, a control point): every other
  // control point is strictly on one side of a plane through it (cosine below −0.05), the
  // sphere, centred along the plane's normal, on the other.
  void make_touching() {
    const double gap = out_->scene.h;
    // Most perturbed spheres' poles are saddles or cones no plane separates: new particles
    // of the kind drawn, then blobs.
    const bool sphere = uniform(0, 1) < 0.5;
    for (int attempt = 0; attempt < 200; ++attempt) {
      const nurbs3::Kind k = sphere && attempt < 150 ? nurbs3::Kind::perturbed_sphere : nurbs3::Kind::cube_sphere;
      const double radius = uniform(0.18, 0.26), rho = uniform(0.1, 0.18);
      geometry::NurbsSurface p = particle(k, radius);
      const double bound = holding_radius(p);
      const double slack = std::max(0.0, 0.5 - bound - gap);
      for (int d = 0; d < 3; ++d) p.translate[d] = 0.5 + uniform(-1, 1) * 0.5 * slack;
      std::vector<Vec3> corners, all;
      placed_points(p, corners, all);
      for (std::size_t i = corners.size(); i > 1; --i)  // Fisher-Yates on our own bits
        std::swap(corners[i - 1], corners[static_cast<std::size_t>(uniform(0, static_cast<double>(i) - 1e-9))]);
      for (const Vec3& x : corners) {
        double margin = 0;
        const Vec3 n = separating_direction(x, all, margin);
        if (margin > -0.05) continue;
        const Vec3 c = add(x, n, rho);
        bool inside = true;
        for (int d = 0; d < 3; ++d) inside = inside && c[d] - rho > gap && c[d] + rho < 1 - gap;
        if (!inside) continue;
        const Vec3 pc = p.translate;
        out_->contact = true;
        out_->contact_point = x;
        push(std::move(p), 2, 0, label(k, radius), pc, bound);  // level 0: the contact raises both to Lmax
        char buf[64];
        std::snprintf(buf, sizeof buf, "sphere r %.3g tangent (cos %.2f)", rho, margin);
        out_->labels.push_back(buf);
        out_->scene.inclusions.push_back({geometry::Sphere{c, rho}, 3, 0});
        return;
      }
    }
  }
};

// ------------------------------------------------------------------------ the checks

std::string describe(const NurbsScene& ns) {
  const geometry::SceneDesc& s = ns.scene;
  char buf[200];
  std::snprintf(buf, sizeof buf, "unit box, h %g, extra levels %d:", s.h, ns.options.extra_levels);
  std::string d = buf;
  for (std::size_t i = 0; i < s.inclusions.size(); ++i) {
    const auto& inc = s.inclusions[i];
    Vec3 c{};
    if (const auto* p = std::get_if<geometry::Sphere>(&inc.shape)) c = p->center;
    if (const auto* p = std::get_if<geometry::NurbsSurface>(&inc.shape)) c = p->translate;
    std::snprintf(buf, sizeof buf, " %s at (%.4g, %.4g, %.4g) phase %d L%d;", ns.labels[i].c_str(), c[0], c[1], c[2],
                  inc.phase, inc.levels);
    d += buf;
  }
  return d;
}

std::string fidelity_text(const quality::FidelityReport& f) {
  std::string text = std::to_string(f.nodes_off_phase) + " nodes off phase, " +
                     std::to_string(f.interface_nodes_off_interface) + " interface nodes off, " +
                     std::to_string(f.cells_off_phase) + " centroids off (max ratio " +
                     std::to_string(f.max_centroid_ratio) + "), max deviation " + std::to_string(f.max_deviation);
  for (const auto& e : f.examples) text += "\n  " + e;
  return text;
}

// Distance from x to the nearest boundary of an inclusion of phase id `phase`: the NURBS
// body's exact surface, the analytic sphere.
double boundary_distance(const geometry::SceneDesc& s, int phase, const Vec3& x) {
  double best = std::numeric_limits<double>::infinity();
  for (const auto& inc : s.inclusions) {
    if (inc.phase != phase) continue;
    if (const auto* p = std::get_if<geometry::Sphere>(&inc.shape)) {
      best = std::min(best, std::abs(norm(sub(x, p->center)) - p->radius));
    } else if (const auto* p = std::get_if<geometry::NurbsSurface>(&inc.shape)) {
      const auto body = surface::cached_body(*p);
      if (body) best = std::min(best, surface::distance(*body, x));
    }
  }
  return best;
}

// The exact phase measures of a scene whose inclusions all lie inside the box (NURBS
// bodies by surface::volume, spheres by the closed form, the matrix the rest); empty when
// the box cuts one. (Oracle3::phase_measures integrates along lines through crossings as
// soon as an inclusion's box, for a NURBS body the control boxes of its pieces, is not
// inside the domain: minutes for one particle.)
std::vector<double> exact_measures(const NurbsScene& ns) {
  const geometry::SceneDesc& s = ns.scene;
  if (ns.clipped) return {};
  std::vector<double> v(s.phases.size(), 0.0);
  double inclusions = 0;
  for (const auto& inc : s.inclusions) {
    double measure = 0;
    if (const auto* p = std::get_if<geometry::Sphere>(&inc.shape))
      measure = 4.0 / 3.0 * M_PI * p->radius * p->radius * p->radius;
    else if (const auto body = surface::cached_body(std::get<geometry::NurbsSurface>(inc.shape)))
      measure = surface::volume(*body);
    for (std::size_t k = 0; k < s.phases.size(); ++k)
      if (s.phases[k].id == inc.phase) v[k] += measure;
    inclusions += measure;
  }
  for (std::size_t k = 0; k < s.phases.size(); ++k)
    if (s.phases[k].id == s.matrix_phase) v[k] = 1.0 - inclusions;  // the unit box
  return v;
}

struct KindSummary {
  int scenes = 0;
  std::size_t tets = 0, above_5 = 0, interface_nodes = 0;
  double worst = 0;
  std::uint64_t worst_seed = 0;
  std::int64_t collapsed = 0;
  double max_collapse_cells = 0, max_interface_distance = 0, worst_volume_error = 0, seconds = 0;
  void add(const KindSummary& k) {
    scenes += k.scenes, tets += k.tets, above_5 += k.above_5, interface_nodes += k.interface_nodes;
    if (k.worst > worst) worst = k.worst, worst_seed = k.worst_seed;
    collapsed += k.collapsed;
    max_collapse_cells = std::max(max_collapse_cells, k.max_collapse_cells);
    max_interface_distance = std::max(max_interface_distance, k.max_interface_distance);
    worst_volume_error = std::max(worst_volume_error, k.worst_volume_error);
    seconds += k.seconds;
  }
};

struct Summary {
  std::map<std::string, KindSummary> kinds;
  double seconds = 0;
  void print(const char* title) const {
    KindSummary all;
    for (const auto& [name, k] : kinds) all.add(k);
    std::printf("[nurbs3] %s: %d scenes, %zu tets in %.1f s; worst aspect %.3f (seed %llu), %zu above 5; %lld collapsed "
                "nodes (max %.3f cells); %zu two-phase nodes, farthest from its surface %.2e (uncollapsed); worst "
                "particle volume error %.2e\n",
                title, all.scenes, all.tets, seconds, all.worst, static_cast<unsigned long long>(all.worst_seed),
                all.above_5, static_cast<long long>(all.collapsed), all.max_collapse_cells, all.interface_nodes,
                all.max_interface_distance, all.worst_volume_error);
    for (const auto& [name, k] : kinds)
      std::printf("[nurbs3]   %-9s %3d scenes %8zu tets in %6.1f s: worst %6.3f (seed %4llu), above 5: %zu; collapsed "
                  "%4lld (max %.3f cells); interface nodes %7zu (max %.2e); volume error %.2e\n",
                  name.c_str(), k.scenes, k.tets, k.seconds, k.worst, static_cast<unsigned long long>(k.worst_seed),
                  k.above_5, static_cast<long long>(k.collapsed), k.max_collapse_cells, k.interface_nodes,
                  k.max_interface_distance, k.worst_volume_error);
  }
  void add(const Summary& o) {
    for (const auto& [name, k] : o.kinds) kinds[name].add(k);
    seconds += o.seconds;
  }
};

Summary& total() {
  static Summary s;
  return s;
}

class PrintTotal : public ::testing::Environment {
 public:
  void TearDown() override {
    if (!total().kinds.empty()) total().print("all scenes");
  }
};
const auto* const print_total = ::testing::AddGlobalTestEnvironment(new PrintTotal);

double ms(std::chrono::steady_clock::duration d) { return std::chrono::duration<double, std::milli>(d).count(); }

// Meshes one scene, checks every property (gtest failures name the seed), adds to `sum`.
void check_scene(std::uint64_t seed, Summary& sum) {
  using Clock = std::chrono::steady_clock;
  const auto t0 = Clock::now();
  NurbsSceneGenerator gen(seed);
  const NurbsScene ns = gen.make();
  const geometry::SceneDesc& scene = ns.scene;
  const std::string kind = kind_name(gen.kind());
  SCOPED_TRACE("seed " + std::to_string(seed) + " (" + kind + "): " + describe(ns));
  if (const char* dir = std::getenv("CISAMR_SCENE_DIR"))
    io::write_scene(std::string(dir) + "/nurbs_properties3_seed_" + std::to_string(seed) + ".json", scene);
  const bool verbose = std::getenv("CISAMR_VERBOSE") != nullptr;
  ASSERT_FALSE(scene.inclusions.empty());
  if (gen.kind() == SceneKind::touching) {
    ASSERT_TRUE(ns.contact) << "no tangent sphere placed";
  }
  if (gen.kind() == SceneKind::clipped) {
    ASSERT_TRUE(ns.clipped) << "no particle crosses the box";
  }

  const surface::Stats before = surface::stats();
  std::unique_ptr<geometry::Oracle3> oracle;
  try {
    oracle = std::make_unique<geometry::Oracle3>(scene);
  } catch (const std::exception& e) {
    FAIL() << "the oracle rejects the scene: " << e.what();
  }
  pipeline::Result<3> r;
  try {
    r = pipeline::mesh(*oracle, ns.options);
  } catch (const std::exception& e) {
    FAIL() << "the mesher throws: " << e.what();
  }
  const auto t1 = Clock::now();
  const mesh::Mesh3& m = r.mesh;
  ASSERT_GT(m.cell_count(), 0u);
  EXPECT_EQ(r.counters.inverted, 0);

  // Conformity; no voids, so the tets fill the box.
  const Box3 domain{{scene.domain_min[0], scene.domain_min[1], scene.domain_min[2]},
                    {scene.domain_max[0], scene.domain_max[1], scene.domain_max[2]}};
  const double box_volume =
      (domain.max[0] - domain.min[0]) * (domain.max[1] - domain.min[1]) * (domain.max[2] - domain.min[2]);
  const auto conformity = quality::check_conformity(m, domain, box_volume, false, 1e-9);
  EXPECT_TRUE(conformity.ok) << "not conforming: open inside " << conformity.open_facets_inside << ", hanging "
                             << conformity.hanging_nodes << ", inverted " << conformity.inverted_cells
                             << ", degenerate " << conformity.degenerate_cells << ", non-manifold "
                             << conformity.non_manifold_facets << ", duplicates " << conformity.duplicate_nodes
                             << ", orientation " << conformity.mismatched_orientation_facets << ", measure error "
                             << conformity.measure_error
                             << (conformity.examples.empty() ? "" : "; " + conformity.examples[0]);

  // Aspect ratio: the bound, everywhere.
  const auto aspect = quality::aspect_statistics<3>(m, kMaxAspect3, 3);
  EXPECT_LE(aspect.max, kMaxAspect3) << "worst tet at (" << aspect.worst[0].centroid[0] << ", "
                                     << aspect.worst[0].centroid[1] << ", " << aspect.worst[0].centroid[2]
                                     << "), phase " << aspect.worst[0].phase;
  EXPECT_EQ(aspect.above_bound, 0u);

  // Phase fidelity against the oracle: strict (1e-9 of the diagonal) unless the guard
  // collapsed nodes; then within the reported deviation, for no more nodes than collapsed.
  const double tol = quality::default_fidelity_tolerance(scene);
  const double coarse_diagonal = scene.h * std::sqrt(3.0);
  EXPECT_LE(r.counters.max_collapse_deviation, coarse_diagonal) << "a collapse moved an interface by more than a cell";
  const double relaxed_tol = std::max(tol, r.counters.max_collapse_deviation * (1 + 1e-9));
  const std::size_t collapsed =
      static_cast<std::size_t>(r.counters.collapsed_nodes + r.counters.collapsed_cut_points);
  // Exact measures where the box cuts nothing; else the meshed ones (volume errors are
  // reported for uncut scenes only).
  std::vector<double> exact = exact_measures(ns);
  if (exact.empty()) {
    exact.assign(scene.phases.size(), 0.0);
    for (std::size_t c = 0; c < m.cell_count(); ++c) {
      const LocalId* v = m.cell(c);
      const Vec3 a = m.point(v[0]), e1 = sub(m.point(v[1]), a), e2 = sub(m.point(v[2]), a), e3 = sub(m.point(v[3]), a);
      const double volume = std::abs(e1[0] * (e2[1] * e3[2] - e2[2] * e3[1]) - e1[1] * (e2[0] * e3[2] - e2[2] * e3[0]) +
                                     e1[2] * (e2[0] * e3[1] - e2[1] * e3[0])) / 6;
      for (std::size_t k = 0; k < scene.phases.size(); ++k)
        if (scene.phases[k].id == m.cell_phase[c]) exact[k] += volume;
    }
  }
  const auto t2 = Clock::now();
  const auto fidelity = quality::check_fidelity(m, *oracle, relaxed_tol, exact, tol);
  EXPECT_LE(fidelity.nodes_beyond_strict, collapsed)
      << "more nodes off their phase than the guard collapsed: " << fidelity_text(fidelity);
  const std::size_t off =
      fidelity.nodes_off_phase + fidelity.interface_nodes_off_interface + fidelity.boundary_nodes_off_void;
  EXPECT_EQ(off, 0u) << "nodes off their phase beyond the collapse deviation: " << fidelity_text(fidelity);
  EXPECT_EQ(fidelity.cells_unknown_phase, 0u);
  EXPECT_EQ(fidelity.cells_wrong_phase, 0u) << "tets lying in another phase: " << fidelity_text(fidelity);

  // Two-phase nodes on the exact surfaces of their inclusion phases.
  std::vector<std::uint32_t> phases_of_node(m.node_count(), 0);  // bit k: phase id k
  for (std::size_t c = 0; c < m.cell_count(); ++c)
    for (int v = 0; v < 4; ++v) phases_of_node[static_cast<std::size_t>(m.cell(c)[v])] |= 1u << m.cell_phase[c];
  std::size_t interface_nodes = 0, beyond_strict = 0, beyond_relaxed = 0, contact_nodes = 0;
  double max_distance = 0, max_uncollapsed = 0;
  std::string example;
  for (std::size_t n = 0; n < m.node_count(); ++n) {
    const std::uint32_t mask = phases_of_node[n];
    if ((mask & (mask - 1)) == 0) continue;  // one phase
    ++interface_nodes;
    contact_nodes += (mask >> 2 & 1) && (mask >> 3 & 1) ? 1 : 0;  // phases 2 and 3 meet
    const Vec3 x = m.point(static_cast<LocalId>(n));
    double d = 0;
    for (int phase = 0; phase < 32; ++phase)
      if ((mask >> phase & 1) && phase != scene.matrix_phase) d = std::max(d, boundary_distance(scene, phase, x));
    max_distance = std::max(max_distance, d);
    if (d > tol) {
      ++beyond_strict;
      if (example.empty()) {
        char buf[160];
        std::snprintf(buf, sizeof buf, "node %zu at (%.17g, %.17g, %.17g), phases mask %#x, %.3e off", n, x[0], x[1],
                      x[2], mask, d);
        example = buf;
      }
    } else {
      max_uncollapsed = std::max(max_uncollapsed, d);
    }
    if (d > relaxed_tol) ++beyond_relaxed;
  }
  EXPECT_GT(interface_nodes, 0u);
  if (gen.kind() == SceneKind::touching) {
    EXPECT_GT(contact_nodes, 0u) << "the particle and the sphere do not meet in the mesh";
  }
  EXPECT_LE(beyond_strict, collapsed) << "two-phase nodes farther than " << tol << " from their surface: " << example
                                      << " (largest " << max_distance << ")";
  EXPECT_EQ(beyond_relaxed, 0u) << "two-phase nodes beyond the collapse deviation " << relaxed_tol << ": " << example;

  // Σ of the phase measures.
  double meshed = 0;
  for (std::size_t k = 0; k < scene.phases.size(); ++k) meshed += fidelity.phase_measure[k];
  EXPECT_NEAR(meshed, box_volume, 1e-9 * box_volume);
  double worst_volume_error = 0;
  if (!ns.clipped)
    for (std::size_t k = 0; k < scene.phases.size(); ++k)
      if (scene.phases[k].id != scene.matrix_phase && exact[k] > 0)
        worst_volume_error = std::max(worst_volume_error, fidelity.relative_error[k]);
  const auto t3 = Clock::now();

  // Partition invariance: the same set of tets through the distributed mesher.
  const std::uint64_t checksum = parallel::mesh_checksum3(m);
  const auto canonical = parallel::canonical_tets(m);
  const SerialComm comm;
  for (const int n : kPartitions) {
    SCOPED_TRACE(std::to_string(n) + " partitions");
    parallel::MeshOptions options;
    options.partitions = n;
    options.pipeline = ns.options;
    try {
      const parallel::DistributedMesh3 d = parallel::mesh_distributed<3>(comm, scene, options);
      EXPECT_EQ(d.partitions.size(), static_cast<std::size_t>(n));
      EXPECT_EQ(parallel::mesh_checksum3(comm, d.piece.mesh), checksum);
      const mesh::Mesh3 gathered = parallel::gather_mesh<3>(comm, d.piece);
      EXPECT_EQ(gathered.cell_count(), m.cell_count());
      EXPECT_EQ(gathered.node_count(), m.node_count());
      EXPECT_TRUE(parallel::canonical_tets(gathered) == canonical) << "the partitioned mesh has other tets";
      std::vector<int> seen(static_cast<std::size_t>(d.piece.global_nodes), 0);
      for (const GlobalId g : d.piece.mesh.node_global_id) ++seen[static_cast<std::size_t>(g)];
      EXPECT_TRUE(std::all_of(seen.begin(), seen.end(), [](int c) { return c == 1; })) << "global node ids not 0..n-1 once each";
    } catch (const std::exception& e) {
      ADD_FAILURE() << "the distributed mesher throws: " << e.what();
    }
  }
  const auto t4 = Clock::now();

  // Every side() answered by the tessellation or a short escape segment.
  const surface::Stats& after = surface::stats();
  EXPECT_EQ(after.side_fallback - before.side_fallback, 0) << "side() fell back to long rays";
  EXPECT_EQ(after.repairs - before.repairs, 0);

  KindSummary& k = sum.kinds[kind];
  ++k.scenes;
  k.tets += m.cell_count();
  k.above_5 += aspect.above_bound;
  if (aspect.max > k.worst) k.worst = aspect.max, k.worst_seed = seed;
  k.collapsed += static_cast<std::int64_t>(collapsed);
  k.max_collapse_cells = std::max(k.max_collapse_cells, r.counters.max_collapse_deviation / scene.h);
  k.interface_nodes += interface_nodes;
  k.max_interface_distance = std::max(k.max_interface_distance, max_uncollapsed);
  k.worst_volume_error = std::max(k.worst_volume_error, worst_volume_error);
  k.seconds += std::chrono::duration<double>(t4 - t0).count();
  if (verbose)
    std::printf("[nurbs3] seed %3llu %-8s %7zu tets, aspect %.3f, dihedral %.2f..%.2f, swaps %lld, collapsed %zu "
                "(%.3g), two-phase nodes %zu (max %.2e, %zu of phases 2 and 3), volume error %.2e, side calls %lld (in shell %lld); ms: scene+"
                "mesh %.0f measures %.0f checks %.0f partitions %.0f: %s\n",
                static_cast<unsigned long long>(seed), kind.c_str(), m.cell_count(), aspect.max, aspect.min_angle_deg,
                aspect.max_angle_deg, static_cast<long long>(r.counters.face_swaps), collapsed,
                r.counters.max_collapse_deviation, interface_nodes, max_distance, contact_nodes, worst_volume_error,
                static_cast<long long>(after.side_calls - before.side_calls),
                static_cast<long long>(after.side_in_shell - before.side_in_shell), ms(t1 - t0), ms(t2 - t1),
                ms(t3 - t2), ms(t4 - t3), describe(ns).c_str());
}

class NurbsProperties3 : public ::testing::TestWithParam<int> {};

TEST_P(NurbsProperties3, SeededParticles) {
  const int shard = GetParam();
  Summary sum;
  const auto start = std::chrono::steady_clock::now();
  for (int i = 0; i < kScenesPerShard; ++i)
    check_scene(static_cast<std::uint64_t>(shard * kScenesPerShard + i + 1), sum);
  sum.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  sum.print(("shard " + std::to_string(shard)).c_str());
  total().add(sum);
}

INSTANTIATE_TEST_SUITE_P(Shards, NurbsProperties3, ::testing::Range(0, kShards));

// One scene by seed (CISAMR_SEED), for debugging; skipped otherwise.
TEST(NurbsProperties3Seed, FromEnvironment) {
  const char* seed = std::getenv("CISAMR_SEED");
  if (!seed) GTEST_SKIP() << "set CISAMR_SEED to run one scene";
  Summary sum;
  check_scene(std::strtoull(seed, nullptr, 10), sum);
  sum.print("one scene");
}

// The generator is deterministic and gives every kind its 20 seeds, each scene what its
// kind is for: NURBS particles in every scene, analytic spheres among them (several),
// a body box across the domain boundary (clipped), a tangent sphere (touching).
TEST(NurbsProperties3Generator, EveryKindDeterministic) {
  std::map<std::string, int> kinds;
  const int scenes = kShards * kScenesPerShard;
  for (std::uint64_t seed = 1; seed <= std::uint64_t(scenes); ++seed) {
    SCOPED_TRACE("seed " + std::to_string(seed));
    NurbsSceneGenerator gen(seed);
    const NurbsScene s = gen.make();
    ++kinds[kind_name(gen.kind())];
    int nurbs = 0, spheres = 0;
    std::set<std::string> particle_kinds;
    std::set<int> phases;
    for (std::size_t i = 0; i < s.scene.inclusions.size(); ++i) {
      const auto& inc = s.scene.inclusions[i];
      nurbs += std::holds_alternative<geometry::NurbsSurface>(inc.shape) ? 1 : 0;
      spheres += std::holds_alternative<geometry::Sphere>(inc.shape) ? 1 : 0;
      if (std::holds_alternative<geometry::NurbsSurface>(inc.shape))
        particle_kinds.insert(s.labels[i].substr(0, s.labels[i].find(' ')));
      phases.insert(inc.phase);
    }
    EXPECT_GE(nurbs, 1);
    switch (gen.kind()) {
      case SceneKind::several:
        EXPECT_GE(particle_kinds.size(), 2u);
        EXPECT_GE(spheres, 1);
        EXPECT_GE(nurbs + spheres, 3);
        EXPECT_EQ(phases.size(), 2u);
        break;
      case SceneKind::clipped: EXPECT_TRUE(s.clipped); break;
      case SceneKind::touching:
        EXPECT_TRUE(s.contact);
        EXPECT_EQ(nurbs, 1);
        EXPECT_EQ(spheres, 1);
        EXPECT_EQ(phases.size(), 2u);
        break;
      default:
        EXPECT_EQ(s.scene.inclusions.size(), 1u);
        EXPECT_FALSE(s.clipped);
    }
    NurbsSceneGenerator again(seed);
    EXPECT_EQ(io::scene_to_json(again.make().scene, ""), io::scene_to_json(s.scene, ""));
  }
  EXPECT_EQ(kinds.size(), std::size_t(kSceneKinds));
  for (const auto& [name, count] : kinds) EXPECT_EQ(count, 20) << name;
}

}  // namespace
}  // namespace cisamr
