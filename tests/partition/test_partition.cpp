// Partitioning: exact tiling on the lattice, load conservation, symmetric neighbours,
// better balance than a uniform grid on a clustered scene, the paper's Fig. 3 merge.
#include <gtest/gtest.h>

#include <chrono>
#include <cmath>
#include <nlohmann/json.hpp>

#include "core/error.hpp"
#include "geometry/shapes.hpp"
#include "pack/pack.hpp"
#include "partition/load_field.hpp"
#include "partition/partition.hpp"

using namespace cisamr;
using namespace cisamr::geometry;

namespace {

SceneDesc base_scene(int dim, double extent, double h) {
  SceneDesc s;
  s.dimension = dim;
  s.domain_min = {0, 0, 0};
  s.domain_max = {extent, extent, dim == 3 ? extent : 0};
  s.h = h;
  s.levels = 1;
  s.phases = {{1, "matrix", false}, {2, "inclusion", false}};
  return s;
}

// A clustered 2D scene from the packer: dense cluster in one corner, sparse elsewhere.
SceneDesc clustered_scene() {
  const auto spec = pack::parse_pack_spec(R"({"format": "cisamr-pack/1", "dimension": 2, "seed": 3,
      "domain": {"min": [0, 0], "max": [200, 200]}, "mesh": {"h": 1, "levels": 2},
      "populations": [
        {"shape": "circle", "count": 250, "size": {"law": "uniform", "min": 1, "max": 2.5}, "min_gap": 0.5,
         "region": {"min": [0, 0], "max": [70, 90]}},
        {"shape": "ellipse", "count": 300, "size": {"law": "uniform", "min": 1, "max": 2.5}, "min_gap": 0.5,
         "aspect": {"law": "uniform", "min": 1, "max": 2}}]})", "clustered.json");
  return pack::pack(spec).scene;
}

void expect_valid_tiling(const partition::Partition& p, int n) {
  ASSERT_EQ(static_cast<int>(p.parts.size()), n);
  const int dim = p.dimension;
  double volume = 0, load = 0;
  for (const auto& a : p.parts) {
    double v = 1;
    for (int d = 0; d < dim; ++d) {
      EXPECT_LT(a.lattice_min[d], a.lattice_max[d]);
      EXPECT_GE(a.lattice_min[d], 0);
      EXPECT_LE(a.lattice_max[d], p.cells[d]);
      EXPECT_EQ(a.box.min[d], p.domain.min[d] + a.lattice_min[d] * p.h);  // on the lattice
      EXPECT_EQ(a.box.max[d], p.domain.min[d] + a.lattice_max[d] * p.h);
      v *= static_cast<double>(a.lattice_max[d] - a.lattice_min[d]);
    }
    volume += v;
    load += a.load;
  }
  double cells = 1;
  for (int d = 0; d < dim; ++d) cells *= static_cast<double>(p.cells[d]);
  EXPECT_EQ(volume, cells);  // with pairwise disjointness: the union is the domain
  for (std::size_t i = 0; i < p.parts.size(); ++i)
    for (std::size_t j = i + 1; j < p.parts.size(); ++j) {
      bool disjoint = false;
      for (int d = 0; d < dim; ++d)
        disjoint = disjoint || p.parts[i].lattice_max[d] <= p.parts[j].lattice_min[d] ||
                   p.parts[j].lattice_max[d] <= p.parts[i].lattice_min[d];
      EXPECT_TRUE(disjoint) << i << " " << j;
    }
  EXPECT_NEAR(load, p.total_load, 1e-9 * std::max(1.0, p.total_load));
  // Neighbours are symmetric, with the same face seen from both sides.
  for (const auto& a : p.parts)
    for (const auto& nb : a.neighbours) {
      bool found = false;
      for (const auto& back : p.parts[nb.part].neighbours)
        if (back.part == a.id && back.axis == nb.axis && back.side == -nb.side && back.periodic == nb.periodic) {
          found = true;
          for (int d = 0; d < dim; ++d) {
            if (d == nb.axis) continue;
            EXPECT_EQ(back.face.min[d], nb.face.min[d]);
            EXPECT_EQ(back.face.max[d], nb.face.max[d]);
          }
        }
      EXPECT_TRUE(found) << a.id << " -> " << nb.part;
    }
}

}  // namespace

