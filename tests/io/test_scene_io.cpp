#include "io/scene_io.hpp"

#include <gtest/gtest.h>

#include <bit>
#include <cmath>

#include <sys/stat.h>

#include "core/error.hpp"
#include "geometry/shapes.hpp"
#include "geometry/step_import.hpp"
#include "io/stl_io.hpp"
#include "support/random_nurbs3.hpp"
#include "temp_dir.hpp"

namespace cisamr::io {
namespace {

using namespace geometry;
using testing::read_text;
using testing::TempDir;

// ---- exact, field-by-field comparison (bits of every double) ----
bool same(double a, double b) { return std::bit_cast<std::uint64_t>(a) == std::bit_cast<std::uint64_t>(b); }
template <std::size_t N>
bool same(const std::array<double, N>& a, const std::array<double, N>& b) {
  for (std::size_t i = 0; i < N; ++i)
    if (!same(a[i], b[i])) return false;
  return true;
}
bool same(const Rotation3& a, const Rotation3& b) {
  for (int i = 0; i < 3; ++i)
    if (!same(a[i], b[i])) return false;
  return true;
}
bool same(const NurbsPatch& a, const NurbsPatch& b);
bool same(const Phase& a, const Phase& b);
template <class T>
bool same(const std::vector<T>& a, const std::vector<T>& b) {
  if (a.size() != b.size()) return false;
  for (std::size_t i = 0; i < a.size(); ++i)
    if (!same(a[i], b[i])) return false;
  return true;
}
bool same(const Circle& a, const Circle& b) { return same(a.center, b.center) && same(a.radius, b.radius); }
bool same(const Ellipse& a, const Ellipse& b) {
  return same(a.center, b.center) && same(a.semi_axes, b.semi_axes) && same(a.angle, b.angle);
}
bool same(const Polygon& a, const Polygon& b) { return same(a.vertices, b.vertices); }
bool same(const NurbsCurve& a, const NurbsCurve& b) {
  return a.degree == b.degree && same(a.knots, b.knots) && same(a.control_points, b.control_points) &&
         same(a.weights, b.weights);
}
bool same(const Sphere& a, const Sphere& b) { return same(a.center, b.center) && same(a.radius, b.radius); }
bool same(const Ellipsoid& a, const Ellipsoid& b) {
  return same(a.center, b.center) && same(a.semi_axes, b.semi_axes) && same(a.rotation, b.rotation);
}
bool same(const Cylinder& a, const Cylinder& b) {
  return same(a.start, b.start) && same(a.end, b.end) && same(a.radius, b.radius);
}
bool same(const StlSurface& a, const StlSurface& b) {
  if (a.triangles.size() != b.triangles.size()) return false;
  for (std::size_t i = 0; i < a.triangles.size(); ++i)
    if (!same(a.triangles[i][0], b.triangles[i][0]) || !same(a.triangles[i][1], b.triangles[i][1]) ||
        !same(a.triangles[i][2], b.triangles[i][2]))
      return false;
  return a.file == b.file && same(a.scale, b.scale) && same(a.rotation, b.rotation) &&
         same(a.translate, b.translate);
}
bool same(const NurbsPatch& a, const NurbsPatch& b) {
  return a.degree == b.degree && same(a.knots_u, b.knots_u) && same(a.knots_v, b.knots_v) &&
         same(a.control_points, b.control_points) && same(a.weights, b.weights);
}
bool same(const NurbsSurface& a, const NurbsSurface& b) {
  return same(a.patches, b.patches) && same(a.scale, b.scale) && same(a.rotation, b.rotation) &&
         same(a.translate, b.translate);
}
bool same(const Shape& a, const Shape& b) {
  if (a.index() != b.index()) return false;
  return std::visit(
      [&](const auto& x) { return same(x, std::get<std::decay_t<decltype(x)>>(b)); }, a);
}
bool same(const Inclusion& a, const Inclusion& b) {
  return a.phase == b.phase && a.levels == b.levels && same(a.shape, b.shape);
}
bool same(const Phase& a, const Phase& b) {
  return a.id == b.id && a.name == b.name && a.is_void == b.is_void;
}
void expect_same_scene(const SceneDesc& a, const SceneDesc& b) {
  EXPECT_EQ(a.dimension, b.dimension);
  EXPECT_TRUE(same(a.domain_min, b.domain_min));
  EXPECT_TRUE(same(a.domain_max, b.domain_max));
  EXPECT_EQ(a.periodic, b.periodic);
  EXPECT_TRUE(same(a.h, b.h));
  EXPECT_EQ(a.levels, b.levels);
  EXPECT_TRUE(same(a.phases, b.phases));
  EXPECT_EQ(a.matrix_phase, b.matrix_phase);
  ASSERT_EQ(a.inclusions.size(), b.inclusions.size());
  for (std::size_t i = 0; i < a.inclusions.size(); ++i)
    EXPECT_TRUE(same(a.inclusions[i], b.inclusions[i])) << "inclusion " << i;
}

TEST(SceneIo, Minimal2dSceneGetsDefaults) {
  const SceneDesc s = parse_scene(R"({
    "format": "cisamr-scene/1", "dimension": 2,
    "domain": {"min": [0, 0], "max": [2, 1]},
    "mesh": {"h": 0.25, "levels": 3},
    "inclusions": [{"shape": "circle", "center": [1, 0.5], "radius": 0.2}]
  })", "mini.json");
  EXPECT_EQ(s.source, "mini.json");
  EXPECT_EQ(s.dimension, 2);
  EXPECT_EQ(s.domain_max[0], 2);
  EXPECT_EQ(s.domain_max[2], 0);
  EXPECT_FALSE(s.any_periodic());
  EXPECT_EQ(s.h, 0.25);
  EXPECT_EQ(s.levels, 3);
  ASSERT_EQ(s.phases.size(), 2u);
  EXPECT_TRUE(same(s.phases[0], Phase{1, "matrix", false}));
  EXPECT_TRUE(same(s.phases[1], Phase{2, "inclusion", false}));
  EXPECT_EQ(s.matrix_phase, 1);
  ASSERT_EQ(s.inclusions.size(), 1u);
  EXPECT_EQ(s.inclusions[0].phase, 2);
  EXPECT_EQ(s.inclusions[0].levels, 3);
  const auto& c = std::get<Circle>(s.inclusions[0].shape);
  EXPECT_EQ(c.center, (Vec2{1, 0.5}));
  EXPECT_EQ(c.radius, 0.2);
}

TEST(SceneIo, Minimal3dSceneGetsDefaults) {
  const SceneDesc s = parse_scene(R"({
    "format": "cisamr-scene/1", "dimension": 3,
    "domain": {"min": [0, 0, 0], "max": [1, 1, 3], "periodic": true},
    "mesh": {"h": 0.1},
    "phases": [{"id": 4}, {"id": 7, "name": "pore", "void": true}],
    "matrix_phase": 4,
    "inclusions": [{"shape": "sphere", "center": [0.5, 0.5, 0.5], "radius": 0.25, "phase": 7, "levels": 2},
                   {"shape": "ellipsoid", "center": [0.5, 0.5, 2], "semi_axes": [0.3, 0.2, 0.1], "phase": 7}]
  })", "");
  EXPECT_EQ(s.dimension, 3);
  EXPECT_TRUE(s.periodic[0] && s.periodic[1] && s.periodic[2]);
  EXPECT_EQ(s.levels, 0);
  ASSERT_EQ(s.phases.size(), 2u);
  EXPECT_TRUE(same(s.phases[0], Phase{4, "phase4", false}));
  EXPECT_TRUE(same(s.phases[1], Phase{7, "pore", true}));
  EXPECT_EQ(s.matrix_phase, 4);
  EXPECT_EQ(s.inclusions[0].levels, 2);
  EXPECT_EQ(s.inclusions[1].levels, 0);
  const auto& e = std::get<Ellipsoid>(s.inclusions[1].shape);
  EXPECT_TRUE(same(e.rotation, Rotation3{{{1, 0, 0}, {0, 1, 0}, {0, 0, 1}}}));
}

