#include "io/scene_io.hpp"

#include <algorithm>
#include <charconv>
#include <cmath>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <limits>
#include <nlohmann/json.hpp>
#include <set>
#include <string_view>

#include "core/error.hpp"
#include "core/input_file.hpp"
#include "io/atomic_file.hpp"
#include "io/stl_io.hpp"

namespace cisamr::io {
namespace {

using nlohmann::json;
using namespace geometry;
namespace fs = std::filesystem;

constexpr int kMaxLevels = 20;
constexpr std::size_t kMaxPhases = 64;  // PhaseMask has 64 bits
constexpr double kDivisionTolerance = 1e-9;
constexpr double kRotationTolerance = 1e-9;
// Lengths the mesher handles (domain coordinates, extents, h): it meshes alike from 1e-60
// to 1e60; near 1e±100 products of lengths in the quality measures leave the double range.
constexpr double kMinLength = 1e-30, kMaxLength = 1e30;
// Base grid cells (domain extent / h per axis, multiplied): 2^40, beyond any memory.
constexpr double kMaxBaseCells = 1099511627776.0;

// Shortest text that reads back to the same double.
std::string number_text(double value) {
  char buffer[32];
  const auto result = std::to_chars(buffer, buffer + sizeof buffer, value);
  return std::string(buffer, result.ptr);
}

std::string join(const std::string& path, std::string_view key) {
  return path.empty() ? std::string(key) : path + "." + std::string(key);
}
std::string index(const std::string& path, std::size_t i) {
  return path + "[" + std::to_string(i) + "]";
}

std::size_t edit_distance(std::string_view a, std::string_view b) {
  std::vector<std::size_t> row(b.size() + 1);
  for (std::size_t j = 0; j <= b.size(); ++j) row[j] = j;
  for (std::size_t i = 1; i <= a.size(); ++i) {
    std::size_t diagonal = row[0];
    row[0] = i;
    for (std::size_t j = 1; j <= b.size(); ++j) {
      const std::size_t above = row[j];
      row[j] = std::min({row[j] + 1, row[j - 1] + 1, diagonal + (a[i - 1] != b[j - 1])});
      diagonal = above;
    }
  }
  return row[b.size()];
}

std::string list_text(const std::vector<std::string_view>& names) {
  std::string text;
  for (std::size_t i = 0; i < names.size(); ++i) {
    if (i > 0) text += ", ";
    text += names[i];
  }
  return text;
}

// Finds keys that appear twice in one object: nlohmann keeps the last silently, which
// would hide a typo such as two "radius" entries. Builds the field path as it goes.
struct DuplicateKeyFinder {
  struct Frame {
    bool is_object = false;
    std::set<std::string> keys;
    std::string key;
    std::size_t index = 0;
  };
  std::vector<Frame> stack;
  std::string duplicate_field;  // empty while none found

  // Where the parser is: the field whose value is being read ("inclusions[2].radius").
  std::string current_field() const {
    std::string text;
    for (const Frame& frame : stack) text = frame.is_object ? join(text, frame.key) : index(text, frame.index);
    return text;
  }
  std::string path() const {
    std::string text;
    for (std::size_t i = 0; i < stack.size(); ++i) {
      if (i + 1 == stack.size() && stack[i].is_object) break;  // the key being added
      if (stack[i].is_object)
        text = join(text, stack[i].key);
      else
        text = index(text, stack[i].index);
    }
    return text;
  }
  void element_done() {
    if (!stack.empty() && !stack.back().is_object) ++stack.back().index;
  }
  bool operator()(int, json::parse_event_t event, json& parsed) {
    switch (event) {
      case json::parse_event_t::object_start: stack.push_back({true, {}, {}, 0}); break;
      case json::parse_event_t::array_start: stack.push_back({false, {}, {}, 0}); break;
      case json::parse_event_t::object_end:
      case json::parse_event_t::array_end:
        stack.pop_back();
        element_done();
        break;
      case json::parse_event_t::key: {
        const std::string key = parsed.get<std::string>();
        if (!stack.back().keys.insert(key).second && duplicate_field.empty())
          duplicate_field = join(path(), key);
        stack.back().key = key;
        break;
      }
      case json::parse_event_t::value: element_done(); break;
    }
    return true;
  }
};

// The checks shared by every field: each takes the value and its field path and returns
// the converted value or throws InputError naming that path.
// Why an STL file cannot be read ("" when it can be opened), as the scene reader words it.
std::string stl_file_problem(const std::string& file) {
  std::error_code ec;
  if (fs::is_directory(file, ec)) return "'" + file + "' is a directory";
  // A FIFO would block the probe below and a device such as /dev/zero never ends.
  if (fs::exists(file, ec) && !fs::is_regular_file(file, ec)) return "'" + file + "' is not a regular file";
  std::ifstream probe(file, std::ios::binary);
  if (!probe) return "cannot read '" + file + "': " + std::strerror(errno);
  return "";
}

// nlohmann's message without its prefix and without the bytes it quotes ("last read: ...",
// which may be long or binary), at most 200 characters.
std::string json_problem(const json::exception& e) {
  std::string detail = e.what();
  // "[json.exception.parse_error.101] parse error at line 1, column 2: syntax error ..."
  if (const auto p = detail.find("] "); p != std::string::npos) detail = detail.substr(p + 2);
  if (detail.rfind("parse error", 0) == 0)
    if (const auto p = detail.find(": "); p != std::string::npos) detail = detail.substr(p + 2);
  if (const auto p = detail.find("; last read"); p != std::string::npos) detail.resize(p);
  if (detail.size() > 200) detail = detail.substr(0, 200) + "...";
  return detail;
}

class SceneReader {
 public:
  SceneReader(std::string file, fs::path base_directory)
      : file_(std::move(file)), base_directory_(std::move(base_directory)) {}
  SceneReader(std::string file, fs::path base_directory, const ReadSceneOptions& options)
      : file_(std::move(file)), base_directory_(std::move(base_directory)), load_stl_(options.load_stl),
        probe_stl_(options.probe_stl) {}