TEST(PartitionLoad, CirclesGiveExactPerimeters) {
  SceneDesc s = base_scene(2, 20, 1);
  s.inclusions.push_back({Circle{{5.3, 6.1}, 2.7}, 2, 2});
  s.inclusions.push_back({Circle{{14.0, 14.0}, 3.0}, 2, 3});
  const double expected = 2 * 2 * M_PI * 2.7 + 3 * 2 * M_PI * 3.0;  // R^1 · perimeter
  EXPECT_NEAR(partition::total_load(s), expected, 1e-9 * expected);
  const auto p = partition::partition_domain(s, 4);
  expect_valid_tiling(p, 4);
  // The arcs inside one quadrant: the circle at (14,14) r=3 lies in the top-right quarter.
  partition::PartitionOptions o;
  const auto u = partition::uniform_grid_partition(s, 4, o);
  EXPECT_NEAR(u.parts[3].load, 3 * 2 * M_PI * 3.0, 1e-9);
}

TEST(PartitionLoad, ClippedOutsideAndWrappedWhenPeriodic) {
  SceneDesc s = base_scene(2, 20, 1);
  s.inclusions.push_back({Circle{{0, 10}, 2}, 2, 1});  // half outside the domain
  EXPECT_NEAR(partition::total_load(s), M_PI * 2, 1e-9);
  s.periodic = {true, true, true};
  EXPECT_NEAR(partition::total_load(s), 2 * M_PI * 2, 1e-9);
}

TEST(PartitionLoad, SurfacesCountOnlyInsideTheDomain) {
  // A sphere of radius 0.6 around the centre of the unit cube pokes out through six caps
  // (which meet neither each other nor the cube's edges).
  SceneDesc s = base_scene(3, 1, 0.05);
  s.inclusions.push_back({Sphere{{0.5, 0.5, 0.5}, 0.6}, 2, 1});
  const double r = 0.6, inside = 4 * M_PI * r * r - 6 * 2 * M_PI * r * (r - 0.5);
  EXPECT_NEAR(partition::total_load(s), inside, 1e-2 * inside);  // leaves cut by the faces
  // The same through a rotated ellipsoid of equal axes.
  s.inclusions[0].shape = Ellipsoid{{0.5, 0.5, 0.5}, {r, r, r}, quaternion_rotation(0.8, 0.6, 0, 0)};
  EXPECT_NEAR(partition::total_load(s), inside, 1e-2 * inside);  // leaves cut by the faces
}

TEST(PartitionLoad, AFibreFarLongerThanTheDomainCostsItsPartInside) {
  // Along z through the unit cube, 2e7 long: 3.2e8 slices of rings, of which ~16 meet it.
  SceneDesc s = base_scene(3, 1, 0.25);
  s.inclusions.push_back({Cylinder{{0.5, 0.5, -1e7}, {0.5, 0.5, 1e7}, 0.1}, 2, 1});
  const auto start = std::chrono::steady_clock::now();
  const double load = partition::total_load(s);
  const double seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  EXPECT_NEAR(load, 2 * M_PI * 0.1, 1e-9);  // the lateral surface inside; the caps are far
  EXPECT_LT(seconds, 5.0);
}

TEST(PartitionLoad, EllipsePerimeterIsExact) {  // the |A_k| the load field scales its samples to
  auto perimeter = [](double a, double b) { return shape_boundary_measure(Ellipse{{3, 4}, {a, b}, 0.7}); };
  EXPECT_NEAR(perimeter(1, 1), 2 * M_PI, 1e-14);
  EXPECT_NEAR(perimeter(2, 1), 9.688448220547675, 1e-12);
  EXPECT_NEAR(perimeter(1, 2), 9.688448220547675, 1e-12);
}