TEST(SceneIo, PolygonClosingVertexIsDroppedAndNurbsRead) {
  const SceneDesc s = parse_scene(R"({
    "format": "cisamr-scene/1", "dimension": 2,
    "domain": {"min": [0, 0], "max": [1, 1]}, "mesh": {"h": 0.5},
    "inclusions": [
      {"shape": "polygon", "vertices": [[0.1, 0.1], [0.4, 0.1], [0.2, 0.3], [0.1, 0.1]], "closed": true},
      {"shape": "nurbs", "degree": 2, "knots": [0, 0, 0, 1, 1, 1],
       "control_points": [[0, 0], [1, 0], [0, 1]], "weights": [1, 0.5, 1]},
      {"shape": "ellipse", "center": [0.5, 0.5], "semi_axes": [0.2, 0.1], "angle": 0.5}
    ]})", "s.json");
  EXPECT_EQ(std::get<Polygon>(s.inclusions[0].shape).vertices.size(), 3u);
  const auto& n = std::get<NurbsCurve>(s.inclusions[1].shape);
  EXPECT_EQ(n.degree, 2);
  EXPECT_EQ(n.knots.size(), 6u);
  EXPECT_EQ(n.weights, (std::vector<double>{1, 0.5, 1}));
  EXPECT_EQ(std::get<Ellipse>(s.inclusions[2].shape).angle, 0.5);
}

SceneDesc full_2d_scene() {
  SceneDesc s;
  s.dimension = 2;
  s.domain_min = {-0.1, 1.0 / 3.0, 0};
  s.domain_max = {0.9, 1.0 / 3.0 + 1.0, 0};  // extents 1 and 1 (to rounding): h = 0.1 divides
  s.h = 0.1;
  s.levels = 2;
  s.periodic = {true, true, false};
  s.phases = {{1, "epoxy", false}, {2, "glass fiber", false}, {3, "pore", true}};
  s.matrix_phase = 1;
  s.inclusions.push_back({Circle{{0.123456789012345678, 0.7}, 1e-17 + 0.05}, 2, 3});
  s.inclusions.push_back({Ellipse{{0.3, 0.6}, {0.1, 0.05}, 2.0 / 3.0}, 3, 0});
  s.inclusions.push_back({Polygon{{{0.1, 0.5}, {0.2, 0.5}, {0.15, 0.6 + 1e-12}}}, 2, 2});
  s.inclusions.push_back(
      {NurbsCurve{2, {0, 0, 0, 0.5, 1, 1, 1}, {{0, 0}, {1, 0}, {1, 1}, {0, 1}}, {1, 0.7071067811865476, 1, 1}},
       2, 2});
  s.inclusions.push_back({NurbsCurve{1, {0, 0, 1, 2, 2}, {{0.5, 0.5}, {0.6, 0.5}, {0.55, 0.6}}, {}}, 2, 2});
  return s;
}

const char* const kStlText = R"(solid grain
  facet normal 0 0 1
    outer loop
      vertex 0 0 0
      vertex 1 0 0
      vertex 0 1.5 0
    endloop
  endfacet
  facet normal 0 0 -1
    outer loop
      vertex 0 0 0
      vertex 0 1.5 0
      vertex 1 0 -2e-3
    endloop
  endfacet
endsolid grain
)";
const std::vector<std::array<Vec3, 3>> kStlTriangles = {{{{0, 0, 0}, {1, 0, 0}, {0, 1.5, 0}}},
                                                        {{{0, 0, 0}, {0, 1.5, 0}, {1, 0, -2e-3}}}};

SceneDesc full_3d_scene(const std::string& stl_path) {
  SceneDesc s;
  s.dimension = 3;
  s.domain_min = {0, 0, 0};
  s.domain_max = {100, 50, 25};
  s.h = 12.5;
  s.levels = 1;
  s.phases = {{1, "matrix", false}, {2, "fiber", false}};
  const double c = std::cos(0.3), sn = std::sin(0.3);
  const Rotation3 rz{{{c, -sn, 0}, {sn, c, 0}, {0, 0, 1}}};
  s.inclusions.push_back({Sphere{{50, 25, 12.5}, 6.5}, 2, 2});
  s.inclusions.push_back({Ellipsoid{{20, 30, 10}, {8, 4, 3}, rz}, 2, 1});
  s.inclusions.push_back({Cylinder{{0, 10, 10}, {100, 10, 10.1}, 3.5}, 2, 1});
  s.inclusions.push_back({StlSurface{stl_path, 2.0, rz, {70, 20, 5}, kStlTriangles}, 2, 1});
  NurbsPatch patch;
  patch.degree = {1, 2};
  patch.knots_u = {0, 0, 1, 1};
  patch.knots_v = {0, 0, 0, 1, 1, 1};
  for (int j = 0; j < 3; ++j)
    for (int i = 0; i < 2; ++i) patch.control_points.push_back({i * 1.0, j * 0.1, 0.3});
  patch.weights = {1, 1, 0.5, 0.5, 1, 1};
  NurbsPatch plain = patch;
  plain.weights.clear();
  s.inclusions.push_back({NurbsSurface{{patch, plain}}, 2, 3});
  NurbsSurface placed{{plain}};
  placed.scale = 1.0 / 3.0;
  placed.rotation = rz;
  placed.translate = {50.125, 1e-3 / 7, 12.5};
  s.inclusions.push_back({placed, 2, 0});
  return s;
}

