// Per-phase volume error of the 3D mesher against the exact volumes, for several background
// sizes h at fixed SAMR levels: the convergence of phase measures as h → 0 (DESIGN.md §2.3,
// issue 3 "Must show"). Interface nodes lie on the surfaces, so a convex inclusion's mesh is
// inscribed and its volume error should fall as h² (observed order ≈ 2).
//
//   build/bin/convergence3                       the three built-in cases (below), h = 1/10, 1/20, 1/40
//   build/bin/convergence3 --case NAME           one of them: spheres | ellipsoid | clipped
//   build/bin/convergence3 --n 10 20 40 80       cells per unit-cube side (h = 1/n)
//   build/bin/convergence3 --levels L            SAMR levels of every inclusion (default 1)
//   build/bin/convergence3 --scene FILE.json [--h h1 h2 ...]   a scene file (exact volumes
//                                                from Oracle3::phase_measures; default h, h/2, h/4)
//
// Built-in cases (unit cube, matrix phase 1, inclusion phase 2):
//   spheres    three disjoint spheres inside the box, r = 0.20, 0.17, 0.13
//   ellipsoid  one ellipsoid, semi-axes 0.32 × 0.20 × 0.12, rotated about three axes
//   clipped    a sphere of radius 0.3 centred at x = 0.8, clipped by the face x = 1 (a cap
//              of height 0.1 is outside; the flat disc and its C0 rim are part of the interface)
// Exact volumes are analytic (and checked against Oracle3::phase_measures to 1e-9).
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <exception>
#include <string>
#include <vector>

#include "core/error.hpp"
#include "geometry/oracle.hpp"
#include "io/scene_io.hpp"
#include "mesh/metrics.hpp"
#include "pipeline/pipeline.hpp"

using namespace cisamr;

namespace {

struct Case {
  std::string name;
  geometry::SceneDesc scene;
  std::vector<double> exact;  // per phase (empty: from the oracle)
};

geometry::SceneDesc unit_cube(const std::string& name, int levels) {
  geometry::SceneDesc s;
  s.source = name;
  s.dimension = 3;
  s.domain_min = {0, 0, 0};
  s.domain_max = {1, 1, 1};
  s.h = 0.1;
  s.levels = levels;
  s.phases = {{1, "matrix", false}, {2, "inclusion", false}};
  s.matrix_phase = 1;
  return s;
}

double ball(double r) { return 4.0 / 3.0 * M_PI * r * r * r; }

geometry::Rotation3 multiply(const geometry::Rotation3& a, const geometry::Rotation3& b) {
  geometry::Rotation3 c{};
  for (int i = 0; i < 3; ++i)
    for (int j = 0; j < 3; ++j)
      for (int k = 0; k < 3; ++k) c[i][j] += a[i][k] * b[k][j];
  return c;
}

Case spheres_case(int levels) {
  Case c{"spheres", unit_cube("spheres", levels), {}};
  const double r[3] = {0.20, 0.17, 0.13};
  c.scene.inclusions.push_back({geometry::Sphere{{0.31, 0.33, 0.29}, r[0]}, 2, levels});
  c.scene.inclusions.push_back({geometry::Sphere{{0.71, 0.69, 0.66}, r[1]}, 2, levels});
  c.scene.inclusions.push_back({geometry::Sphere{{0.70, 0.27, 0.72}, r[2]}, 2, levels});
  const double inside = ball(r[0]) + ball(r[1]) + ball(r[2]);
  c.exact = {1 - inside, inside};
  return c;
}

Case ellipsoid_case(int levels) {
  Case c{"ellipsoid", unit_cube("ellipsoid", levels), {}};
  const double x = 10 * M_PI / 180, y = 20 * M_PI / 180, z = 30 * M_PI / 180;
  const geometry::Rotation3 rx{{{1, 0, 0}, {0, std::cos(x), -std::sin(x)}, {0, std::sin(x), std::cos(x)}}};
  const geometry::Rotation3 ry{{{std::cos(y), 0, std::sin(y)}, {0, 1, 0}, {-std::sin(y), 0, std::cos(y)}}};
  const geometry::Rotation3 rz{{{std::cos(z), -std::sin(z), 0}, {std::sin(z), std::cos(z), 0}, {0, 0, 1}}};
  const Vec3 axes{0.32, 0.20, 0.12};
  c.scene.inclusions.push_back({geometry::Ellipsoid{{0.5, 0.48, 0.52}, axes, multiply(rz, multiply(ry, rx))}, 2, levels});
  const double inside = 4.0 / 3.0 * M_PI * axes[0] * axes[1] * axes[2];
  c.exact = {1 - inside, inside};
  return c;
}

Case clipped_case(int levels) {
  Case c{"clipped", unit_cube("clipped", levels), {}};
  const double r = 0.3, cx = 0.8, cap = cx + r - 1.0;  // height of the cap beyond x = 1
  c.scene.inclusions.push_back({geometry::Sphere{{cx, 0.47, 0.53}, r}, 2, levels});
  const double inside = ball(r) - M_PI * cap * cap * (3 * r - cap) / 3;
  c.exact = {1 - inside, inside};
  return c;
}

struct Row {
  double h = 0;
  std::size_t tets = 0;
  double seconds = 0, worst_aspect = 0;
  std::vector<double> meshed, error;  // per phase; error = (meshed - exact) / exact
};

Row run(geometry::SceneDesc scene, double h, const std::vector<double>& exact_given, std::vector<double>& exact) {
  scene.h = h;
  const geometry::Oracle3 oracle(scene);
  const std::vector<double> from_oracle = oracle.phase_measures();
  exact = exact_given.empty() ? from_oracle : exact_given;
  for (std::size_t p = 0; p < exact.size(); ++p)
    if (std::abs(from_oracle[p] - exact[p]) > 1e-9 * std::max(1.0, std::abs(exact[p])))
      throw std::logic_error(scene.source + ": the oracle's phase volume " + std::to_string(from_oracle[p]) +
                             " differs from the analytic " + std::to_string(exact[p]));
  const auto start = std::chrono::steady_clock::now();
  const pipeline::Result<3> result = pipeline::mesh(oracle);
  Row row;
  row.h = h;
  row.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  const mesh::Mesh3& m = result.mesh;
  row.tets = m.cell_count();
  row.meshed.assign(scene.phases.size(), 0.0);
  for (std::size_t c = 0; c < m.cell_count(); ++c) {
    const LocalId* n = m.cell(c);
    const Vec3 a = m.point(n[0]), b = m.point(n[1]), cc = m.point(n[2]), d = m.point(n[3]);
    row.meshed[static_cast<std::size_t>(scene.phase_index(m.cell_phase[c]))] += mesh::signed_volume(a, b, cc, d);
    row.worst_aspect = std::max(row.worst_aspect, mesh::aspect_ratio(a, b, cc, d));
  }
  double box = 1, meshed = 0;
  for (int d = 0; d < 3; ++d) box *= scene.domain_max[d] - scene.domain_min[d];
  for (double v : row.meshed) meshed += v;
  for (std::size_t p = 0; p < scene.phases.size(); ++p) {
    // A void phase is not meshed: its measure is the box minus every meshed phase.
    if (scene.phases[p].is_void) row.meshed[p] = box - meshed;
    row.error.push_back(exact[p] > 0 ? (row.meshed[p] - exact[p]) / exact[p] : 0.0);
  }
  return row;
}

void study(const Case& c, const std::vector<double>& hs) {
  std::printf("\n%s\n", c.name.c_str());
  std::printf("%-10s %10s %8s %7s  %-10s %14s %14s %12s %7s\n", "h", "tets", "s", "max AR", "phase", "exact volume",
              "mesh volume", "rel. error", "order");
  std::vector<Row> rows;
  for (double h : hs) {
    std::vector<double> exact;
    rows.push_back(run(c.scene, h, c.exact, exact));
    const Row& r = rows.back();
    for (std::size_t p = 0; p < c.scene.phases.size(); ++p) {
      char order[32] = "";
      if (rows.size() > 1) {
        const Row& q = rows[rows.size() - 2];
        if (r.error[p] != 0 && q.error[p] != 0)
          std::snprintf(order, sizeof order, "%.2f", std::log(std::abs(q.error[p] / r.error[p])) / std::log(q.h / r.h));
      }
      if (p == 0)
        std::printf("%-10.6g %10zu %8.2f %7.3f  ", h, r.tets, r.seconds, r.worst_aspect);
      else
        std::printf("%-10s %10s %8s %7s  ", "", "", "", "");
      std::printf("%-10s %14.9f %14.9f %+12.3e %7s\n", c.scene.phases[p].name.c_str(), exact[p], r.meshed[p], r.error[p],
                  order);
    }
  }
}

}  // namespace

