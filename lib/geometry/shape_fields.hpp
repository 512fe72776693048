#pragma once
// The fields of one object of a scene file, as a shape family reads and writes them
// (ShapeFamily::read/write). The file format lives in lib/io, which implements these
// interfaces over JSON; a family sees only named fields. Keys are the object's member
// names ("radius"); a field path passed to fail() is relative to the object
// ("knots[3]") and comes back as "FILE: inclusions[2].knots[3]: problem".
#include <array>
#include <cstddef>
#include <functional>
#include <memory>
#include <string>
#include <string_view>
#include <vector>

#include "core/types.hpp"
#include "geometry/scene.hpp"

namespace cisamr::geometry {

// Shortest text that reads back to the same double (for messages: "got 0.1").
std::string number_text(double value);

bool is_identity(const Rotation3& r);

// A file named by a field, relative names resolved against the scene file's directory.
struct SurfaceFile {
  std::string path;                           // absolute, normalised
  std::vector<std::array<Vec3, 3>> triangles;  // empty where the reader defers loading
};

struct BrepData;
// A STEP file named by a field: resolved, imported once per process (null where the
// reader defers loading).
struct StepFile {
  std::string path;
  std::shared_ptr<const BrepData> brep;
};

// Every getter but has() reads a required member (missing: "missing required field") and
// throws InputError naming the member's field for a value of the wrong kind.
class FieldReader {
 public:
  virtual ~FieldReader() = default;

  [[noreturn]] virtual void fail(const std::string& field, const std::string& problem) const = 0;
  // Every member of the object must be one of `keys` (or one the reader adds itself, such
  // as an inclusion's "shape", "phase" and "levels"); suggests the closest for a typo.
  virtual void allow_keys(const std::vector<std::string_view>& keys) const = 0;
  virtual bool has(std::string_view key) const = 0;

  virtual double number(std::string_view key) const = 0;    // finite
  virtual double positive(std::string_view key) const = 0;  // finite, > 0
  virtual int integer_in(std::string_view key, int lo, int hi) const = 0;
  virtual bool boolean(std::string_view key) const = 0;
  virtual std::string string(std::string_view key) const = 0;
  // An array of exactly out.size() numbers.
  virtual void fixed_numbers(std::string_view key, std::vector<double>& out) const = 0;
  // Element i, in [lo, hi], of an array of exactly `count` integers; `meaning` says what
  // they are.
  virtual int integer_of(std::string_view key, std::size_t count, std::size_t i, int lo, int hi,
                         std::string_view meaning) const = 0;
  virtual std::vector<double> numbers(std::string_view key) const = 0;  // any length
  virtual std::size_t array_size(std::string_view key) const = 0;       // any array
  virtual std::vector<Vec2> points2(std::string_view key) const = 0;    // arrays of 2 numbers
  virtual std::vector<Vec3> points3(std::string_view key) const = 0;    // arrays of 3 numbers
  virtual Rotation3 rotation(std::string_view key) const = 0;           // proper, orthonormal
  // A NURBS control net of count_u × count_v points (the counts follow from the knots),
  // returned u fastest. Written either as count_v rows of count_u points
  // ([[[x, y, z], …], …]; errors name "key[j][i]") or as one flat list u fastest (errors
  // name "key[k]"); a wrong shape names the counts ("expected 7 rows of 9 points (from the
  // knots), got 6 rows").
  virtual std::vector<Vec3> point_grid3(std::string_view key, std::size_t count_u, std::size_t count_v) const = 0;
  // The same two layouts for finite numbers (the net's weights), each > 0 when `positive`.
  virtual std::vector<double> number_grid(std::string_view key, std::size_t count_u, std::size_t count_v,
                                          bool positive) const = 0;
  // Each element of an array of objects, read by `read_one`.
  virtual void objects(std::string_view key, const std::function<void(const FieldReader&)>& read_one) const = 0;
  // A triangulated surface file (STL): a non-empty name, resolved; loaded or only checked
  // to be readable as the scene reader's options ask.
  virtual SurfaceFile surface_file(std::string_view key) const = 0;
  // A STEP file: a non-empty name, resolved, imported (errors name the file).
  virtual StepFile step_file(std::string_view key) const = 0;

  template <int N>
  Vec<N> vec(std::string_view key) const {
    std::vector<double> v(N);
    fixed_numbers(key, v);
    Vec<N> result;
    for (int d = 0; d < N; ++d) result[d] = v[d];
    return result;
  }
  template <int N>
  Vec<N> positive_vec(std::string_view key) const {
    const Vec<N> result = vec<N>(key);
    for (int d = 0; d < N; ++d)
      if (!(result[d] > 0))
        fail(std::string(key) + "[" + std::to_string(d) + "]",
             "must be positive (got " + number_text(result[d]) + ")");
    return result;
  }
};

// Writes the members of one object, in the order of the calls.
class FieldWriter {
 public:
  virtual ~FieldWriter() = default;

  virtual void number(std::string_view key, double value) = 0;
  virtual void integer(std::string_view key, int value) = 0;
  virtual void numbers(std::string_view key, const std::vector<double>& values) = 0;
  virtual void integers(std::string_view key, const std::vector<int>& values) = 0;
  virtual void points(std::string_view key, const std::vector<Vec2>& points) = 0;
  virtual void points(std::string_view key, const std::vector<Vec3>& points) = 0;
  virtual void rotation(std::string_view key, const Rotation3& r) = 0;
  // A file by its resolved path, written relative to the new scene file where it can be.
  virtual void file(std::string_view key, const std::string& path) = 0;
  // An array of `count` objects, the i-th written by write_one(writer, i).
  virtual void objects(std::string_view key, std::size_t count,
                       const std::function<void(FieldWriter&, std::size_t)>& write_one) = 0;

  template <std::size_t N>
  void vec(std::string_view key, const std::array<double, N>& v) {
    numbers(key, std::vector<double>(v.begin(), v.end()));
  }
};

// The placement members (scale, rotation, translate) of STL, NURBS-surface and STEP
// descriptors: read where present, written where not the default.
template <class Placed>
void read_placement(const FieldReader& f, Placed& s) {
  if (f.has("scale")) s.scale = f.positive("scale");
  if (f.has("rotation")) s.rotation = f.rotation("rotation");
  if (f.has("translate")) s.translate = f.vec<3>("translate");
}
template <class Placed>
void write_placement(const Placed& s, FieldWriter& f) {
  if (s.scale != 1) f.number("scale", s.scale);
  if (!is_identity(s.rotation)) f.rotation("rotation", s.rotation);
  if (s.translate != Vec3{0, 0, 0}) f.vec("translate", s.translate);
}

}  // namespace cisamr::geometry
