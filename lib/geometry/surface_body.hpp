#pragma once
// A closed exact surface made of rational Bézier pieces (private to lib/geometry;
// docs/nurbs-step-design.md §2): the NURBS patches of a `nurbs_surface` inclusion, placed,
// with a watertight tessellation whose cells each carry a certified shell (an axis box
// and a slab that provably hold both the cell's triangles and the surface piece they
// stand for). Outside every shell the tessellation's exact ray parity decides inside and
// outside; inside a shell the exact surface does, through the roots of short segments.
// Every answer is a pure function of the descriptor and the query (no state, no threads),
// so meshes stay the same on any number of partitions.
#include <array>
#include <functional>
#include <cstdint>
#include <map>
#include <memory>
#include <mutex>
#include <string>
#include <vector>

#include "core/types.hpp"
#include "geometry/brep_data.hpp"
#include "geometry/flat_bvh.hpp"
#include "geometry/nurbs3.hpp"
#include "geometry/scene.hpp"
#include "geometry/stl_mesh.hpp"

namespace cisamr::geometry::surface {

// One grid cell of a piece: the parameter rectangle [s0, s1] × [t0, t1] (local to the
// piece) that one or two tessellation triangles stand for, and its shell.
struct Cell {
  std::int32_t patch = 0, piece = 0;  // piece index within the patch's pieces
  double s0 = 0, s1 = 1, t0 = 0, t1 = 1;
  Box3 box{};          // holds the restricted piece and the cell's triangles
  Vec3 normal{};       // unit; the slab is lo <= normal·x <= hi
  double lo = 0, hi = 0;
  std::int8_t outward = 1;  // outward normal = outward · (S_s × S_t)
};

struct Body {
  std::vector<nurbs::PatchPieces> patches;  // placed control points
  std::vector<Cell> cells;
  std::vector<nurbs::BezierPatch> cell_pieces;  // each cell's piece restricted to its rectangle
  FlatBvh<3> cell_bvh;  // over the cells' boxes
  stl::Mesh mesh;       // the tessellation (outward faces)
  Box3 box{};           // holds the surface
  double size = 0;      // box diagonal
  double tolerance = 0; // τ = 1e-12·size, the ON band
  double max_thickness = 0;  // thickest shell (hi − lo)
  // Trimmed faces (STEP): per patch, its trimming loops as closed polygons in (u, v) (empty:
  // the whole parameter rectangle), and the slack in (u, v) within which a root near a
  // loop still counts (a root on an edge between two faces is found by both). The polygons
  // stay within a quarter of the slack of their curves, so a root inside the face between a
  // chord and its arc is within the slack of the polygon.
  std::vector<std::vector<std::vector<Vec2>>> trims;
  std::vector<double> trim_slack;
  // Per patch, the polygon edges by horizontal band of v (each edge in every band its v
  // range, widened by the slack, meets): edges of band b are
  // trim_edges[k][trim_band_start[k][b] .. trim_band_start[k][b + 1]) as (loop, index).
  struct TrimBands {
    double v0 = 0, inv_height = 0;
    std::vector<std::int32_t> start;
    std::vector<std::array<std::int32_t, 2>> edges;
  };
  std::vector<TrimBands> trim_bands;
  double exact_volume = -1;  // ≥ 0: the volume as imported (trimmed faces)
  double exact_area = -1;
};

// A placement: x' = rotation·(scale·x) + translate.
struct Placement {
  double scale = 1;
  Rotation3 rotation{{{1, 0, 0}, {0, 1, 0}, {0, 0, 1}}};
  Vec3 translate{};
};

// Per-thread counters of the query paths (benchmarks and tests read them).
struct Stats {
  std::int64_t side_calls = 0, side_in_shell = 0, side_fallback = 0;
  std::int64_t segment_calls = 0, roots = 0, repairs = 0;
  std::int64_t touch_refinements = 0;
};
Stats& stats();

// A control point placed: rotation·(scale·x) + translate, in the operation order of STL
// vertices (stl_mesh.cpp), so boxes computed from descriptors agree with bodies bit for bit.
Vec3 place(const NurbsSurface& surface, const Vec3& x);

// Builds the body of the placed patches. Returns "" or the problem, field suffix first
// (".patches[2].v_max: meets no other patch boundary ...").
std::string build(const NurbsSurface& surface, Body& out);

// Builds the body of the selected solids of an imported STEP file (all of them when
// `solids` is empty), placed: its faces' surfaces and trims, the import's mesh as the
// tessellation, a cell per (triangle, Bézier piece its (u, v) box meets) and per span of a
// trimming curve. Returns "" or the problem ("solid 1: faces 3 and 7 intersect …").
std::string build_brep(const BrepData& data, const std::vector<int>& solids, const Placement& placement, Body& out);

// The body of a descriptor, built once per process (families answer many questions about
// the same descriptor, and every partition's oracle builds its own). Throws nothing: a
// descriptor that does not build gives nullptr and its problem in `problem`.
std::shared_ptr<const Body> cached_body(const NurbsSurface& surface, std::string* problem = nullptr);

// A process-wide cache of bodies by key, one per call site: `build(body)` returns "" or the
// problem and runs once per key (the problem is cached too); at most 256 entries, then
// cleared. Thread-safe; two threads may build the same key once each.
template <class Key, class Build>
std::shared_ptr<const Body> cached(const Key& key, Build&& build, std::string* problem) {
  static std::mutex mutex;
  static std::map<Key, std::pair<std::shared_ptr<const Body>, std::string>> cache;
  {
    std::lock_guard<std::mutex> lock(mutex);
    if (const auto it = cache.find(key); it != cache.end()) {
      if (problem) *problem = it->second.second;
      return it->second.first;
    }
  }
  auto body = std::make_shared<Body>();
  const std::string why = build(*body);
  std::shared_ptr<const Body> result;
  if (why.empty()) result = std::move(body);
  if (problem) *problem = why;
  std::lock_guard<std::mutex> lock(mutex);
  if (cache.size() >= 256) cache.clear();
  cache.emplace(key, std::make_pair(result, why));
  return result;
}

// +1 inside, 0 within τ of the surface, −1 outside.
int side(const Body& body, const Vec3& p);
// Parameters t in (0, 1) where the open segment a→b meets the surface, ascending, roots
// closer than τ merged.
void segment_roots(const Body& body, const Vec3& a, const Vec3& b, std::vector<double>& ts);
// Does the surface come within τ of the closed box? Never false when it meets it.
bool touches_box(const Body& body, const Box3& box);
// Distance from p to the surface, and the nearest point's outward normal (not unit;
// zero where it is undefined: a pole, a crease of the parametrisation).
double distance(const Body& body, const Vec3& p, Vec3* normal = nullptr);
// Do the closed regions of a and b come within gap of each other? Never false when they
// do; true also when they miss by less than the subdivision resolves (over-refinement only).
bool within(const Body& a, const Body& b, double gap);
// The same against a convex region, given by its support function h(d) = max x·d and a
// membership test (its box's centre must lie in it: spheres, ellipsoids, cylinders): never
// false when they come within gap; true also when they miss by less than 1e-3 of the
// body's size.
bool within_convex(const Body& a, const std::function<double(const Vec3&)>& support,
                   const std::function<bool(const Vec3&)>& contains, double gap);
// The extremes of x over the surface, and of y over its section at x (where the length of a
// line through the body has a square-root kink: breakpoints of the oracle's measures), to
// about 1e-12 (x) and 1e-6 (y) of the size. Interior tangencies (a torus's hole) are not among them.
void x_extremes(const Body& body, std::vector<double>& out);
void y_extremes_at(const Body& body, double x, std::vector<double>& out);
double volume(const Body& body);
double area(const Body& body);
// Points on the exact surface about `spacing` apart (at least every tessellation vertex).
std::vector<Vec3> surface_points(const Body& body, double spacing);

}  // namespace cisamr::geometry::surface