  [[noreturn]] void fail(const std::string& field, const std::string& problem) const {
    throw InputError(file_, field, problem);
  }

  static std::string type_text(const json& v) {
    if (v.is_number()) return "a number";
    if (v.is_string()) return "a string";
    if (v.is_boolean()) return "a boolean";
    if (v.is_null()) return "null";
    if (v.is_array()) return "an array";
    return "an object";
  }

  void expect_object(const json& v, const std::string& field) const {
    if (!v.is_object()) fail(field, "expected an object, got " + type_text(v));
  }
  void expect_array(const json& v, const std::string& field) const {
    if (!v.is_array()) fail(field, "expected an array, got " + type_text(v));
  }

  // Every key of `object` must be in `allowed`.
  void check_keys(const json& object, const std::string& field,
                  const std::vector<std::string_view>& allowed) const {
    for (const auto& item : object.items()) {
      const std::string& key = item.key();
      if (std::find(allowed.begin(), allowed.end(), key) != allowed.end()) continue;
      std::string problem = "unknown key '" + key + "'";
      std::string_view best;
      std::size_t best_distance = 3;
      for (std::string_view candidate : allowed) {
        const std::size_t d = edit_distance(key, candidate);
        if (d < best_distance) best_distance = d, best = candidate;
      }
      if (!best.empty())
        problem += " (did you mean '" + std::string(best) + "'?)";
      else
        problem += " (allowed: " + list_text(allowed) + ")";
      fail(join(field, key), problem);
    }
  }

  const json* member(const json& object, std::string_view key) const {
    const auto it = object.find(key);
    return it == object.end() ? nullptr : &*it;
  }
  const json& required(const json& object, const std::string& field,
                       std::string_view key) const {
    const json* v = member(object, key);
    if (!v) fail(join(field, key), "missing required field");
    return *v;
  }

  double number(const json& v, const std::string& field) const {
    if (!v.is_number()) fail(field, "expected a number, got " + type_text(v));
    const double x = v.get<double>();
    if (!std::isfinite(x)) fail(field, "must be finite");
    return x;
  }
  double positive(const json& v, const std::string& field) const {
    const double x = number(v, field);
    if (!(x > 0)) fail(field, "must be positive (got " + number_text(x) + ")");
    return x;
  }
  long long integer(const json& v, const std::string& field) const {
    if (v.is_number_integer()) {
      if (v.is_number_unsigned() && v.get<unsigned long long>() >
                                        static_cast<unsigned long long>(
                                            std::numeric_limits<int>::max()))
        fail(field, "integer too large");
      const long long x = v.get<long long>();
      if (x < std::numeric_limits<int>::min() || x > std::numeric_limits<int>::max())
        fail(field, "integer out of range");
      return x;
    }
    if (v.is_number_float()) {  // accept 2.0, not 2.5
      const double x = v.get<double>();
      if (std::isfinite(x) && x == std::floor(x) && std::abs(x) < 2147483647.0)
        return static_cast<long long>(x);
      fail(field, "expected an integer, got " + number_text(x));
    }
    fail(field, "expected an integer, got " + type_text(v));
  }
  int integer_in(const json& v, const std::string& field, int lo, int hi) const {
    const long long x = integer(v, field);
    if (x < lo || x > hi)
      fail(field, "must be between " + std::to_string(lo) + " and " + std::to_string(hi) +
                      " (got " + std::to_string(x) + ")");
    return static_cast<int>(x);
  }
  bool boolean(const json& v, const std::string& field) const {
    if (!v.is_boolean()) fail(field, "expected true or false, got " + type_text(v));
    return v.get<bool>();
  }
  std::string string(const json& v, const std::string& field) const {
    if (!v.is_string()) fail(field, "expected a string, got " + type_text(v));
    return v.get<std::string>();
  }

