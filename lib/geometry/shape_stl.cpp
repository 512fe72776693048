// STL surfaces (README: classification, crossings, volumes, distances).
#include "geometry/shape_stl.hpp"

#include "core/error.hpp"
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

std::unique_ptr<SurfaceModel> make_stl_model(const Shape& shape, const std::string& source, const std::string& field) {
  return std::make_unique<StlModel>(shape, source, field);
}

}  // namespace cisamr::geometry
