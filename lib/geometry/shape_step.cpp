// STEP solids: the scene members, and the questions about a descriptor, answered on the
// exact (converted) faces through the body of the selected solids (surface_body.hpp
// build_brep); the import itself is io's (step_import.hpp), once per file and process.
#include "geometry/shape_step.hpp"

#include <algorithm>
#include <cmath>
#include <cstring>
#include <map>
#include <mutex>
#include <set>

#include "core/error.hpp"
#include "geometry/brep_data.hpp"
#include "geometry/nurbs_surface_model.hpp"
#include "geometry/shape_fields.hpp"
#include "geometry/shape_model.hpp"
#include "geometry/surface_body.hpp"

namespace cisamr::geometry {
namespace {

surface::Placement placement_of(const StepSolids& s) { return {s.scale, s.rotation, s.translate}; }

// The body of a descriptor, built once per process (keyed by the imported data, the
// selection and the placement).
std::shared_ptr<const surface::Body> body_of(const StepSolids& s, std::string* problem = nullptr) {
  if (!s.brep) {
    if (problem) *problem = ".file: not loaded";
    return nullptr;
  }
  std::string key(reinterpret_cast<const char*>(&s.brep), sizeof(void*));
  key.append(reinterpret_cast<const char*>(s.solids.data()), s.solids.size() * sizeof(int));
  key.append(reinterpret_cast<const char*>(&s.scale), sizeof s.scale);
  key.append(reinterpret_cast<const char*>(&s.rotation), sizeof s.rotation);
  key.append(reinterpret_cast<const char*>(&s.translate), sizeof s.translate);
  return surface::cached(
      key,
      [&](surface::Body& body) {
        std::string why = surface::build_brep(*s.brep, s.solids, placement_of(s), body);
        if (!why.empty()) why = ".file: " + s.file.substr(s.file.find_last_of('/') + 1) + why;
        return why;
      },
      problem);
}

class StepFamily final : public FamilyOf<StepSolids> {
 public:
  std::string_view name() const override { return "step"; }
  int dimension() const override { return 3; }
  Shape read(const FieldReader& f) const override {
    f.allow_keys({"file", "solids", "scale", "rotation", "translate"});
    StepSolids s;
    StepFile file = f.step_file("file");
    s.file = std::move(file.path);
    s.brep = std::move(file.brep);
    if (f.has("solids")) {
      const std::size_t n = f.array_size("solids");
      if (n == 0) f.fail("solids", "needs at least one solid index (or leave it out: every solid)");
      const int count = s.brep ? static_cast<int>(s.brep->solids.size()) : 1 << 30;
      std::set<int> seen;
      for (std::size_t i = 0; i < n; ++i) {
        const int k = f.integer_of("solids", n, i, 0, count - 1,
                                   "a solid index of " + s.file.substr(s.file.find_last_of('/') + 1) + " (it has " +
                                       std::to_string(count) + " solids)");
        if (!seen.insert(k).second) f.fail("solids", "solid " + std::to_string(k) + " is named twice");
        s.solids.push_back(k);
      }
    }
    read_placement(f, s);
    return s;
  }
  void write(const Shape& shape, FieldWriter& f) const override {
    const StepSolids& s = of(shape);
    f.file("file", s.file);
    if (!s.solids.empty()) f.integers("solids", s.solids);
    write_placement(s, f);
  }
  Box3 bounding_box(const Shape& s) const override {
    const auto body = body_of(of(s));
    return body ? body->box : Box3{};
  }
  // The imported boxes of the selected solids, placed (the box of their placed corners).
  Box3 holding_box(const Shape& shape) const override {
    const StepSolids& s = of(shape);
    if (!s.brep) return {};
    Box3 b{{INFINITY, INFINITY, INFINITY}, {-INFINITY, -INFINITY, -INFINITY}};
    const surface::Placement pl = placement_of(s);
    for (std::size_t k = 0; k < s.brep->solids.size(); ++k) {
      if (!s.solids.empty() && std::find(s.solids.begin(), s.solids.end(), static_cast<int>(k)) == s.solids.end())
        continue;
      const Box3& sb = s.brep->solids[k].box;
      for (int c = 0; c < 8; ++c) {
        const Vec3 x{c & 1 ? sb.max[0] : sb.min[0], c & 2 ? sb.max[1] : sb.min[1], c & 4 ? sb.max[2] : sb.min[2]};
        Vec3 y{};
        for (int r = 0; r < 3; ++r)
          y[r] = pl.rotation[r][0] * (pl.scale * x[0]) + pl.rotation[r][1] * (pl.scale * x[1]) +
                 pl.rotation[r][2] * (pl.scale * x[2]) + pl.translate[r];
        for (int d = 0; d < 3; ++d) b.min[d] = std::min(b.min[d], y[d]), b.max[d] = std::max(b.max[d], y[d]);
      }
    }
    return b;
  }
  double measure(const Shape& s) const override {
    const auto body = body_of(of(s));
    return body ? surface::volume(*body) : 0.0;
  }
  double boundary_measure(const Shape& s) const override {
    const auto body = body_of(of(s));
    return body ? surface::area(*body) : 0.0;
  }
  std::vector<Vec3> boundary_samples(const Shape& s, double spacing) const override {
    const auto body = body_of(of(s));
    return body ? surface::surface_points(*body, spacing) : std::vector<Vec3>{};
  }
  bool contains(const Shape& s, const Vec3& p) const override {
    const auto body = body_of(of(s));
    return body && point_in_box<3>(p, body->box) && surface::side(*body, p) >= 0;
  }
  void translate(Shape& s, const Vec3& o) const override {
    for (int k = 0; k < 3; ++k) of(s).translate[k] += o[k];
  }
  std::optional<bool> overlap_same_family(const Shape& a, const Shape& b, double gap) const override {
    const auto ba = body_of(of(a)), bb = body_of(of(b));
    if (!ba || !bb) return std::nullopt;
    return surface::within(*ba, *bb, gap);
  }
  // Near a sphere, ellipsoid or cylinder: the body's pieces against its support function,
  // so that the level rules refine where they come close, not wherever their boxes meet.
  std::optional<bool> overlap_convex(const Shape& self, const Shape& other, double gap) const override {
    const auto body = body_of(of(self));
    if (!body) return std::nullopt;
    const ShapeFamily& f = shape_family(other);
    return surface::within_convex(
        *body, [&](const Vec3& d) { return f.support(other, d); }, [&](const Vec3& p) { return f.contains(other, p); }, gap);
  }
  std::unique_ptr<SurfaceModel> surface_model(const Shape& s, const std::string& source,
                                              const std::string& field) const override {
    const StepSolids& st = of(s);
    if (!(st.scale > 0) || !std::isfinite(st.scale)) throw InputError(source, field + ".scale", "must be positive");
    if (!orthonormal(st.rotation)) throw InputError(source, field + ".rotation", "must be orthonormal");
    if (!finite(st.translate)) throw InputError(source, field + ".translate", "must be finite");
    if (!st.brep) throw InputError(source, field + ".file", st.file + ": not loaded");
    std::string problem;
    auto body = body_of(st, &problem);
    if (!body) {
      const std::size_t colon = problem.find(": ");
      throw InputError(source, field + problem.substr(0, colon), problem.substr(colon + 2));
    }
    return make_body_model(s, std::move(body));
  }
};

}  // namespace

const ShapeFamily& step_family() {
  static const StepFamily family;
  return family;
}

}  // namespace cisamr::geometry