int main(int argc, char** argv) {
  std::string which = "all", scene_file;
  std::vector<int> cells{10, 20, 40};
  std::vector<double> hs;
  int levels = 1;
  for (int i = 1; i < argc; ++i) {
    const std::string a = argv[i];
    if (a == "--case" && i + 1 < argc) which = argv[++i];
    else if (a == "--levels" && i + 1 < argc) levels = std::atoi(argv[++i]);
    else if (a == "--scene" && i + 1 < argc) scene_file = argv[++i];
    else if (a == "--n") {
      cells.clear();
      while (i + 1 < argc && argv[i + 1][0] != '-') cells.push_back(std::atoi(argv[++i]));
    } else if (a == "--h") {
      while (i + 1 < argc && argv[i + 1][0] != '-') hs.push_back(std::atof(argv[++i]));
    } else {
      std::fprintf(stderr,
                   "usage: convergence3 [--case spheres|ellipsoid|clipped|all] [--n N1 N2 ...] [--levels L]\n"
                   "       convergence3 --scene SCENE.json [--h h1 h2 ...]\n");
      return 2;
    }
  }
  try {
    if (!scene_file.empty()) {
      const geometry::SceneDesc scene = io::read_scene(scene_file);
      if (scene.dimension != 3) throw InputError(scene_file, "dimension", "convergence3 needs a 3D scene");
      if (hs.empty()) hs = {scene.h, scene.h / 2, scene.h / 4};
      study(Case{scene_file, scene, {}}, hs);
      return 0;
    }
    for (int n : cells) hs.push_back(1.0 / n);
    std::printf("3D per-phase volume error, unit cube, SAMR levels %d, h = 1/n for n =", levels);
    for (int n : cells) std::printf(" %d", n);
    std::printf(" (order = log(e_coarse/e_fine) / log(h_coarse/h_fine))\n");
    std::vector<Case> cases;
    if (which == "all" || which == "spheres") cases.push_back(spheres_case(levels));
    if (which == "all" || which == "ellipsoid") cases.push_back(ellipsoid_case(levels));
    if (which == "all" || which == "clipped") cases.push_back(clipped_case(levels));
    if (cases.empty()) {
      std::fprintf(stderr, "convergence3: unknown case %s\n", which.c_str());
      return 2;
    }
    for (const Case& c : cases) study(c, hs);
  } catch (const InputError& e) {
    std::fprintf(stderr, "convergence3: error: %s\n", e.what());
    return 2;
  } catch (const std::exception& e) {
    std::fprintf(stderr, "convergence3: %s\n", e.what());
    return 1;
  }
  return 0;
}
