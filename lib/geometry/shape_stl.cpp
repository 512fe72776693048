// STL surfaces (README: classification, crossings, volumes, distances).
#include "geometry/shape_stl.hpp"

#include <algorithm>
#include <cmath>

#include "core/error.hpp"
#include "geometry/shape_fields.hpp"
#include "geometry/shape_model.hpp"
#include "geometry/stl_mesh.hpp"

namespace cisamr::geometry {

namespace {

class StlModel final : public SurfaceModel {
 public:
  // Throws for a bad transform and, at field ".file", for a surface that is open,
  // non-manifold, self-intersecting or inconsistently oriented (naming the first bad face).
  StlModel(const Shape& shape, const std::string& src, const std::string& field) : SurfaceModel(shape) {
    const StlSurface& st = std::get<StlSurface>(shape);
    if (!(st.scale > 0) || !std::isfinite(st.scale)) throw InputError(src, field + ".scale", "must be positive");
    if (!orthonormal(st.rotation)) throw InputError(src, field + ".rotation", "must be orthonormal");
    if (!finite(st.translate)) throw InputError(src, field + ".translate", "must be finite");
    const std::string problem = stl::build(st, mesh_, true);
    if (!problem.empty()) throw InputError(src, field + ".file", st.file + ": " + problem);
    box_ = mesh_.box;
  }

  int side(const Vec3& p) const override { return stl::side(mesh_, p); }

  bool segment_events(const Vec3& a, const Vec3& b, const Box3&, EventSink& sink,
                      std::vector<double>& ts) const override {
    ts.clear();
    stl::segment_hits(mesh_, a, b, ts);
    return events_from_hits<3>(a, sub(b, a), ts, sink, [&](const Vec3& q) { return stl::side(mesh_, q) >= 0; });
  }

  double boundary_distance(const Vec3& p) const override { return stl::distance_to_surface(mesh_, p); }
  bool boundary_touches(const Box3& box) const override { return stl::touches_box(mesh_, box); }
  double measure() const override { return stl::volume(mesh_); }

  void x_breakpoints(std::vector<double>& out) const override {
    if (mesh_.vertices.size() <= 512)
      for (const Vec3& v : mesh_.vertices) out.push_back(v[0]);
  }

  void y_breakpoints_at(double x, std::vector<double>& out) const override {
    if (mesh_.faces.size() <= 4096) stl::edge_crossings_at_x(mesh_, x, out);
  }

  // Two meshes: an edge of one piercing the other (the oracle adds boundary samples).
  std::optional<bool> regions_intersect(const ShapeModel<3>& other, bool, double) const override {
    const auto* o = dynamic_cast<const StlModel*>(&other);
    if (!o) return std::nullopt;
    std::vector<double> ts;
    const StlModel* pair[2] = {this, o};
    for (int w = 0; w < 2; ++w) {
      const stl::Mesh& m = pair[w]->mesh_;
      const stl::Mesh& target = pair[1 - w]->mesh_;
      for (const auto& f : m.faces)
        for (int e = 0; e < 3; ++e) {
          ts.clear();
          stl::segment_hits(target, m.vertices[f[e]], m.vertices[f[(e + 1) % 3]], ts);
          if (!ts.empty()) return true;
        }
    }
    return std::nullopt;
  }

  void nearest_boundary_points(const Vec3&, std::vector<Vec3>& out) const override {
    const std::vector<Vec3> samples = boundary_points(256);
    out.insert(out.end(), samples.begin(), samples.end());
  }

  // The vertices and face centroids (whatever per_axis).
  std::vector<Vec3> boundary_points(int) const override {
    std::vector<Vec3> pts = mesh_.vertices;
    for (const auto& f : mesh_.faces) {
      Vec3 c{};
      for (int d = 0; d < 3; ++d)
        c[d] = (mesh_.vertices[f[0]][d] + mesh_.vertices[f[1]][d] + mesh_.vertices[f[2]][d]) / 3;
      pts.push_back(c);
    }
    return pts;
  }