TEST(SceneIo, WriteReadRoundTrip2dIsExact) {
  TempDir dir;
  const SceneDesc original = full_2d_scene();
  write_scene(dir.file("scene.json"), original);
  EXPECT_EQ(dir.entries(), std::vector<std::string>{"scene.json"});
  const SceneDesc back = read_scene(dir.file("scene.json"));
  EXPECT_EQ(back.source, dir.file("scene.json"));
  expect_same_scene(original, back);
  // Writing what was read gives the same text: the format is stable.
  EXPECT_EQ(scene_to_json(back, dir.file("scene.json")), read_text(dir.file("scene.json")));
}

TEST(SceneIo, WriteReadRoundTrip3dIsExactAndStlPathsFollowTheFile) {
  TempDir dir;
  std::filesystem::create_directories(dir.path() / "shapes");
  std::filesystem::create_directories(dir.path() / "out");
  const std::string stl = dir.write("shapes/grain.stl", kStlText);
  const SceneDesc original = full_3d_scene(stl);
  write_scene(dir.file("out/scene.json"), original);
  const std::string text = read_text(dir.file("out/scene.json"));
  EXPECT_NE(text.find("\"../shapes/grain.stl\""), std::string::npos) << text;
  const SceneDesc back = read_scene(dir.file("out/scene.json"));
  expect_same_scene(original, back);
}

TEST(SceneIo, StlFileIsResolvedAgainstTheSceneDirectory) {
  TempDir dir;
  dir.write("grain.stl", kStlText);
  const std::string scene = dir.write("scene.json", R"({
    "format": "cisamr-scene/1", "dimension": 3,
    "domain": {"min": [0, 0, 0], "max": [1, 1, 1]}, "mesh": {"h": 1},
    "inclusions": [{"shape": "stl", "file": "grain.stl"}]})");
  const SceneDesc s = read_scene(scene);
  const auto& stl = std::get<StlSurface>(s.inclusions[0].shape);
  EXPECT_EQ(std::filesystem::path(stl.file), dir.path() / "grain.stl");
  EXPECT_EQ(stl.scale, 1);
  EXPECT_TRUE(same(stl, StlSurface{stl.file, 1, stl.rotation, {0, 0, 0}, kStlTriangles}));
}

TEST(SceneIo, MalformedStlNamesTheStlFile) {
  TempDir dir;
  const std::string stl = dir.write("bad.stl", "solid x\n facet normal 0 0 1\n outer loop\n vertex 0 0\n endloop\n");
  const std::string scene = dir.write("scene.json", R"({
    "format": "cisamr-scene/1", "dimension": 3,
    "domain": {"min": [0, 0, 0], "max": [1, 1, 1]}, "mesh": {"h": 1},
    "inclusions": [{"shape": "stl", "file": "bad.stl"}]})");
  try {
    read_scene(scene);
    FAIL() << "expected InputError";
  } catch (const InputError& e) {
    EXPECT_EQ(std::filesystem::path(e.file()), std::filesystem::path(stl));
    EXPECT_EQ(e.field(), "line 5");
    EXPECT_NE(e.problem().find("expected a number, got 'endloop'"), std::string::npos) << e.what();
  }
}

// ---- malformed scenes ----

struct BadScene {
  const char* name;
  std::string text;
  std::string field;    // expected field, exactly
  std::string problem;  // expected substring of the problem
};

std::string scene2(const std::string& inclusions, const std::string& extra = "") {
  return R"({"format": "cisamr-scene/1", "dimension": 2, "domain": {"min": [0, 0], "max": [1, 1]},
             "mesh": {"h": 0.25})" + extra + R"(, "inclusions": [)" + inclusions + "]}";
}
std::string scene3(const std::string& inclusions) {
  return R"({"format": "cisamr-scene/1", "dimension": 3, "domain": {"min": [0, 0, 0], "max": [1, 1, 1]},
             "mesh": {"h": 0.5}, "inclusions": [)" + inclusions + "]}";
}
const std::string kCircle = R"({"shape": "circle", "center": [0.5, 0.5], "radius": 0.1})";