TEST(Partition, TilesTheDomainOnTheLattice2D) {
  const SceneDesc s = clustered_scene();
  for (int n : {1, 3, 7, 12, 20}) {
    SCOPED_TRACE(n);
    expect_valid_tiling(partition::partition_domain(s, n), n);
    partition::PartitionOptions merge_only;
    merge_only.method = partition::PartitionOptions::Method::merge;
    expect_valid_tiling(partition::partition_domain(s, n, merge_only), n);
    expect_valid_tiling(partition::uniform_grid_partition(s, n), n);
  }
}

// A sparse 3D scene: most boxes hold no load, where the prefix sums' round-off used to
// give loads of -1e-19 that made the bisection reject every cut of an empty region and
// lose its boxes (64 partitions covered 6,084 of the 6,144 cubes: a hole in the mesh).
TEST(Partition, SparseSceneStillTilesTheDomain) {
  SceneDesc s = base_scene(3, 4.0, 0.125);
  s.domain_max = {4.0, 2.0, 1.5};
  s.levels = 1;
  s.inclusions.push_back({Sphere{{3.98, 1.97, 0.04}, 0.22}, 2, 1});
  s.inclusions.push_back({Sphere{{0.4450248076601411, 1.216609103825386, 0.9464221038244527}, 0.14681136175770101}, 2, 1});
  for (int n : {27, 64, 100}) {
    SCOPED_TRACE(n);
    expect_valid_tiling(partition::partition_domain(s, n), n);
    partition::PartitionOptions bisection;
    bisection.method = partition::PartitionOptions::Method::bisection;
    expect_valid_tiling(partition::partition_domain(s, n, bisection), n);
  }
}

TEST(Partition, BeatsTheUniformGridOnAClusteredScene) {
  const SceneDesc s = clustered_scene();
  for (int n : {4, 9, 16}) {
    const auto ours = partition::partition_domain(s, n);
    const auto grid = partition::uniform_grid_partition(s, n);
    EXPECT_LT(ours.max_load(), grid.max_load()) << n;
    EXPECT_LT(ours.imbalance(), 1.15) << n;
  }
}

TEST(Partition, MergesTheTwoLightRegionsFirst) {  // the paper's Fig. 3b: 2×2 → 3
  SceneDesc s = base_scene(2, 40, 1);
  s.inclusions.push_back({Circle{{10, 10}, 4}, 2, 1});
  s.inclusions.push_back({Circle{{10, 30}, 4}, 2, 1});
  s.inclusions.push_back({Circle{{30, 10}, 2}, 2, 1});
  s.inclusions.push_back({Circle{{30, 30}, 2}, 2, 1});
  partition::PartitionOptions o;
  o.method = partition::PartitionOptions::Method::merge;
  o.oversubscription = 1;
  o.extra_depths = 0;
  o.rebalance = false;
  const auto p = partition::partition_domain(s, 3, o);
  expect_valid_tiling(p, 3);
  bool right_half = false;
  for (const auto& a : p.parts)
    right_half = right_half || (a.lattice_min[0] == 20 && a.lattice_max[0] == 40 && a.lattice_min[1] == 0 &&
                                a.lattice_max[1] == 40);
  EXPECT_TRUE(right_half);
  // Fig. 3c: 3 levels on the right particles make the left pair the lighter one.
  for (int k = 2; k < 4; ++k) s.inclusions[k].levels = 5;
  const auto q = partition::partition_domain(s, 3, o);
  bool left_half = false;
  for (const auto& a : q.parts)
    left_half = left_half || (a.lattice_min[0] == 0 && a.lattice_max[0] == 20 && a.lattice_max[1] == 40 &&
                              a.lattice_min[1] == 0);
  EXPECT_TRUE(left_half);
}