  template <int N>
  Vec<N> vec(const json& v, const std::string& field) const {
    if (!v.is_array() || v.size() != N)
      fail(field, "expected an array of " + std::to_string(N) + " numbers, got " +
                      (v.is_array() ? "an array of " + std::to_string(v.size())
                                    : type_text(v)));
    Vec<N> result;
    for (int d = 0; d < N; ++d) result[d] = number(v[d], index(field, d));
    return result;
  }
  template <int N>
  Vec<N> positive_vec(const json& v, const std::string& field) const {
    const Vec<N> result = vec<N>(v, field);
    for (int d = 0; d < N; ++d)
      if (!(result[d] > 0))
        fail(index(field, d), "must be positive (got " + number_text(result[d]) + ")");
    return result;
  }
  template <int N>
  std::vector<Vec<N>> points(const json& v, const std::string& field) const {
    expect_array(v, field);
    std::vector<Vec<N>> result;
    result.reserve(v.size());
    for (std::size_t i = 0; i < v.size(); ++i) result.push_back(vec<N>(v[i], index(field, i)));
    return result;
  }
  std::vector<double> numbers(const json& v, const std::string& field) const {
    expect_array(v, field);
    std::vector<double> result;
    result.reserve(v.size());
    for (std::size_t i = 0; i < v.size(); ++i) result.push_back(number(v[i], index(field, i)));
    return result;
  }

  Rotation3 rotation(const json& v, const std::string& field) const {
    if (!v.is_array() || v.size() != 3)
      fail(field, "expected a 3×3 matrix (an array of 3 rows of 3 numbers)");
    Rotation3 r;
    for (int i = 0; i < 3; ++i) r[i] = vec<3>(v[i], index(field, i));
    double worst = 0;  // largest entry of R·Rᵀ − I
    for (int i = 0; i < 3; ++i)
      for (int j = 0; j < 3; ++j) {
        double dot = 0;
        for (int k = 0; k < 3; ++k) dot += r[i][k] * r[j][k];
        worst = std::max(worst, std::abs(dot - (i == j ? 1.0 : 0.0)));
      }
    if (worst > kRotationTolerance)
      fail(field, "not an orthonormal matrix (R·Rᵀ differs from I by " + number_text(worst) +
                      ")");
    const double det = r[0][0] * (r[1][1] * r[2][2] - r[1][2] * r[2][1]) -
                       r[0][1] * (r[1][0] * r[2][2] - r[1][2] * r[2][0]) +
                       r[0][2] * (r[1][0] * r[2][1] - r[1][1] * r[2][0]);
    if (det < 0) fail(field, "a reflection (determinant −1), not a rotation");
    return r;
  }

  // Non-decreasing knots with a non-empty parameter range; returns them.
  std::vector<double> knots(const json& v, const std::string& field, int degree,
                            std::size_t expected_count) const {
    std::vector<double> k = numbers(v, field);
    if (expected_count != 0 && k.size() != expected_count)
      fail(field, "expected " + std::to_string(expected_count) +
                      " knots (control points + degree + 1), got " + std::to_string(k.size()));
    for (std::size_t i = 1; i < k.size(); ++i)
      if (k[i] < k[i - 1])
        fail(index(field, i), "knots decrease (" + number_text(k[i]) + " after " +
                                  number_text(k[i - 1]) + ")");
    const std::size_t first = static_cast<std::size_t>(degree);
    const std::size_t last = k.size() - 1 - static_cast<std::size_t>(degree);
    if (!(k[first] < k[last])) fail(field, "the knots leave an empty parameter range");
    return k;
  }
  std::vector<double> weights(const json* v, const std::string& field,
                              std::size_t expected_count) const {
    if (!v) return {};
    std::vector<double> w = numbers(*v, field);
    if (w.size() != expected_count)
      fail(field, "expected " + std::to_string(expected_count) +
                      " weights (one per control point), got " + std::to_string(w.size()));
    for (std::size_t i = 0; i < w.size(); ++i)
      if (!(w[i] > 0)) fail(index(field, i), "must be positive (got " + number_text(w[i]) + ")");
    return w;
  }

  Shape shape_2d(const std::string& name, const json& object, const std::string& field) const {
    if (name == "circle") {
      check_keys(object, field, {"shape", "phase", "levels", "center", "radius"});
      Circle c;
      c.center = vec<2>(required(object, field, "center"), join(field, "center"));
      c.radius = positive(required(object, field, "radius"), join(field, "radius"));
      return c;
    }
    if (name == "ellipse") {
      check_keys(object, field, {"shape", "phase", "levels", "center", "semi_axes", "angle"});
      Ellipse e;
      e.center = vec<2>(required(object, field, "center"), join(field, "center"));
      e.semi_axes =
          positive_vec<2>(required(object, field, "semi_axes"), join(field, "semi_axes"));
      if (const json* a = member(object, "angle")) e.angle = number(*a, join(field, "angle"));
      return e;
    }
    if (name == "polygon") {
      check_keys(object, field, {"shape", "phase", "levels", "vertices", "closed"});
      if (const json* closed = member(object, "closed"))
        if (!boolean(*closed, join(field, "closed")))
          fail(join(field, "closed"), "open polygon: an inclusion must be a closed region");
      Polygon p;
      const std::string vertices_field = join(field, "vertices");
      p.vertices = points<2>(required(object, field, "vertices"), vertices_field);
      // A repeated first vertex at the end (GeoJSON style) closes the ring explicitly.
      if (p.vertices.size() > 1 && p.vertices.front() == p.vertices.back()) p.vertices.pop_back();
      if (p.vertices.size() < 3)
        fail(vertices_field, "open polygon: needs at least 3 distinct vertices, got " +
                                 std::to_string(p.vertices.size()));
      return p;
    }
    check_keys(object, field,
               {"shape", "phase", "levels", "degree", "knots", "control_points", "weights"});
    NurbsCurve n;
    n.degree = integer_in(required(object, field, "degree"), join(field, "degree"), 1, 30);
    const std::string points_field = join(field, "control_points");
    n.control_points = points<2>(required(object, field, "control_points"), points_field);
    const std::size_t count = n.control_points.size();
    if (count < static_cast<std::size_t>(n.degree) + 1)
      fail(points_field, "a degree-" + std::to_string(n.degree) + " curve needs at least " +
                             std::to_string(n.degree + 1) + " control points, got " +
                             std::to_string(count));
    n.knots = knots(required(object, field, "knots"), join(field, "knots"), n.degree,
                    count + n.degree + 1);
    n.weights = weights(member(object, "weights"), join(field, "weights"), count);
    return n;
  }