std::vector<BadScene> bad_scenes() {
  return {
      {"bad JSON", "{\"format\": \"cisamr-scene/1\",\n \"dimension\": 2\n \"mesh\": {}}", "",
       "invalid JSON at line 3, column "},
      {"trailing garbage", scene2(kCircle) + " x", "", "invalid JSON at line 2"},
      {"not an object", "[1, 2]", "", "expected an object"},
      {"missing format", R"({"dimension": 2})", "format", "missing required field"},
      {"wrong format", R"({"format": "cisamr-scene/2"})", "format", "unsupported format 'cisamr-scene/2'"},
      {"dimension 4", R"({"format": "cisamr-scene/1", "dimension": 4})", "dimension", "must be 2 or 3"},
      {"missing mesh.h", R"({"format": "cisamr-scene/1", "dimension": 2,
         "domain": {"min": [0, 0], "max": [1, 1]}, "mesh": {"levels": 1}})", "mesh.h", "missing required field"},
      {"h not a number", R"({"format": "cisamr-scene/1", "dimension": 2,
         "domain": {"min": [0, 0], "max": [1, 1]}, "mesh": {"h": "0.1"}})", "mesh.h", "expected a number, got a string"},
      {"negative h", R"({"format": "cisamr-scene/1", "dimension": 2,
         "domain": {"min": [0, 0], "max": [1, 1]}, "mesh": {"h": -0.1}})", "mesh.h", "must be positive"},
      {"h does not divide", R"({"format": "cisamr-scene/1", "dimension": 2,
         "domain": {"min": [0, 0], "max": [1, 0.9]}, "mesh": {"h": 0.2}})", "mesh.h", "does not divide the domain extent 0.9 along y"},
      {"h larger than domain", R"({"format": "cisamr-scene/1", "dimension": 2,
         "domain": {"min": [0, 0], "max": [1, 1]}, "mesh": {"h": 2}})", "mesh.h", "does not divide"},
      {"levels too high", R"({"format": "cisamr-scene/1", "dimension": 2,
         "domain": {"min": [0, 0], "max": [1, 1]}, "mesh": {"h": 0.5, "levels": 21}})", "mesh.levels", "between 0 and 20"},
      {"domain min >= max", R"({"format": "cisamr-scene/1", "dimension": 2,
         "domain": {"min": [0, 1], "max": [1, 1]}, "mesh": {"h": 0.5}})", "domain.max[1]", "must be greater than domain.min[1]"},
      {"wrong array length", R"({"format": "cisamr-scene/1", "dimension": 3,
         "domain": {"min": [0, 0, 0], "max": [1, 1]}, "mesh": {"h": 0.5}})", "domain.max", "expected an array of 3 numbers, got an array of 2"},
      {"non-numeric coordinate", R"({"format": "cisamr-scene/1", "dimension": 3,
         "domain": {"min": [0, 0, 0], "max": [1, 1, "1"]}, "mesh": {"h": 0.5}})", "domain.max[2]", "expected a number"},
      {"unknown top-level key", R"({"format": "cisamr-scene/1", "dimension": 2, "meshh": {}})", "meshh",
       "unknown key 'meshh' (did you mean 'mesh'?)"},
      {"duplicate phase id", scene2(kCircle, R"(, "phases": [{"id": 1}, {"id": 2}, {"id": 2, "name": "x"}])"),
       "phases[2].id", "duplicate phase id 2 (also phases[1])"},
      {"non-positive phase id", scene2(kCircle, R"(, "phases": [{"id": 0}, {"id": 2}])"), "phases[0].id", "positive"},
      {"phase id not integer", scene2(kCircle, R"(, "phases": [{"id": 1.5}, {"id": 2}])"), "phases[0].id", "expected an integer"},
      {"duplicate phase name", scene2(kCircle, R"(, "phases": [{"id": 1, "name": "a"}, {"id": 2, "name": "a"}])"),
       "phases[1].name", "duplicate phase name 'a'"},
      {"matrix phase unknown", scene2(kCircle, R"(, "matrix_phase": 5)"), "matrix_phase", "phase 5 is not in phases"},
      {"matrix phase void", scene2(kCircle, R"(, "phases": [{"id": 1, "void": true}, {"id": 2}])"), "matrix_phase", "void"},
      {"inclusion phase unknown", scene2(R"({"shape": "circle", "center": [0.5, 0.5], "radius": 0.1, "phase": 9})"),
       "inclusions[0].phase", "phase 9 is not in phases"},
      {"inclusion default phase missing", scene2(kCircle, R"(, "phases": [{"id": 1}, {"id": 3}])"),
       "inclusions[0].phase", "phase 2 (the default) is not in phases"},
      {"inclusion in matrix phase", scene2(R"({"shape": "circle", "center": [0.5, 0.5], "radius": 0.1, "phase": 1})"),
       "inclusions[0].phase", "is the matrix phase"},
      {"inclusion levels negative", scene2(R"({"shape": "circle", "center": [0.5, 0.5], "radius": 0.1, "levels": -1})"),
       "inclusions[0].levels", "between 0 and 20"},
      {"negative radius", scene2(kCircle + R"(, {"shape": "circle", "center": [0.5, 0.5], "radius": -0.1})"),
       "inclusions[1].radius", "must be positive (got -0.1)"},
      {"zero semi-axis", scene2(R"({"shape": "ellipse", "center": [0.5, 0.5], "semi_axes": [0.1, 0]})"),
       "inclusions[0].semi_axes[1]", "must be positive"},
      {"unknown shape", scene2(R"({"shape": "circel", "center": [0.5, 0.5], "radius": 0.1})"),
       "inclusions[0].shape", "unknown shape 'circel'"},
      {"3D shape in 2D", scene2(R"({"shape": "sphere", "center": [0.5, 0.5, 0.5], "radius": 0.1})"),
       "inclusions[0].shape", "shape 'sphere' is 3D but the scene is 2D"},
      {"2D shape in 3D", scene3(R"({"shape": "circle", "center": [0.5, 0.5], "radius": 0.1})"),
       "inclusions[0].shape", "is 2D but the scene is 3D"},
      {"misspelt key", scene2(R"({"shape": "circle", "center": [0.5, 0.5], "raduis": 0.1})"),
       "inclusions[0].raduis", "unknown key 'raduis' (did you mean 'radius'?)"},
      {"missing radius", scene2(R"({"shape": "circle", "center": [0.5, 0.5]})"), "inclusions[0].radius",
       "missing required field"},
      {"duplicate key", scene2(R"({"shape": "circle", "center": [0.5, 0.5], "radius": 0.1, "radius": 0.2})"),
       "inclusions[0].radius", "duplicate key"},
      {"open polygon", scene2(R"({"shape": "polygon", "vertices": [[0, 0], [1, 0], [0, 0]]})"),
       "inclusions[0].vertices", "open polygon"},
      {"polygon closed false", scene2(R"({"shape": "polygon", "vertices": [[0, 0], [1, 0], [0, 1]], "closed": false})"),
       "inclusions[0].closed", "open polygon"},
      {"polygon vertex of 3 numbers", scene2(R"({"shape": "polygon", "vertices": [[0, 0], [1, 0, 0], [0, 1]]})"),
       "inclusions[0].vertices[1]", "expected an array of 2 numbers"},
      {"nurbs degree 0", scene2(R"({"shape": "nurbs", "degree": 0, "knots": [0, 1], "control_points": [[0, 0]]})"),
       "inclusions[0].degree", "between 1 and 30"},
      {"nurbs knots wrong length", scene2(R"({"shape": "nurbs", "degree": 2, "knots": [0, 0, 0, 1, 1],
         "control_points": [[0, 0], [1, 0], [0, 1]]})"), "inclusions[0].knots", "expected 6 knots"},
      {"nurbs knots decreasing", scene2(R"({"shape": "nurbs", "degree": 1, "knots": [0, 0, 2, 1, 3],
         "control_points": [[0, 0], [1, 0], [0, 1]]})"), "inclusions[0].knots[3]", "knots decrease"},
      {"nurbs weight zero", scene2(R"({"shape": "nurbs", "degree": 1, "knots": [0, 0, 1, 2, 2],
         "control_points": [[0, 0], [1, 0], [0, 1]], "weights": [1, 0, 1]})"), "inclusions[0].weights[1]", "must be positive"},
      {"nurbs weight count", scene2(R"({"shape": "nurbs", "degree": 1, "knots": [0, 0, 1, 2, 2],
         "control_points": [[0, 0], [1, 0], [0, 1]], "weights": [1, 1]})"), "inclusions[0].weights", "expected 3 weights"},
      {"rotation not orthonormal", scene3(R"({"shape": "ellipsoid", "center": [0.5, 0.5, 0.5], "semi_axes": [0.1, 0.1, 0.2],
         "rotation": [[1, 0, 0], [0, 1, 0.001], [0, 0, 1]]})"), "inclusions[0].rotation", "not an orthonormal matrix"},
      {"rotation is a reflection", scene3(R"({"shape": "ellipsoid", "center": [0.5, 0.5, 0.5], "semi_axes": [0.1, 0.1, 0.2],
         "rotation": [[1, 0, 0], [0, 1, 0], [0, 0, -1]]})"), "inclusions[0].rotation", "reflection"},
      {"rotation row too short", scene3(R"({"shape": "ellipsoid", "center": [0.5, 0.5, 0.5], "semi_axes": [0.1, 0.1, 0.2],
         "rotation": [[1, 0, 0], [0, 1], [0, 0, 1]]})"), "inclusions[0].rotation[1]", "expected an array of 3 numbers"},
      {"zero-length cylinder", scene3(R"({"shape": "cylinder", "start": [0, 0, 0], "end": [0, 0, 0], "radius": 0.1})"),
       "inclusions[0].end", "length 0"},
      {"stl file missing", scene3(R"({"shape": "stl", "file": "no_such_grain.stl"})"), "inclusions[0].file",
       "cannot read"},
      {"nurbs surface control point count", scene3(R"({"shape": "nurbs_surface", "patches": [
         {"degree": [1, 1], "knots_u": [0, 0, 1, 1], "knots_v": [0, 0, 1, 1],
          "control_points": [[0, 0, 0], [1, 0, 0], [0, 1, 0]]}]})"),
       "inclusions[0].patches[0].control_points", "2 × 2 = 4 points u fastest (from the knots), got 3 points"},
      {"nurbs surface degree pair", scene3(R"({"shape": "nurbs_surface", "patches": [
         {"degree": 1, "knots_u": [0, 0, 1, 1], "knots_v": [0, 0, 1, 1], "control_points": []}]})"),
       "inclusions[0].patches[0].degree", "array of 2 integers"},
      {"inclusions not an array", R"({"format": "cisamr-scene/1", "dimension": 2,
         "domain": {"min": [0, 0], "max": [1, 1]}, "mesh": {"h": 0.5}, "inclusions": {}})",
       "inclusions", "expected an array, got an object"},
  };
}

