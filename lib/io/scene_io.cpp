#include "io/scene_io.hpp"

#include <algorithm>
#include <cmath>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <functional>
#include <limits>
#include <memory>
#include <sstream>
#include <mutex>
#include <map>
#include <nlohmann/json.hpp>
#include <set>
#include <span>
#include <string_view>

#include "core/error.hpp"
#include "core/input_file.hpp"
#include "geometry/brep_data.hpp"
#include "geometry/shape_family.hpp"
#include "geometry/shape_fields.hpp"
#include "geometry/step_import.hpp"
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

  // An array of exactly out.size() numbers.
  void fixed_numbers(const json& v, const std::string& field, std::span<double> out) const {
    if (!v.is_array() || v.size() != out.size())
      fail(field, "expected an array of " + std::to_string(out.size()) + " numbers, got " +
                      (v.is_array() ? "an array of " + std::to_string(v.size())
                                    : type_text(v)));
    for (std::size_t d = 0; d < out.size(); ++d) out[d] = number(v[d], index(field, d));
  }
  template <int N>
  Vec<N> vec(const json& v, const std::string& field) const {
    Vec<N> result;
    fixed_numbers(v, field, result);
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

  // A control net of count_u × count_v elements, u fastest: count_v rows of count_u
  // elements or one flat list. Rows are recognised by their first element being an array
  // of arrays (points) or an array (numbers); read_one(element, field) reads one element.
  template <class T, class ReadOne>
  std::vector<T> grid(const json& v, const std::string& field, std::size_t count_u, std::size_t count_v,
                      bool element_is_array, std::string_view noun, const ReadOne& read_one) const {
    expect_array(v, field);
    const auto is_row = [&](const json& e) {
      return e.is_array() && (!element_is_array || (!e.empty() && e[0].is_array()));
    };
    const std::string counts = std::to_string(count_v) + " rows of " + std::to_string(count_u) + " " +
                               std::string(noun);
    std::vector<T> result;  // grows with the elements present (the counts may be huge)
    if (!v.empty() && is_row(v[0])) {
      if (v.size() != count_v)
        fail(field, "expected " + counts + " (from the knots), got " + std::to_string(v.size()) +
                        (v.size() == 1 ? " row" : " rows"));
      for (std::size_t j = 0; j < count_v; ++j) {
        const std::string row = index(field, j);
        if (!v[j].is_array())
          fail(row, "expected a row of " + std::to_string(count_u) + " " + std::string(noun) + ", got " +
                        type_text(v[j]));
        if (v[j].size() != count_u)
          fail(row, "expected a row of " + std::to_string(count_u) + " " + std::string(noun) +
                        " (from the knots), got " + std::to_string(v[j].size()));
        for (std::size_t i = 0; i < count_u; ++i) result.push_back(read_one(v[j][i], index(row, i)));
      }
      return result;
    }
    if (v.size() != count_u * count_v)
      fail(field, "expected " + counts + ", or " + std::to_string(count_u) + " × " + std::to_string(count_v) +
                      " = " + std::to_string(count_u * count_v) + " " + std::string(noun) +
                      " u fastest (from the knots), got " + std::to_string(v.size()) + " " + std::string(noun));
    result.reserve(v.size());
    for (std::size_t k = 0; k < v.size(); ++k) result.push_back(read_one(v[k], index(field, k)));
    return result;
  }
  std::vector<Vec3> point_grid3(const json& v, const std::string& field, std::size_t count_u,
                                std::size_t count_v) const {
    return grid<Vec3>(v, field, count_u, count_v, true, "points",
                      [&](const json& e, const std::string& f) { return vec<3>(e, f); });
  }
  std::vector<double> number_grid(const json& v, const std::string& field, std::size_t count_u,
                                  std::size_t count_v, bool positive_only) const {
    return grid<double>(v, field, count_u, count_v, false, "numbers", [&](const json& e, const std::string& f) {
      return positive_only ? positive(e, f) : number(e, f);
    });
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

  std::string resolve(const std::string& file) const {
    fs::path p(file);
    if (p.is_relative()) p = base_directory_ / p;
    return fs::absolute(p).lexically_normal().string();
  }

  // A file named in `field`: resolved against the scene file's directory; checked to be
  // readable and loaded as the options ask.
  SurfaceFile surface_file(const std::string& given, const std::string& field) const {
    if (given.empty()) fail(field, "empty file name");
    SurfaceFile file{resolve(given), {}};
    if (load_stl_ || probe_stl_) {
      const std::string problem = stl_file_problem(file.path);
      if (!problem.empty()) fail(field, problem);
    }
    if (load_stl_) file.triangles = read_stl(file.path);  // its own errors name the STL file and line
    return file;
  }

  // A STEP file named in `field`, imported once per process and path, whatever the
  // options say: every rank needs its solids' boxes for the partition, the import is cheap
  // next to meshing (0.3 s for data/shapes/parts.step) and deterministic, so every rank
  // holds the same solids, and a bad file is refused by every rank alike.
  StepFile step_file(const std::string& given, const std::string& field) const {
    if (given.empty()) fail(field, "empty file name");
    StepFile file{resolve(given), nullptr};
    static std::mutex mutex;
    static std::map<std::string, std::shared_ptr<const BrepData>> imported;
    std::lock_guard<std::mutex> lock(mutex);
    if (const auto it = imported.find(file.path); it != imported.end()) {
      file.brep = it->second;
      return file;
    }
    std::ifstream in(file.path, std::ios::binary);
    if (!in) fail(field, file.path + ": cannot be opened");
    std::ostringstream bytes;
    bytes << in.rdbuf();
    auto data = std::make_shared<BrepData>();
    const std::string problem = geometry::import_step(bytes.str(), fs::path(file.path).filename().string(), *data);
    if (!problem.empty()) fail(field, problem);
    imported.emplace(file.path, data);
    file.brep = std::move(data);
    return file;
  }

  SceneDesc scene(const json& root) const;

 private:
  std::string file_;
  fs::path base_directory_;
  bool load_stl_ = true;   // false: STL triangles are read later (load_stl_surfaces)
  bool probe_stl_ = true;  // without load_stl_: still check that each STL file can be opened
};

// The fields of one object of the scene file, for a shape family to read.
class JsonFieldReader final : public FieldReader {
 public:
  // own_keys: the members the caller reads itself, allowed beside the family's.
  JsonFieldReader(const SceneReader& reader, const json& object, std::string field,
                  std::vector<std::string_view> own_keys)
      : reader_(reader), object_(object), field_(std::move(field)), own_keys_(std::move(own_keys)) {}

  [[noreturn]] void fail(const std::string& field, const std::string& problem) const override {
    reader_.fail(join(field_, field), problem);
  }
  void allow_keys(const std::vector<std::string_view>& keys) const override {
    std::vector<std::string_view> allowed = own_keys_;
    allowed.insert(allowed.end(), keys.begin(), keys.end());
    reader_.check_keys(object_, field_, allowed);
  }
  bool has(std::string_view key) const override { return reader_.member(object_, key) != nullptr; }
  double number(std::string_view key) const override { return reader_.number(get(key), path(key)); }
  double positive(std::string_view key) const override { return reader_.positive(get(key), path(key)); }
  int integer_in(std::string_view key, int lo, int hi) const override {
    return reader_.integer_in(get(key), path(key), lo, hi);
  }
  bool boolean(std::string_view key) const override { return reader_.boolean(get(key), path(key)); }
  std::string string(std::string_view key) const override { return reader_.string(get(key), path(key)); }
  void fixed_numbers(std::string_view key, std::vector<double>& out) const override {
    reader_.fixed_numbers(get(key), path(key), out);
  }
  int integer_of(std::string_view key, std::size_t count, std::size_t i, int lo, int hi,
                 std::string_view meaning) const override {
    const json& v = get(key);
    if (!v.is_array() || v.size() != count)
      reader_.fail(path(key), "expected an array of " + std::to_string(count) + " integers (" +
                                  std::string(meaning) + ")");
    return reader_.integer_in(v[i], index(path(key), i), lo, hi);
  }
  std::vector<double> numbers(std::string_view key) const override { return reader_.numbers(get(key), path(key)); }
  std::size_t array_size(std::string_view key) const override {
    const json& v = get(key);
    reader_.expect_array(v, path(key));
    return v.size();
  }
  std::vector<Vec2> points2(std::string_view key) const override { return reader_.points<2>(get(key), path(key)); }
  std::vector<Vec3> points3(std::string_view key) const override { return reader_.points<3>(get(key), path(key)); }
  Rotation3 rotation(std::string_view key) const override { return reader_.rotation(get(key), path(key)); }
  std::vector<Vec3> point_grid3(std::string_view key, std::size_t count_u, std::size_t count_v) const override {
    return reader_.point_grid3(get(key), path(key), count_u, count_v);
  }
  std::vector<double> number_grid(std::string_view key, std::size_t count_u, std::size_t count_v,
                                  bool positive) const override {
    return reader_.number_grid(get(key), path(key), count_u, count_v, positive);
  }
  void objects(std::string_view key, const std::function<void(const FieldReader&)>& read_one) const override {
    const json& v = get(key);
    const std::string field = path(key);
    reader_.expect_array(v, field);
    for (std::size_t i = 0; i < v.size(); ++i) {
      const std::string element = index(field, i);
      reader_.expect_object(v[i], element);
      read_one(JsonFieldReader(reader_, v[i], element, {}));
    }
  }
  StepFile step_file(std::string_view key) const override { return reader_.step_file(string(key), path(key)); }
  SurfaceFile surface_file(std::string_view key) const override {
    return reader_.surface_file(string(key), path(key));
  }

 private:
  std::string path(std::string_view key) const { return join(field_, key); }
  const json& get(std::string_view key) const { return reader_.required(object_, field_, key); }

  const SceneReader& reader_;
  const json& object_;
  std::string field_;
  std::vector<std::string_view> own_keys_;
};

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
  if (const json* p = member(domain, "periodic")) {
    // true/false for every axis, or one boolean per axis.
    if (p->is_array()) {
      if (static_cast<int>(p->size()) != dim)
        fail("domain.periodic", "must be a boolean or an array of " + std::to_string(dim) + " booleans (got " +
                                    std::to_string(p->size()) + " entries)");
      for (int d = 0; d < dim; ++d)
        s.periodic[static_cast<std::size_t>(d)] = boolean((*p)[static_cast<std::size_t>(d)], index("domain.periodic", d));
    } else {
      const bool all = boolean(*p, "domain.periodic");
      for (int d = 0; d < dim; ++d) s.periodic[static_cast<std::size_t>(d)] = all;
    }
  }

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
      const ShapeFamily* family = shape_family_named(name);
      if (family == nullptr || family->dimension() != dim) {
        if (family != nullptr)
          fail(shape_field, "shape '" + name + "' is " + std::to_string(family->dimension()) +
                                "D but the scene is " + std::to_string(dim) + "D");
        fail(shape_field, "unknown shape '" + name + "' (" + std::to_string(dim) +
                              "D shapes: " + list_text(shape_family_names(dim)) + ")");
      }
      Inclusion inclusion;
      inclusion.shape = family->read(JsonFieldReader(*this, object, field, {"shape", "phase", "levels"}));
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
      // Every solid of a `step` entry is an inclusion of its own (its box, levels and
      // partition load are its own), named "inclusions[i] (solid k)" in messages.
      std::vector<int> solids;
      if (const auto* step = std::get_if<StepSolids>(&inclusion.shape); step != nullptr && step->brep) {
        solids = step->solids;
        if (solids.empty())
          for (std::size_t k = 0; k < step->brep->solids.size(); ++k) solids.push_back(static_cast<int>(k));
      }
      if (solids.size() > 1) {
        for (int k : solids) {
          Inclusion one = inclusion;
          std::get<StepSolids>(one.shape).solids = {k};
          s.inclusions.push_back(std::move(one));
          s.entry.push_back(static_cast<std::int32_t>(i));
          s.entry_solid.push_back(k);
        }
        continue;
      }
      s.inclusions.push_back(std::move(inclusion));
      s.entry.push_back(static_cast<std::int32_t>(i));
      s.entry_solid.push_back(-1);
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

// Absolute, normalised directory of a file ("" = the current directory's file).
fs::path directory_of(const std::string& file) {
  fs::path directory = fs::path(file).parent_path();
  if (directory.empty()) directory = ".";
  directory = fs::absolute(directory).lexically_normal();
  if (!directory.has_filename() && directory.has_relative_path())
    directory = directory.parent_path();  // drop the trailing "/" left by "a/."
  return directory;
}

// The members of one object of the new scene file, as a shape family writes them.
class JsonFieldWriter final : public FieldWriter {
 public:
  JsonFieldWriter(ordered& object, const fs::path& destination_directory)
      : object_(object), destination_directory_(destination_directory) {}

  void number(std::string_view key, double value) override { at(key) = value; }
  void integer(std::string_view key, int value) override { at(key) = value; }
  void numbers(std::string_view key, const std::vector<double>& values) override { at(key) = values; }
  void integers(std::string_view key, const std::vector<int>& values) override { at(key) = values; }
  void points(std::string_view key, const std::vector<Vec2>& points) override { at(key) = points_json(points); }
  void points(std::string_view key, const std::vector<Vec3>& points) override { at(key) = points_json(points); }
  void rotation(std::string_view key, const Rotation3& r) override { at(key) = rotation_json(r); }
  void file(std::string_view key, const std::string& path) override {
    // Relative to the new scene file, so that the pair can be moved together.
    const fs::path target = fs::absolute(fs::path(path)).lexically_normal();
    const fs::path relative = target.lexically_relative(destination_directory_);
    at(key) = relative.empty() ? target.string() : relative.string();
  }
  void objects(std::string_view key, std::size_t count,
               const std::function<void(FieldWriter&, std::size_t)>& write_one) override {
    ordered array = ordered::array();
    for (std::size_t i = 0; i < count; ++i) {
      ordered element;
      JsonFieldWriter writer(element, destination_directory_);
      write_one(writer, i);
      array.push_back(std::move(element));
    }
    at(key) = std::move(array);
  }

 private:
  ordered& at(std::string_view key) { return object_[std::string(key)]; }

  ordered& object_;
  const fs::path& destination_directory_;
};

ordered shape_json(const Shape& shape, const fs::path& destination_directory) {
  const ShapeFamily& family = shape_family(shape);
  ordered o;
  o["shape"] = std::string(family.name());
  JsonFieldWriter writer(o, destination_directory);
  family.write(shape, writer);
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
      if (!problem.empty()) throw InputError(scene.source, inclusion_field(scene, static_cast<std::size_t>(k)) + ".file", problem);
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
  bool all_same = true;
  for (int d = 1; d < dim; ++d) all_same &= scene.periodic[static_cast<std::size_t>(d)] == scene.periodic[0];
  if (all_same) {
    domain["periodic"] = scene.periodic[0];
  } else {
    domain["periodic"] = ordered::array();
    for (int d = 0; d < dim; ++d) domain["periodic"].push_back(scene.periodic[static_cast<std::size_t>(d)]);
  }
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