  NurbsPatch patch(const json& object, const std::string& field) const {
    expect_object(object, field);
    check_keys(object, field, {"degree", "knots_u", "knots_v", "control_points", "weights"});
    NurbsPatch p;
    const std::string degree_field = join(field, "degree");
    const json& degree = required(object, field, "degree");
    if (!degree.is_array() || degree.size() != 2)
      fail(degree_field, "expected an array of 2 integers (degree in u and v)");
    std::array<std::size_t, 2> counts{};
    for (int a = 0; a < 2; ++a) {
      p.degree[a] = integer_in(degree[a], index(degree_field, a), 1, 30);
      const char* key = a == 0 ? "knots_u" : "knots_v";
      const std::string knots_field = join(field, key);
      const json& k = required(object, field, key);
      expect_array(k, knots_field);
      const std::size_t minimum = 2 * static_cast<std::size_t>(p.degree[a] + 1);
      if (k.size() < minimum)
        fail(knots_field, "a degree-" + std::to_string(p.degree[a]) + " direction needs at least " +
                              std::to_string(minimum) + " knots, got " + std::to_string(k.size()));
      (a == 0 ? p.knots_u : p.knots_v) = knots(k, knots_field, p.degree[a], 0);
      counts[a] = k.size() - static_cast<std::size_t>(p.degree[a]) - 1;
    }
    const std::string points_field = join(field, "control_points");
    p.control_points = points<3>(required(object, field, "control_points"), points_field);
    const std::size_t expected = counts[0] * counts[1];
    if (p.control_points.size() != expected)
      fail(points_field, "the knot vectors give " + std::to_string(counts[0]) + " × " +
                             std::to_string(counts[1]) + " = " + std::to_string(expected) +
                             " control points (u fastest), got " +
                             std::to_string(p.control_points.size()));
    p.weights = weights(member(object, "weights"), join(field, "weights"), expected);
    return p;
  }

  std::string resolve(const std::string& file) const {
    fs::path p(file);
    if (p.is_relative()) p = base_directory_ / p;
    return fs::absolute(p).lexically_normal().string();
  }

  Shape shape_3d(const std::string& name, const json& object, const std::string& field) const {
    if (name == "sphere") {
      check_keys(object, field, {"shape", "phase", "levels", "center", "radius"});
      Sphere s;
      s.center = vec<3>(required(object, field, "center"), join(field, "center"));
      s.radius = positive(required(object, field, "radius"), join(field, "radius"));
      return s;
    }
    if (name == "ellipsoid") {
      check_keys(object, field,
                 {"shape", "phase", "levels", "center", "semi_axes", "rotation"});
      Ellipsoid e;
      e.center = vec<3>(required(object, field, "center"), join(field, "center"));
      e.semi_axes =
          positive_vec<3>(required(object, field, "semi_axes"), join(field, "semi_axes"));
      if (const json* r = member(object, "rotation")) e.rotation = rotation(*r, join(field, "rotation"));
      return e;
    }
    if (name == "cylinder") {
      check_keys(object, field, {"shape", "phase", "levels", "start", "end", "radius"});
      Cylinder c;
      c.start = vec<3>(required(object, field, "start"), join(field, "start"));
      c.end = vec<3>(required(object, field, "end"), join(field, "end"));
      if (c.start == c.end) fail(join(field, "end"), "equals start (a cylinder of length 0)");
      c.radius = positive(required(object, field, "radius"), join(field, "radius"));
      return c;
    }
    if (name == "stl") {
      check_keys(object, field,
                 {"shape", "phase", "levels", "file", "scale", "rotation", "translate"});
      StlSurface s;
      const std::string file_field = join(field, "file");
      const std::string given = string(required(object, field, "file"), file_field);
      if (given.empty()) fail(file_field, "empty file name");
      s.file = resolve(given);
      if (load_stl_ || probe_stl_) {
        const std::string problem = stl_file_problem(s.file);
        if (!problem.empty()) fail(file_field, problem);
      }
      if (load_stl_) s.triangles = read_stl(s.file);  // its own errors name the STL file and line
      if (const json* v = member(object, "scale")) s.scale = positive(*v, join(field, "scale"));
      if (const json* r = member(object, "rotation")) s.rotation = rotation(*r, join(field, "rotation"));
      if (const json* t = member(object, "translate")) s.translate = vec<3>(*t, join(field, "translate"));
      return s;
    }
    check_keys(object, field, {"shape", "phase", "levels", "patches"});
    NurbsSurface surface;
    const std::string patches_field = join(field, "patches");
    const json& patches = required(object, field, "patches");
    expect_array(patches, patches_field);
    if (patches.empty()) fail(patches_field, "needs at least one patch");
    for (std::size_t i = 0; i < patches.size(); ++i)
      surface.patches.push_back(patch(patches[i], index(patches_field, i)));
    return surface;
  }