TEST(SceneIo, MalformedScenesNameTheField) {
  const auto cases = bad_scenes();
  ASSERT_GE(cases.size(), 15u);
  for (const BadScene& c : cases) {
    try {
      parse_scene(c.text, "bad.json");
      ADD_FAILURE() << c.name << ": no error";
    } catch (const InputError& e) {
      EXPECT_EQ(e.file(), "bad.json") << c.name;
      EXPECT_EQ(e.field(), c.field) << c.name << ": " << e.what();
      EXPECT_NE(e.problem().find(c.problem), std::string::npos) << c.name << ": " << e.what();
    }
  }
}

// ---- nurbs_surface: control nets as rows or flat, placement, errors naming the field

// One patch of degree (1, 1) with 3 × 2 control points (from the knots), then `tail`.
const std::string kNurbsKnots = R"("degree": [1, 1], "knots_u": [0, 0, 0.5, 1, 1], "knots_v": [0, 0, 1, 1])";
const std::string kNurbsRows = "[[[0, 0, 0], [1, 0, 0], [2, 0, 0]], [[0, 1, 0], [1, 1, 0], [2, 1, 1]]]";
const std::string kNurbsFlat = "[[0, 0, 0], [1, 0, 0], [2, 0, 0], [0, 1, 0], [1, 1, 0], [2, 1, 1]]";
std::string nurbs_scene(const std::string& tail, const std::string& extra = "") {
  return scene3(R"({"shape": "nurbs_surface")" + extra + R"(, "patches": [{)" + kNurbsKnots + ", " + tail + "}]}");
}
// Two patches, the second with `tail`: errors name patches[1].
std::string nurbs_scene2(const std::string& tail) {
  return scene3(R"({"shape": "nurbs_surface", "patches": [{)" + kNurbsKnots + R"(, "control_points": )" + kNurbsFlat +
                "}, {" + kNurbsKnots + ", " + tail + "}]}");
}

NurbsPatch nurbs_expected(bool weights) {
  NurbsPatch p;
  p.degree = {1, 1};
  p.knots_u = {0, 0, 0.5, 1, 1};
  p.knots_v = {0, 0, 1, 1};
  p.control_points = {{0, 0, 0}, {1, 0, 0}, {2, 0, 0}, {0, 1, 0}, {1, 1, 0}, {2, 1, 1}};
  if (weights) p.weights = {1, 0.5, 1, 0.25, 1, 2};
  return p;
}

TEST(SceneIo, NurbsSurfaceNetsAsRowsOrFlatGiveTheSameDescriptor) {
  const std::string weight_rows = "[[1, 0.5, 1], [0.25, 1, 2]]", weight_flat = "[1, 0.5, 1, 0.25, 1, 2]";
  NurbsSurface expected{{nurbs_expected(true)}};
  for (const std::string& points : {kNurbsRows, kNurbsFlat})
    for (const std::string& weights : {weight_rows, weight_flat}) {
      const SceneDesc s =
          parse_scene(nurbs_scene(R"("control_points": )" + points + R"(, "weights": )" + weights), "n.json");
      ASSERT_EQ(s.inclusions.size(), 1u);
      EXPECT_TRUE(same(std::get<NurbsSurface>(s.inclusions[0].shape), expected)) << points << " " << weights;
    }
  for (const std::string& points : {kNurbsRows, kNurbsFlat}) {  // no weights: all 1
    const SceneDesc s = parse_scene(nurbs_scene(R"("control_points": )" + points), "n.json");
    EXPECT_TRUE(same(std::get<NurbsSurface>(s.inclusions[0].shape), NurbsSurface{{nurbs_expected(false)}}));
  }
}