 private:
  stl::Mesh mesh_;
};

}  // namespace

// ---------------------------------------------------------------- scene descriptors

namespace {

// Unvalidated (the oracle's model validates): geometry of whatever the file holds.
stl::Mesh mesh_of(const StlSurface& s) {
  stl::Mesh m;
  stl::build(s, m, false);
  return m;
}

class StlFamily final : public FamilyOf<StlSurface> {
 public:
  std::string_view name() const override { return "stl"; }
  int dimension() const override { return 3; }
  Shape read(const FieldReader& f) const override {
    f.allow_keys({"file", "scale", "rotation", "translate"});
    StlSurface s;
    SurfaceFile file = f.surface_file("file");
    s.file = std::move(file.path);
    s.triangles = std::move(file.triangles);
    read_placement(f, s);
    return s;
  }
  void write(const Shape& shape, FieldWriter& f) const override {
    const StlSurface& s = of(shape);
    f.file("file", s.file);
    write_placement(s, f);
  }
  // A surface whose triangles are not loaded (a parallel rank that did not read the file)
  // has an empty box, no measure, no samples and contains nothing.
  Box3 bounding_box(const Shape& s) const override {
    if (of(s).triangles.empty()) return {};
    return mesh_of(of(s)).box;
  }
  double measure(const Shape& s) const override { return of(s).triangles.empty() ? 0.0 : stl::volume(mesh_of(of(s))); }
  double boundary_measure(const Shape& s) const override {
    return of(s).triangles.empty() ? 0.0 : stl::surface_area(mesh_of(of(s)));
  }
  std::vector<Vec3> boundary_samples(const Shape& s, double spacing) const override {
    // Vertices, then a barycentric grid on each face fine enough for `spacing`.
    std::vector<Vec3> out;
    if (of(s).triangles.empty()) return out;
    const stl::Mesh m = mesh_of(of(s));
    out = m.vertices;
    for (const auto& f : m.faces) {
      const Vec3 &a = m.vertices[f[0]], &b = m.vertices[f[1]], &c = m.vertices[f[2]];
      const double longest = std::max({norm(Vec3{b[0] - a[0], b[1] - a[1], b[2] - a[2]}),
                                       norm(Vec3{c[0] - b[0], c[1] - b[1], c[2] - b[2]}),
                                       norm(Vec3{a[0] - c[0], a[1] - c[1], a[2] - c[2]})});
      const int n = std::max(1, static_cast<int>(std::ceil(longest / spacing)));
      for (int i = 0; i <= n; ++i)
        for (int j = 0; i + j <= n; ++j) {
          if ((i == 0 && j == 0) || (i == n) || (j == n)) continue;  // vertices already in
          const double u = double(i) / n, v = double(j) / n, w = 1 - u - v;
          out.push_back({w * a[0] + u * b[0] + v * c[0], w * a[1] + u * b[1] + v * c[1], w * a[2] + u * b[2] + v * c[2]});
        }
    }
    return out;
  }
  bool contains(const Shape& s, const Vec3& p) const override {
    return !of(s).triangles.empty() && stl::side(mesh_of(of(s)), p) >= 0;
  }
  bool contains_any(const Shape& s, const std::vector<Vec3>& points) const override {
    if (of(s).triangles.empty() || points.empty()) return false;
    const stl::Mesh m = mesh_of(of(s));
    for (const Vec3& p : points)
      if (stl::side(m, p) >= 0) return true;
    return false;
  }
  void translate(Shape& s, const Vec3& o) const override {
    for (int k = 0; k < 3; ++k) of(s).translate[k] += o[k];
  }
  bool judged_by_box() const override { return true; }
  // Besides the sampled test of shapes_overlap: a mesh edge piercing the other mesh.
  bool edges_pierce(const Shape& a, const Shape& b) const override {
    const stl::Mesh ma = mesh_of(of(a)), mb = mesh_of(of(b));
    std::vector<double> ts;
    for (const auto& f : ma.faces)
      for (int e = 0; e < 3; ++e) {
        stl::segment_hits(mb, ma.vertices[f[e]], ma.vertices[f[(e + 1) % 3]], ts);
        if (!ts.empty()) return true;
      }
    return false;
  }
  std::unique_ptr<SurfaceModel> surface_model(const Shape& s, const std::string& source,
                                              const std::string& field) const override {
    return std::make_unique<StlModel>(s, source, field);
  }
};

}  // namespace

const ShapeFamily& stl_family() {
  static const StlFamily family;
  return family;
}

}  // namespace cisamr::geometry