  SceneDesc scene(const json& root) const;

 private:
  std::string file_;
  fs::path base_directory_;
  bool load_stl_ = true;   // false: STL triangles are read later (load_stl_surfaces)
  bool probe_stl_ = true;  // without load_stl_: still check that each STL file can be opened
};

const std::vector<std::string_view> kShapes2 = {"circle", "ellipse", "polygon", "nurbs"};
const std::vector<std::string_view> kShapes3 = {"sphere", "ellipsoid", "cylinder", "stl",
                                                "nurbs_surface"};

SceneDesc SceneReader::scene(const json& root) const {
  expect_object(root, "");
  SceneDesc s;
  s.source = file_;

  const std::string format = string(required(root, "", "format"), "format");
  if (format != "cisamr-scene/1")
    fail("format", "unsupported format '" + format + "' (expected 'cisamr-scene/1')");
  check_keys(root, "",
             {"format", "dimension", "domain", "mesh", "phases", "matrix_phase", "inclusions"});

  s.dimension = static_cast<int>(integer(required(root, "", "dimension"), "dimension"));
  if (s.dimension != 2 && s.dimension != 3)
    fail("dimension", "must be 2 or 3 (got " + std::to_string(s.dimension) + ")");
  const int dim = s.dimension;
  static const char* const kAxis = "xyz";

  // domain
  const json& domain = required(root, "", "domain");
  expect_object(domain, "domain");
  check_keys(domain, "domain", {"min", "max", "periodic"});
  for (const char* key : {"min", "max"}) {
    const std::string field = join("domain", key);
    const json& v = required(domain, "domain", key);
    std::array<double, 3> corner{};
    if (dim == 2) {
      const Vec2 c = vec<2>(v, field);
      corner = {c[0], c[1], 0};
    } else {
      corner = vec<3>(v, field);
    }
    (key[1] == 'i' ? s.domain_min : s.domain_max) = corner;
    for (int d = 0; d < dim; ++d)
      if (!(std::abs(corner[d]) <= kMaxLength))
        fail(index(field, d), number_text(corner[d]) + " is beyond the supported range [-" + number_text(kMaxLength) +
                                  ", " + number_text(kMaxLength) + "]");
  }
  for (int d = 0; d < dim; ++d)
    if (!(s.domain_min[d] < s.domain_max[d]))
      fail(index("domain.max", d), "must be greater than domain.min[" + std::to_string(d) +
                                       "] (" + number_text(s.domain_max[d]) +
                                       " <= " + number_text(s.domain_min[d]) + ")");
    else if (!(s.domain_max[d] - s.domain_min[d] >= kMinLength))
      fail(index("domain.max", d), "the extent " + number_text(s.domain_max[d] - s.domain_min[d]) +
                                       " is below the supported " + number_text(kMinLength));
  if (const json* p = member(domain, "periodic")) s.periodic = boolean(*p, "domain.periodic");

  // mesh
  const json& mesh = required(root, "", "mesh");
  expect_object(mesh, "mesh");
  check_keys(mesh, "mesh", {"h", "levels"});
  s.h = positive(required(mesh, "mesh", "h"), "mesh.h");
  if (s.h < kMinLength) fail("mesh.h", number_text(s.h) + " is below the supported " + number_text(kMinLength));
  double base_cells = 1;
  for (int d = 0; d < dim; ++d) {
    const double extent = s.domain_max[d] - s.domain_min[d];
    const double cells = std::round(extent / s.h);
    if (cells < 1 || std::abs(extent - cells * s.h) > kDivisionTolerance * extent)
      fail("mesh.h", "h = " + number_text(s.h) + " does not divide the domain extent " +
                         number_text(extent) + " along " + kAxis[d] + " (ratio " +
                         number_text(extent / s.h) + ")");
    base_cells *= cells;
  }
  if (base_cells > kMaxBaseCells)  // before any grid is allocated
    fail("mesh.h", "h = " + number_text(s.h) + " gives " + number_text(base_cells) +
                       " base cells, more than the " + number_text(kMaxBaseCells) + " a mesh may have");
  if (const json* l = member(mesh, "levels"))
    s.levels = integer_in(*l, "mesh.levels", 0, kMaxLevels);

  // phases
  if (const json* phases = member(root, "phases")) {
    expect_array(*phases, "phases");
    if (phases->empty()) fail("phases", "needs at least one phase");
    if (phases->size() > kMaxPhases)
      fail("phases", "at most " + std::to_string(kMaxPhases) + " phases, got " +
                         std::to_string(phases->size()));
    for (std::size_t i = 0; i < phases->size(); ++i) {
      const std::string field = index("phases", i);
      const json& p = (*phases)[i];
      expect_object(p, field);
      check_keys(p, field, {"id", "name", "void"});
      Phase phase;
      const long long id = integer(required(p, field, "id"), join(field, "id"));
      if (id < 1)
        fail(join(field, "id"), "phase ids must be positive integers (got " + std::to_string(id) + ")");
      phase.id = static_cast<int>(id);
      const int previous = s.phase_index(phase.id);
      if (previous >= 0)
        fail(join(field, "id"), "duplicate phase id " + std::to_string(id) + " (also phases[" +
                                    std::to_string(previous) + "])");
      phase.name = "phase" + std::to_string(id);
      if (const json* name = member(p, "name")) {
        phase.name = string(*name, join(field, "name"));
        if (phase.name.empty()) fail(join(field, "name"), "must not be empty");
      }
      for (std::size_t j = 0; j < s.phases.size(); ++j)
        if (s.phases[j].name == phase.name)
          fail(join(field, "name"), "duplicate phase name '" + phase.name + "' (also phases[" +
                                        std::to_string(j) + "])");
      if (const json* v = member(p, "void")) phase.is_void = boolean(*v, join(field, "void"));
      s.phases.push_back(phase);
    }
  } else {
    s.phases = {Phase{1, "matrix", false}, Phase{2, "inclusion", false}};
  }

  if (const json* m = member(root, "matrix_phase"))
    s.matrix_phase = static_cast<int>(integer(*m, "matrix_phase"));
  {
    const int i = s.phase_index(s.matrix_phase);
    if (i < 0)
      fail("matrix_phase", "phase " + std::to_string(s.matrix_phase) + " is not in phases");
    if (s.phases[i].is_void)
      fail("matrix_phase", "phase " + std::to_string(s.matrix_phase) +
                               " is a void phase: the matrix must be meshed");
  }

  // inclusions
  if (const json* inclusions = member(root, "inclusions")) {
    expect_array(*inclusions, "inclusions");
    s.inclusions.reserve(inclusions->size());
    for (std::size_t i = 0; i < inclusions->size(); ++i) {
      const std::string field = inclusion_field(i);
      const json& object = (*inclusions)[i];
      expect_object(object, field);
      const std::string shape_field = join(field, "shape");
      const std::string name = string(required(object, field, "shape"), shape_field);
      const auto& own = dim == 2 ? kShapes2 : kShapes3;
      const auto& other = dim == 2 ? kShapes3 : kShapes2;
      if (std::find(own.begin(), own.end(), name) == own.end()) {
        if (std::find(other.begin(), other.end(), name) != other.end())
          fail(shape_field, "shape '" + name + "' is " + std::to_string(5 - dim) +
                                "D but the scene is " + std::to_string(dim) + "D");
        fail(shape_field, "unknown shape '" + name + "' (" + std::to_string(dim) +
                              "D shapes: " + list_text(own) + ")");
      }
      Inclusion inclusion;
      inclusion.shape = dim == 2 ? shape_2d(name, object, field) : shape_3d(name, object, field);
      const std::string phase_field = join(field, "phase");
      const json* phase = member(object, "phase");
      inclusion.phase = phase ? static_cast<int>(integer(*phase, phase_field)) : 2;
      if (s.phase_index(inclusion.phase) < 0)
        fail(phase_field, "phase " + std::to_string(inclusion.phase) +
                              (phase ? "" : " (the default)") + " is not in phases");
      if (inclusion.phase == s.matrix_phase)
        fail(phase_field, "phase " + std::to_string(inclusion.phase) +
                              " is the matrix phase: an inclusion must be another phase");
      inclusion.levels = s.levels;
      if (const json* l = member(object, "levels"))
        inclusion.levels = integer_in(*l, join(field, "levels"), 0, kMaxLevels);
      s.inclusions.push_back(std::move(inclusion));
    }
  }
  return s;
}

// 1-based line and column of a byte offset (nlohmann reports the byte just read).
std::pair<std::size_t, std::size_t> line_and_column(const std::string& text, std::size_t byte) {
  std::size_t line = 1, column = 1;
  const std::size_t end = std::min(byte > 0 ? byte - 1 : 0, text.size());
  for (std::size_t i = 0; i < end; ++i) {
    if (text[i] == '\n')
      ++line, column = 1;
    else
      ++column;
  }
  return {line, column};
}

// ---------------------------------------------------------------- writing

using ordered = nlohmann::ordered_json;

ordered vec_json(const double* v, int n) {
  ordered a = ordered::array();
  for (int i = 0; i < n; ++i) a.push_back(v[i]);
  return a;
}
template <std::size_t N>
ordered vec_json(const std::array<double, N>& v) {
  return vec_json(v.data(), static_cast<int>(N));
}
template <std::size_t N>
ordered points_json(const std::vector<std::array<double, N>>& points) {
  ordered a = ordered::array();
  for (const auto& p : points) a.push_back(vec_json(p));
  return a;
}
ordered rotation_json(const Rotation3& r) {
  ordered a = ordered::array();
  for (const auto& row : r) a.push_back(vec_json(row));
  return a;
}
bool is_identity(const Rotation3& r) {
  for (int i = 0; i < 3; ++i)
    for (int j = 0; j < 3; ++j)
      if (r[i][j] != (i == j ? 1.0 : 0.0)) return false;
  return true;
}

// Absolute, normalised directory of a file ("" = the current directory's file).
fs::path directory_of(const std::string& file) {
  fs::path directory = fs::path(file).parent_path();
  if (directory.empty()) directory = ".";
  directory = fs::absolute(directory).lexically_normal();
  if (!directory.has_filename() && directory.has_relative_path())
    directory = directory.parent_path();  // drop the trailing "/" left by "a/."
  return directory;
}

ordered shape_json(const Shape& shape, const fs::path& destination_directory) {
  ordered o;
  std::visit(
      [&](const auto& s) {
        using T = std::decay_t<decltype(s)>;
        if constexpr (std::is_same_v<T, Circle>) {
          o["shape"] = "circle";
          o["center"] = vec_json(s.center);
          o["radius"] = s.radius;
        } else if constexpr (std::is_same_v<T, Ellipse>) {
          o["shape"] = "ellipse";
          o["center"] = vec_json(s.center);
          o["semi_axes"] = vec_json(s.semi_axes);
          o["angle"] = s.angle;
        } else if constexpr (std::is_same_v<T, Polygon>) {
          o["shape"] = "polygon";
          o["vertices"] = points_json(s.vertices);
        } else if constexpr (std::is_same_v<T, NurbsCurve>) {
          o["shape"] = "nurbs";
          o["degree"] = s.degree;
          o["knots"] = s.knots;
          o["control_points"] = points_json(s.control_points);
          if (!s.weights.empty()) o["weights"] = s.weights;
        } else if constexpr (std::is_same_v<T, Sphere>) {
          o["shape"] = "sphere";
          o["center"] = vec_json(s.center);
          o["radius"] = s.radius;
        } else if constexpr (std::is_same_v<T, Ellipsoid>) {
          o["shape"] = "ellipsoid";
          o["center"] = vec_json(s.center);
          o["semi_axes"] = vec_json(s.semi_axes);
          if (!is_identity(s.rotation)) o["rotation"] = rotation_json(s.rotation);
        } else if constexpr (std::is_same_v<T, Cylinder>) {
          o["shape"] = "cylinder";
          o["start"] = vec_json(s.start);
          o["end"] = vec_json(s.end);
          o["radius"] = s.radius;
        } else if constexpr (std::is_same_v<T, StlSurface>) {
          o["shape"] = "stl";
          // Relative to the new scene file, so that the pair can be moved together.
          const fs::path target = fs::absolute(fs::path(s.file)).lexically_normal();
          const fs::path relative = target.lexically_relative(destination_directory);
          o["file"] = relative.empty() ? target.string() : relative.string();
          if (s.scale != 1) o["scale"] = s.scale;
          if (!is_identity(s.rotation)) o["rotation"] = rotation_json(s.rotation);
          if (s.translate != Vec3{0, 0, 0}) o["translate"] = vec_json(s.translate);
        } else {
          static_assert(std::is_same_v<T, NurbsSurface>);
          o["shape"] = "nurbs_surface";
          ordered patches = ordered::array();
          for (const NurbsPatch& p : s.patches) {
            ordered patch;
            patch["degree"] = {p.degree[0], p.degree[1]};
            patch["knots_u"] = p.knots_u;
            patch["knots_v"] = p.knots_v;
            patch["control_points"] = points_json(p.control_points);
            if (!p.weights.empty()) patch["weights"] = p.weights;
            patches.push_back(std::move(patch));
          }
          o["patches"] = std::move(patches);
        }
      },
      shape);
  return o;
}

// Pretty printer that keeps short arrays and objects on one line ("center": [1, 2]),
// one inclusion per line when it fits, and long scalar lists wrapped.
class PrettyPrinter {
 public:
  std::string text;