TEST(SceneIo, NurbsSurfacePlacementRoundTripsAndMovesTheBox) {
  TempDir dir;
  const SceneDesc s = parse_scene(
      nurbs_scene(R"("control_points": )" + kNurbsRows + R"(, "weights": [[1, 0.5, 1], [0.25, 1, 2]])",
                  R"(, "scale": 2, "rotation": [[0, -1, 0], [1, 0, 0], [0, 0, 1]], "translate": [10, 20, 30])"),
      dir.file("scene.json"));
  const auto& n = std::get<NurbsSurface>(s.inclusions[0].shape);
  EXPECT_EQ(n.scale, 2);
  EXPECT_TRUE(same(n.rotation, Rotation3{{{0, -1, 0}, {1, 0, 0}, {0, 0, 1}}}));
  EXPECT_TRUE(same(n.translate, Vec3{10, 20, 30}));
  EXPECT_TRUE(same(n.patches, std::vector<NurbsPatch>{nurbs_expected(true)}));  // the net as read, not placed

  // Written flat with the placement; read back bit for bit; the same text again.
  write_scene(dir.file("out.json"), s);
  const std::string text = read_text(dir.file("out.json"));
  for (const char* key : {"\"scale\": 2", "\"rotation\": [[0", "\"translate\": [10"})
    EXPECT_NE(text.find(key), std::string::npos) << key << "\n" << text;
  const std::size_t net = text.find("\"control_points\": [");
  ASSERT_NE(net, std::string::npos) << text;
  const std::size_t first = text.find_first_not_of(" \n", net + 19);  // the first point, not a row
  EXPECT_EQ(text.substr(first, 2), "[0") << text;
  const SceneDesc back = read_scene(dir.file("out.json"));
  expect_same_scene(s, back);
  EXPECT_EQ(scene_to_json(back, dir.file("out.json")), text);

  // Defaults are not written.
  const SceneDesc plain = parse_scene(nurbs_scene(R"("control_points": )" + kNurbsRows), "");
  const std::string plain_text = scene_to_json(plain, dir.file("plain.json"));
  for (const char* key : {"scale", "rotation", "translate", "weights"})
    EXPECT_EQ(plain_text.find(key), std::string::npos) << key << "\n" << plain_text;

  // The holding box is the placed net's (x' = R·(2x) + t: x' = 10 − 2y, y' = 20 + 2x,
  // z' = 30 + 2z); translating moves the placement, not the net.
  const Box3 box = shape_holding_box(s.inclusions[0].shape);
  EXPECT_TRUE(same(box.min, Vec3{8, 20, 30})) << box.min[0] << " " << box.min[1] << " " << box.min[2];
  EXPECT_TRUE(same(box.max, Vec3{10, 24, 32})) << box.max[0] << " " << box.max[1] << " " << box.max[2];
  const Shape moved = translated(s.inclusions[0].shape, {1, -2, 0.5});
  const auto& m = std::get<NurbsSurface>(moved);
  EXPECT_TRUE(same(m.translate, Vec3{11, 18, 30.5}));
  EXPECT_TRUE(same(m.patches, n.patches));
  EXPECT_TRUE(same(shape_holding_box(moved).min, Vec3{9, 18, 30.5}));
  EXPECT_TRUE(same(shape_holding_box(moved).max, Vec3{11, 22, 32.5}));
}

// The fixtures of data/shapes/make_nurbs.py are scene-ready entries, equal to the shapes of
// tests/support/random_nurbs3.hpp bit for bit, and round-trip.
TEST(SceneIo, NurbsFixturesReadAsTheExactShapes) {
  namespace rn = ::cisamr::testing::nurbs3;
  TempDir dir;
  const auto fixture = [&](const char* name) {
    const std::string entry = read_text(std::string(CISAMR_SOURCE_DIR) + "/data/shapes/" + name);
    EXPECT_FALSE(entry.empty()) << name;
    const SceneDesc s = parse_scene(scene3(entry), name);
    write_scene(dir.file("out.json"), s);
    expect_same_scene(s, read_scene(dir.file("out.json")));
    return std::get<NurbsSurface>(s.inclusions.at(0).shape);
  };
  EXPECT_TRUE(same(fixture("nurbs_sphere.json"), rn::exact_sphere({0, 0, 0}, 1)));
  EXPECT_TRUE(same(fixture("nurbs_torus.json"), rn::exact_torus({0, 0, 0}, 1, 0.3)));
  EXPECT_TRUE(same(fixture("nurbs_cubesphere.json"), rn::cube_sphere({0, 0, 0}, 1)));
  // The two-patch sphere: the one patch's columns 0–4 and 4–8.
  const NurbsSurface two = fixture("nurbs_sphere2.json");
  const NurbsPatch one = rn::exact_sphere({0, 0, 0}, 1).patches[0];
  ASSERT_EQ(two.patches.size(), 2u);
  for (std::size_t h = 0; h < 2; ++h) {
    NurbsPatch half = one;
    half.knots_u = {0, 0, 0, 0.5, 0.5, 1, 1, 1};
    half.control_points.clear();
    half.weights.clear();
    for (std::size_t j = 0; j < 5; ++j)
      for (std::size_t i = 4 * h; i <= 4 * h + 4; ++i) {
        half.control_points.push_back(one.control_points[i + 9 * j]);
        half.weights.push_back(one.weights[i + 9 * j]);
      }
    EXPECT_TRUE(same(two.patches[h], half)) << h;
  }
}