TEST(Partition, SpheresIn3DAndPeriodicNeighbours) {
  const auto spec = pack::parse_pack_spec(R"({"format": "cisamr-pack/1", "dimension": 3, "seed": 2,
      "domain": {"min": [0, 0, 0], "max": [40, 40, 40], "periodic": true}, "mesh": {"h": 1, "levels": 2},
      "populations": [{"shape": "sphere", "count": 150, "size": {"law": "uniform", "min": 1.5, "max": 3}, "min_gap": 0.5},
                      {"shape": "ellipsoid", "count": 30, "size": 2, "aspect": 2, "min_gap": 0.5}]})", "s.json");
  const SceneDesc s = pack::pack(spec).scene;
  double area = 0;
  for (const auto& inc : s.inclusions)
    if (auto* sp = std::get_if<Sphere>(&inc.shape)) area += 4 * M_PI * sp->radius * sp->radius;
  const double total = partition::total_load(s);
  EXPECT_GT(total, area * std::pow(2.0, 1.5));  // spheres plus the ellipsoids, M = 1.5
  const auto p = partition::partition_domain(s, 12);
  expect_valid_tiling(p, 12);
  int periodic = 0;
  for (const auto& a : p.parts)
    for (const auto& nb : a.neighbours) periodic += nb.periodic;
  EXPECT_GT(periodic, 0);
  EXPECT_LE(p.max_load(), partition::uniform_grid_partition(s, 12).max_load());
}

// The parallel mesher's 3D ghost (issue #15): with PartitionOptions' ghost, each box costs its
// load plus the weighted load of its ghost (the box grown, clipped to the domain), and the
// cuts balance that cost. On a uniform lattice of spheres, 27 boxes: the costliest box is
// cheaper than the costliest of the load-balanced boxes (by the same cost), boxes inside the
// domain get less load than those at its corners, and each box's cost is its load plus the
// weighted ghost load of the field's sums.
TEST(Partition, GhostAwareCostBalancesEachBoxWithItsGhost) {
  SceneDesc s = base_scene(3, 60, 1);
  for (int k = 0; k < 6; ++k)
    for (int j = 0; j < 6; ++j)
      for (int i = 0; i < 6; ++i) s.inclusions.push_back({Sphere{{5.0 + 10 * i, 5.0 + 10 * j, 5.0 + 10 * k}, 3.0}, 2});
  partition::PartitionOptions plain_options, ghost_options;
  ghost_options.ghost_cells_at_level = {7, 4, 3, 2};  // level 1: 4 cells
  ghost_options.ghost_weight = 0.35;
  const auto plain = partition::partition_domain(s, 27, plain_options);
  const auto aware = partition::partition_domain(s, 27, ghost_options);
  expect_valid_tiling(plain, 27);
  expect_valid_tiling(aware, 27);
  EXPECT_EQ(aware.ghost_cells, 4);
  EXPECT_EQ(aware.ghost_weight, 0.35);
  EXPECT_EQ(plain.ghost_weight, 0.0);

  const partition::LoadField field = partition::build_load_field(s, ghost_options);
  ASSERT_EQ(field.coarsen, 1);  // raster = lattice: boxes in lattice cells
  const auto cost_of = [&](const partition::Part& part) {
    std::array<std::int64_t, 3> lo{}, hi{}, glo{}, ghi{};
    for (int d = 0; d < 3; ++d) {
      lo[d] = part.lattice_min[d], hi[d] = part.lattice_max[d];
      glo[d] = std::max<std::int64_t>(0, lo[d] - 4), ghi[d] = std::min<std::int64_t>(60, hi[d] + 4);
    }
    const double own = field.box_load(lo, hi);
    return own + 0.35 * (field.box_load(glo, ghi) - own);
  };
  double plain_worst = 0;
  for (const auto& part : plain.parts) {
    EXPECT_EQ(part.cost, part.load);
    plain_worst = std::max(plain_worst, cost_of(part));
  }
  // Loads of the boxes at a corner of the domain (three domain faces) and of those with at
  // most one domain face (the rest of their surface carries ghost).
  double corner_load = 0, inner_load = 1e300;
  for (const auto& part : aware.parts) {
    EXPECT_NEAR(part.cost, cost_of(part), 1e-9 * part.cost);
    int faces = 0;
    for (int d = 0; d < 3; ++d) faces += (part.lattice_min[d] == 0) + (part.lattice_max[d] == 60);
    if (faces == 3) corner_load = std::max(corner_load, part.load);
    if (faces <= 1) inner_load = std::min(inner_load, part.load);
  }
  EXPECT_LT(aware.max_cost(), 0.97 * plain_worst);
  ASSERT_GT(corner_load, 0);
  ASSERT_LT(inner_load, 1e300);
  EXPECT_LT(inner_load, 0.8 * corner_load);
  EXPECT_GT(aware.imbalance(), plain.imbalance());  // the loads alone are less even, by design

  const auto doc = nlohmann::json::parse(partition::to_json(aware, "s.json"));
  EXPECT_EQ(doc["summary"]["ghost_cells"], 4);
  EXPECT_EQ(doc["summary"]["max_cost"].get<double>(), aware.max_cost());
  EXPECT_TRUE(doc["parts"][0].contains("cost"));
  EXPECT_FALSE(nlohmann::json::parse(partition::to_json(plain, "s.json"))["parts"][0].contains("cost"));

  // A periodic scene's ghost wraps: its boxes balance their loads only.
  s.periodic = {true, true, true};
  const auto wrapped = partition::partition_domain(s, 8, ghost_options);
  EXPECT_EQ(wrapped.ghost_weight, 0.0);
  for (const auto& part : wrapped.parts) EXPECT_EQ(part.cost, part.load);
}