  void print(const ordered& v, int indent) {
    const std::string flat = compact(v);
    if (flat.size() + static_cast<std::size_t>(indent) <= kWidth || !(v.is_array() || v.is_object())) {
      text += flat;
      return;
    }
    const std::string pad(static_cast<std::size_t>(indent + 2), ' ');
    if (v.is_object()) {
      text += "{\n";
      std::size_t i = 0;
      for (const auto& item : v.items()) {
        text += pad;
        text += ordered(item.key()).dump();
        text += ": ";
        print(item.value(), indent + 2);
        text += ++i < v.size() ? ",\n" : "\n";
      }
      text += std::string(static_cast<std::size_t>(indent), ' ') + "}";
      return;
    }
    const bool scalars = std::all_of(v.begin(), v.end(), [](const ordered& e) {
      return !e.is_array() && !e.is_object();
    });
    text += "[\n" + pad;
    std::size_t column = pad.size();
    for (std::size_t i = 0; i < v.size(); ++i) {
      if (scalars) {
        const std::string item = v[i].dump() + (i + 1 < v.size() ? "," : "");
        if (column > pad.size() && column + 1 + item.size() > kWidth) {
          text += "\n" + pad;
          column = pad.size();
        } else if (column > pad.size()) {
          text += " ";
          ++column;
        }
        text += item;
        column += item.size();
      } else {
        print(v[i], indent + 2);
        if (i + 1 < v.size()) text += ",\n" + pad;
      }
    }
    text += "\n" + std::string(static_cast<std::size_t>(indent), ' ') + "]";
  }