std::vector<BadScene> bad_nurbs_surfaces() {
  const std::string rows = R"("control_points": )" + kNurbsRows;
  return {
      {"no patches", scene3(R"({"shape": "nurbs_surface", "patches": []})"), "inclusions[0].patches",
       "needs at least one patch"},
      {"degree 31", scene3(R"({"shape": "nurbs_surface", "patches": [{"degree": [1, 31], "knots_u": [0, 0, 1, 1],
         "knots_v": [0, 0, 1, 1], "control_points": []}]})"), "inclusions[0].patches[0].degree[1]", "between 1 and 30"},
      {"too few knots", scene3(R"({"shape": "nurbs_surface", "patches": [{"degree": [2, 1], "knots_u": [0, 0, 1, 1],
         "knots_v": [0, 0, 1, 1], "control_points": []}]})"), "inclusions[0].patches[0].knots_u",
       "a degree-2 direction needs at least 6 knots, got 4"},
      {"decreasing knots", scene3(R"({"shape": "nurbs_surface", "patches": [{"degree": [1, 1], "knots_u": [0, 0, 1, 1],
         "knots_v": [0, 0, 0.5, 0.25, 1, 1], "control_points": []}]})"), "inclusions[0].patches[0].knots_v[3]",
       "knots decrease (0.25 after 0.5)"},
      {"empty parameter range", scene3(R"({"shape": "nurbs_surface", "patches": [{"degree": [1, 1], "knots_u": [0, 0, 0, 0],
         "knots_v": [0, 0, 1, 1], "control_points": []}]})"), "inclusions[0].patches[0].knots_u", "empty parameter range"},
      {"missing net", nurbs_scene(R"("weights": [1, 1, 1, 1, 1, 1])"), "inclusions[0].patches[0].control_points",
       "missing required field"},
      {"net not an array", nurbs_scene(R"("control_points": {})"), "inclusions[0].patches[0].control_points",
       "expected an array, got an object"},
      {"too few rows", nurbs_scene(R"("control_points": [[[0, 0, 0], [1, 0, 0], [2, 0, 0]]])"),
       "inclusions[0].patches[0].control_points", "expected 2 rows of 3 points (from the knots), got 1 row"},
      {"too few rows, second patch", nurbs_scene2(R"("control_points": [[[0, 0, 0], [1, 0, 0], [2, 0, 0]]])"),
       "inclusions[0].patches[1].control_points", "expected 2 rows of 3 points (from the knots), got 1 row"},
      {"too many rows", nurbs_scene(R"("control_points": [[[0, 0, 0]], [[0, 0, 0]], [[0, 0, 0]]])"),
       "inclusions[0].patches[0].control_points", "expected 2 rows of 3 points (from the knots), got 3 rows"},
      {"short row", nurbs_scene(R"("control_points": [[[0, 0, 0], [1, 0, 0], [2, 0, 0]], [[0, 1, 0], [1, 1, 0]]])"),
       "inclusions[0].patches[0].control_points[1]", "expected a row of 3 points (from the knots), got 2"},
      {"row not an array", nurbs_scene(R"("control_points": [[[0, 0, 0], [1, 0, 0], [2, 0, 0]], 5])"),
       "inclusions[0].patches[0].control_points[1]", "expected a row of 3 points, got a number"},
      {"bad point in a row", nurbs_scene(R"("control_points": [[[0, 0, 0], [1, 0, 0], [2, 0, 0]], [[0, 1, 0], [1, 1], [2, 1, 1]]])"),
       "inclusions[0].patches[0].control_points[1][1]", "expected an array of 3 numbers, got an array of 2"},
      {"bad coordinate in a row", nurbs_scene2(R"("control_points": [[[0, 0, 0], [1, 0, 0], [2, 0, 0]], [[0, 1, 0], [1, 1, 0], [2, "1", 1]]])"),
       "inclusions[0].patches[1].control_points[1][2][1]", "expected a number, got a string"},
      {"flat list too short", nurbs_scene(R"("control_points": [[0, 0, 0], [1, 0, 0], [2, 0, 0], [0, 1, 0], [1, 1, 0]])"),
       "inclusions[0].patches[0].control_points", "expected 2 rows of 3 points, or 3 × 2 = 6 points u fastest (from the knots), got 5 points"},
      {"bad point in the flat list", nurbs_scene(R"("control_points": [[0, 0, 0], [1, 0, 0], [2, 0, 0], [0, 1, 0], [1, 1], [2, 1, 1]])"),
       "inclusions[0].patches[0].control_points[4]", "expected an array of 3 numbers, got an array of 2"},
      {"too few weight rows", nurbs_scene(rows + R"(, "weights": [[1, 1, 1]])"), "inclusions[0].patches[0].weights",
       "expected 2 rows of 3 numbers (from the knots), got 1 row"},
      {"short weight row", nurbs_scene(rows + R"(, "weights": [[1, 1, 1], [1, 1]])"), "inclusions[0].patches[0].weights[1]",
       "expected a row of 3 numbers (from the knots), got 2"},
      {"weight row not an array", nurbs_scene(rows + R"(, "weights": [[1, 1, 1], 1])"), "inclusions[0].patches[0].weights[1]",
       "expected a row of 3 numbers, got a number"},
      {"zero weight in a row", nurbs_scene2(rows + R"(, "weights": [[1, 1, 1], [1, 0, 1]])"),
       "inclusions[0].patches[1].weights[1][1]", "must be positive (got 0)"},
      {"weight not a number", nurbs_scene(rows + R"(, "weights": [[1, 1, 1], [1, 1, null]])"),
       "inclusions[0].patches[0].weights[1][2]", "expected a number, got null"},
      {"weight overflow", nurbs_scene(rows + R"(, "weights": [[1, 1, 1], [1, 1, 1e400]])"),
       "inclusions[0].patches[0].weights[1][2]", "number overflow"},
      {"negative weight in the flat list", nurbs_scene(rows + R"(, "weights": [1, 1, 1, 1, -2, 1])"),
       "inclusions[0].patches[0].weights[4]", "must be positive (got -2)"},
      {"flat weights too many", nurbs_scene(rows + R"(, "weights": [1, 1, 1, 1, 1, 1, 1])"), "inclusions[0].patches[0].weights",
       "expected 2 rows of 3 numbers, or 3 × 2 = 6 numbers u fastest (from the knots), got 7 numbers"},
      {"misspelt patch key", nurbs_scene(rows + R"(, "weight": [1, 1, 1, 1, 1, 1])"), "inclusions[0].patches[0].weight",
       "unknown key 'weight' (did you mean 'weights'?)"},
      {"zero scale", nurbs_scene(rows, R"(, "scale": 0)"), "inclusions[0].scale", "must be positive (got 0)"},
      {"scale not a number", nurbs_scene(rows, R"(, "scale": [2])"), "inclusions[0].scale", "expected a number"},
      {"rotation not orthonormal", nurbs_scene(rows, R"(, "rotation": [[1, 0, 0], [0, 2, 0], [0, 0, 1]])"),
       "inclusions[0].rotation", "not an orthonormal matrix"},
      {"rotation a reflection", nurbs_scene(rows, R"(, "rotation": [[0, 1, 0], [1, 0, 0], [0, 0, 1]])"),
       "inclusions[0].rotation", "reflection"},
      {"translate of 2 numbers", nurbs_scene(rows, R"(, "translate": [1, 2])"), "inclusions[0].translate",
       "expected an array of 3 numbers, got an array of 2"},
      {"misspelt inclusion key", nurbs_scene(rows, R"(, "translates": [1, 2, 3])"), "inclusions[0].translates",
       "unknown key 'translates' (did you mean 'translate'?)"},
  };
}

TEST(SceneIo, MalformedNurbsSurfacesNameTheField) {
  for (const BadScene& c : bad_nurbs_surfaces()) {
    try {
      parse_scene(c.text, "bad.json");
      ADD_FAILURE() << c.name << ": no error";
    } catch (const InputError& e) {
      EXPECT_EQ(e.file(), "bad.json") << c.name;
      EXPECT_EQ(e.field(), c.field) << c.name << ": " << e.what();
      EXPECT_NE(e.problem().find(c.problem), std::string::npos) << c.name << ": " << e.what();
      EXPECT_EQ(std::string(e.what()).find('\n'), std::string::npos) << c.name;
    }
  }
}

TEST(SceneIo, UnreadableFileIsInputError) {
  TempDir dir;
  const std::string missing = dir.file("nope.json");
  try {
    read_scene(missing);
    FAIL() << "expected InputError";
  } catch (const InputError& e) {
    EXPECT_EQ(e.file(), missing);
    EXPECT_EQ(e.field(), "");
    EXPECT_NE(e.problem().find("cannot read"), std::string::npos);
  }
  EXPECT_THROW(read_scene(dir.path().string()), InputError);  // a directory
}