TEST(Partition, JsonIsCompleteAndDeterministic) {
  const SceneDesc s = clustered_scene();
  const auto a = partition::partition_domain(s, 6), b = partition::partition_domain(s, 6);
  const std::string ja = partition::to_json(a, "scene.json");
  EXPECT_EQ(ja, partition::to_json(b, "scene.json"));
  const auto doc = nlohmann::json::parse(ja);
  EXPECT_EQ(doc["format"], "cisamr-partition/1");
  ASSERT_EQ(doc["parts"].size(), 6u);
  std::size_t listed = 0;
  for (const auto& part : doc["parts"]) {
    EXPECT_EQ(part["min"].size(), 2u);
    EXPECT_FALSE(part["neighbours"].empty());
    listed += part["inclusions"].size();
  }
  EXPECT_GE(listed, s.inclusions.size());  // every inclusion is listed by a part that meets it
  const std::string svg = partition::to_svg(a, s);
  EXPECT_NE(svg.find("<svg"), std::string::npos);
  EXPECT_NE(svg.find("<polygon"), std::string::npos);  // the inclusions
}

// Partitioning (and so the distributed mesher) refuses what the sequential mesher's oracle
// refuses, with the same message, even for shapes outside the domain.
TEST(Partition, ValidatesShapesAsTheOracleDoes) {
  const auto message = [](const SceneDesc& s) {
    try {
      partition::partition_domain(s, 2);
    } catch (const InputError& e) {
      return std::string(e.what());
    }
    return std::string("accepted");
  };
  SceneDesc s = base_scene(2, 10, 1);
  s.source = "scene.json";
  s.inclusions.push_back({Polygon{{{20, 20}, {20, 20}, {20, 20}, {20, 20}}}, 2, 1});
  EXPECT_NE(message(s).find("scene.json: inclusions[0].vertices: a polygon needs at least 3 distinct vertices"),
            std::string::npos)
      << message(s);
  NurbsCurve open;  // quadratic, clamped, its ends apart
  open.degree = 2;
  open.knots = {0, 0, 0, 0.5, 1, 1, 1};
  open.control_points = {{2, 2}, {8, 2}, {8, 8}, {2, 8}};
  s.inclusions[0].shape = open;
  EXPECT_NE(message(s).find("scene.json: inclusions[0].control_points: curve is not closed"), std::string::npos)
      << message(s);
}

TEST(Partition, BadCountsAreInputErrors) {
  SceneDesc s = base_scene(2, 4, 1);
  EXPECT_THROW(partition::partition_domain(s, 0), InputError);
  EXPECT_THROW(partition::partition_domain(s, 17), InputError);
  expect_valid_tiling(partition::partition_domain(s, 16), 16);
}