 private:
  static constexpr std::size_t kWidth = 100;

  static std::string compact(const ordered& v) {
    if (v.is_object()) {
      std::string s = "{";
      std::size_t i = 0;
      for (const auto& item : v.items()) {
        if (i++ > 0) s += ", ";
        s += ordered(item.key()).dump() + ": " + compact(item.value());
      }
      return s + "}";
    }
    if (v.is_array()) {
      std::string s = "[";
      for (std::size_t i = 0; i < v.size(); ++i) {
        if (i > 0) s += ", ";
        s += compact(v[i]);
      }
      return s + "]";
    }
    return v.dump();  // numbers: shortest round-trip text
  }
};

}  // namespace

SceneDesc parse_scene(const std::string& json_text, const std::string& source) {
  return parse_scene(json_text, source, ReadSceneOptions{});
}

SceneDesc parse_scene(const std::string& json_text, const std::string& source, const ReadSceneOptions& options) {
  DuplicateKeyFinder duplicates;
  json root;
  try {
    root = json::parse(json_text, std::ref(duplicates), /*allow_exceptions=*/true,
                       /*ignore_comments=*/false);
  } catch (const json::parse_error& e) {
    const auto [line, column] = line_and_column(json_text, e.byte);
    throw InputError(source, "",
                     "invalid JSON at line " + std::to_string(line) + ", column " +
                         std::to_string(column) + ": " + json_problem(e));
  } catch (const json::exception& e) {  // a number beyond the double range (1e400)
    throw InputError(source, duplicates.current_field(), "invalid JSON: " + json_problem(e));
  }
  if (!duplicates.duplicate_field.empty())
    throw InputError(source, duplicates.duplicate_field, "duplicate key");
  return SceneReader(source, directory_of(source), options).scene(root);
}

SceneDesc read_scene(const std::string& path) { return read_scene(path, ReadSceneOptions{}); }

std::int64_t load_stl_surfaces(SceneDesc& scene, std::span<const std::int32_t> inclusions, StlCache* cache) {
  StlCache local;
  StlCache& files = cache != nullptr ? *cache : local;
  std::int64_t read = 0;
  for (std::int32_t k : inclusions) {
    auto* s = std::get_if<StlSurface>(&scene.inclusions.at(static_cast<std::size_t>(k)).shape);
    if (s == nullptr || !s->triangles.empty()) continue;
    auto it = files.find(s->file);
    if (it == files.end()) {
      // As read_scene reports it: the scene's field for a file that cannot be opened, the
      // STL file and line for a malformed one.
      const std::string problem = stl_file_problem(s->file);
      if (!problem.empty()) throw InputError(scene.source, "inclusions[" + std::to_string(k) + "].file", problem);
      it = files.emplace(s->file, read_stl(s->file)).first;
      ++read;
    }
    s->triangles = it->second;
  }
  return read;
}

SceneDesc read_scene(const std::string& path, const ReadSceneOptions& options) {
  return parse_scene(read_input_file(path), path, options);
}

std::string scene_to_json(const SceneDesc& scene, const std::string& destination) {
  const int dim = scene.dimension;
  ordered root;
  root["format"] = "cisamr-scene/1";
  root["dimension"] = dim;
  ordered domain;
  domain["min"] = vec_json(scene.domain_min.data(), dim);
  domain["max"] = vec_json(scene.domain_max.data(), dim);
  domain["periodic"] = scene.periodic;
  root["domain"] = std::move(domain);
  ordered mesh;
  mesh["h"] = scene.h;
  mesh["levels"] = scene.levels;
  root["mesh"] = std::move(mesh);
  ordered phases = ordered::array();
  for (const Phase& p : scene.phases) {
    ordered phase;
    phase["id"] = p.id;
    phase["name"] = p.name;
    if (p.is_void) phase["void"] = true;
    phases.push_back(std::move(phase));
  }
  root["phases"] = std::move(phases);
  root["matrix_phase"] = scene.matrix_phase;
  const fs::path directory = directory_of(destination);
  ordered inclusions = ordered::array();
  for (const Inclusion& inclusion : scene.inclusions) {
    ordered o = shape_json(inclusion.shape, directory);
    o["phase"] = inclusion.phase;
    o["levels"] = inclusion.levels;
    inclusions.push_back(std::move(o));
  }
  root["inclusions"] = std::move(inclusions);
  PrettyPrinter printer;
  printer.print(root, 0);
  return printer.text + "\n";
}

void write_scene(const std::string& path, const SceneDesc& scene) {
  const std::string text = scene_to_json(scene, path);
  AtomicFile file(path);
  file.write(text);
  file.commit();
}

}  // namespace cisamr::io