TEST(SceneIo, IntegralFloatsAreAcceptedAsIntegers) {
  const SceneDesc s = parse_scene(scene2(kCircle, R"(, "matrix_phase": 1.0)"), "");
  EXPECT_EQ(s.matrix_phase, 1);
}

// ---- input that must be refused, not followed (found by fuzzing) ----

InputError scene_error(const std::string& json, const std::string& source = "s.json") {
  try {
    parse_scene(json, source);
  } catch (const InputError& e) {
    return e;
  }
  return InputError(source, "", "no error");
}

TEST(SceneIo, NumbersBeyondTheDoubleRangeNameTheField) {
  const InputError e = scene_error(scene2(R"({"shape": "circle", "center": [0.5, 0.5], "radius": 1e400})"));
  EXPECT_EQ(e.field(), "inclusions[0].radius") << e.what();
  EXPECT_NE(e.problem().find("number overflow"), std::string::npos) << e.what();
  EXPECT_EQ(scene_error(scene2(kCircle, R"(, "matrix_phase": -1e999)")).field(), "matrix_phase");
}

TEST(SceneIo, ErrorsAreOneLineOfText) {
  // nlohmann quotes what it last read: binary bytes, control characters, a long run.
  for (const std::string& json : {std::string("{\"format\": \x01\xff}"), std::string(9000, '[') + "x",
                                  std::string("{\"a\n\tb\": 1}")}) {
    const std::string what = scene_error(json, "dir/line\nbreak.json").what();
    EXPECT_EQ(what.find('\n'), std::string::npos) << what;
    EXPECT_EQ(what.find('\t'), std::string::npos) << what;
    EXPECT_EQ(what.find('\x01'), std::string::npos) << what;
    EXPECT_EQ(what.find('\xff'), std::string::npos) << what;
    EXPECT_LT(what.size(), 400u) << what;
    EXPECT_EQ(what.rfind("dir/line\\nbreak.json: ", 0), 0u) << what;
  }
}

TEST(SceneIo, BaseCellsAreBoundedBeforeAnyGrid) {
  const InputError e = scene_error(R"({"format": "cisamr-scene/1", "dimension": 3,
      "domain": {"min": [0, 0, 0], "max": [1e6, 1e6, 1e6]}, "mesh": {"h": 0.5}, "inclusions": []})");
  EXPECT_EQ(e.field(), "mesh.h") << e.what();
  EXPECT_NE(e.problem().find("base cells"), std::string::npos) << e.what();
}

TEST(SceneIo, NonRegularFilesAreRefusedNotRead) {
  TempDir dir;
  const std::string fifo = dir.file("pipe");
  ASSERT_EQ(::mkfifo(fifo.c_str(), 0600), 0);
  // A FIFO blocks until a writer comes and /dev/zero never ends: both must fail at once.
  for (const std::string& file : {fifo, std::string("/dev/zero"), dir.path().string()}) {
    try {
      read_scene(file);
      ADD_FAILURE() << file;
    } catch (const InputError& e) {
      EXPECT_NE(e.problem().find("cannot read"), std::string::npos) << e.what();
    }
    const std::string scene = dir.write("stl.json", scene3(R"({"shape": "stl", "file": ")" + file + R"("})"));
    try {
      read_scene(scene);
      ADD_FAILURE() << file;
    } catch (const InputError& e) {
      EXPECT_EQ(e.field(), "inclusions[0].file") << e.what();
    }
    EXPECT_THROW(read_stl(file), InputError) << file;
  }
}

// A `step` entry is one inclusion per selected solid (issue #14: "every solid in the file is
// an inclusion"), each named by its entry and solid; a scene written back lists them one by
// one and reads back the same.
TEST(SceneIo, StepEntriesBecomeOneInclusionPerSolid) {
  if (!geometry::step_import_available()) GTEST_SKIP() << "built with CISAMR_WITH_OCCT=OFF";
  TempDir dir;
  const std::string parts = std::string(CISAMR_SOURCE_DIR) + "/data/shapes/parts.step";
  const std::string path = dir.write("scene.json", R"({"format": "cisamr-scene/1", "dimension": 3,
    "domain": {"min": [0, 0, 0], "max": [2, 1, 1]}, "mesh": {"h": 0.1, "levels": 1},
    "phases": [{"id": 1, "name": "matrix"}, {"id": 2, "name": "particle"}, {"id": 3, "name": "ball"}],
    "inclusions": [{"shape": "step", "file": ")" + parts + R"(", "scale": 0.05, "translate": [0.2, 0.5, 0.5], "phase": 2},
                   {"shape": "sphere", "center": [1.5, 0.5, 0.5], "radius": 0.1, "phase": 3},
                   {"shape": "step", "file": ")" + parts + R"(", "solids": [1], "scale": 0.05, "translate": [0.2, 0.2, 0.2]}]})");
  const SceneDesc s = read_scene(path);
  ASSERT_EQ(s.inclusions.size(), 5u);
  const std::vector<std::vector<int>> solids = {{0}, {1}, {2}, {}, {1}};
  for (std::size_t k = 0; k < 5; ++k) {
    const auto* st = std::get_if<StepSolids>(&s.inclusions[k].shape);
    ASSERT_EQ(st != nullptr, k != 3) << k;
    if (st != nullptr) {
      EXPECT_EQ(st->solids, solids[k]) << k;
      EXPECT_TRUE(st->brep != nullptr);
    }
  }
  EXPECT_EQ(s.inclusions[2].phase, 2);
  EXPECT_EQ(s.entry, (std::vector<std::int32_t>{0, 0, 0, 1, 2}));
  EXPECT_EQ(s.entry_solid, (std::vector<std::int32_t>{0, 1, 2, -1, -1}));
  EXPECT_EQ(inclusion_field(s, 2), "inclusions[0] (solid 2)");
  EXPECT_EQ(inclusion_field(s, 3), "inclusions[1]");
  EXPECT_EQ(inclusion_field(s, 4), "inclusions[2]");
  // Written back: five entries, each of one solid, read back as they are.
  write_scene(dir.file("back.json"), s);
  const SceneDesc back = read_scene(dir.file("back.json"));
  ASSERT_EQ(back.inclusions.size(), 5u);
  EXPECT_EQ(back.entry, (std::vector<std::int32_t>{0, 1, 2, 3, 4}));
  for (std::size_t k = 0; k < 5; ++k)
    if (const auto* st = std::get_if<StepSolids>(&back.inclusions[k].shape)) EXPECT_EQ(st->solids, solids[k]) << k;
}

}  // namespace
}  // namespace cisamr::io
