// The oracle's view of a surface body (NURBS patches, STEP solids) (README: shape concept; design in
// docs/nurbs-step-design.md §2.3–2.5): classification, crossings, touches, distances and
// the volume, all through surface_body on the exact surface.
#include "geometry/nurbs_surface_model.hpp"

#include <cmath>

#include "core/error.hpp"
#include "geometry/shape_model.hpp"
#include "geometry/surface_body.hpp"

namespace cisamr::geometry {
namespace {

class BodyModel final : public SurfaceModel {
 public:
  BodyModel(const Shape& shape, std::shared_ptr<const surface::Body> body) : SurfaceModel(shape), body_(std::move(body)) {
    box_ = body_->box;
  }

  int side(const Vec3& p) const override { return surface::side(*body_, p); }

  bool segment_events(const Vec3& a, const Vec3& b, const Box3&, EventSink& sink,
                      std::vector<double>& ts) const override {
    ts.clear();
    surface::segment_roots(*body_, a, b, ts);
    // A root at an end that is ON the surface is that end, not a crossing inside.
    const double len = norm(sub(b, a));
    const double near_end = 4 * body_->tolerance / len;
    if (!ts.empty() && ts.front() <= near_end && surface::side(*body_, a) == 0) ts.erase(ts.begin());
    if (!ts.empty() && ts.back() >= 1 - near_end && surface::side(*body_, b) == 0) ts.pop_back();
    return events_from_hits<3>(a, sub(b, a), ts, sink, [&](const Vec3& q) { return surface::side(*body_, q) >= 0; });
  }

  double boundary_distance(const Vec3& p) const override { return surface::distance(*body_, p); }
  bool boundary_touches(const Box3& box) const override { return surface::touches_box(*body_, box); }
  double measure() const override { return surface::volume(*body_); }

  bool outward_normal(const Vec3& p, Vec3& n) const override {
    surface::distance(*body_, p, &n);
    return dot(n, n) > 0;
  }

  void nearest_boundary_points(const Vec3& p, std::vector<Vec3>& out) const override {
    // The tessellation vertices (surface points) and the nearest surface point.
    out.insert(out.end(), body_->mesh.vertices.begin(), body_->mesh.vertices.end());
    Vec3 n;
    const double d = surface::distance(*body_, p, &n);
    if (std::isfinite(d) && dot(n, n) > 0) {
      const Vec3 u = scale(n, 1 / norm(n));
      // p lies on the normal line through its nearest point, on the side its classification says.
      const int s = surface::side(*body_, p);
      out.push_back(add(p, scale(u, s > 0 ? d : -d)));
    }
  }

  bool approximate_sections() const override { return true; }
  void x_breakpoints(std::vector<double>& out) const override { surface::x_extremes(*body_, out); }
  void y_breakpoints_at(double x, std::vector<double>& out) const override { surface::y_extremes_at(*body_, x, out); }

  std::vector<Vec3> boundary_points(int per_axis) const override {
    return surface::surface_points(*body_, body_->size / std::max(per_axis, 1));
  }

 private:
  std::shared_ptr<const surface::Body> body_;
};

}  // namespace

std::unique_ptr<SurfaceModel> make_nurbs_surface_model(const Shape& shape, const std::string& source,
                                                       const std::string& field) {
  std::string problem;
  auto body = surface::cached_body(std::get<NurbsSurface>(shape), &problem);
  if (!body) {
    // The problem starts with the field suffix: ".patches[2].v_max: ...".
    const std::size_t colon = problem.find(": ");
    const std::string suffix = colon == std::string::npos ? "" : problem.substr(0, colon);
    const std::string what = colon == std::string::npos ? problem : problem.substr(colon + 2);
    throw InputError(source, field + suffix, what);
  }
  return std::make_unique<BodyModel>(shape, std::move(body));
}

std::unique_ptr<SurfaceModel> make_body_model(const Shape& shape, std::shared_ptr<const surface::Body> body) {
  return std::make_unique<BodyModel>(shape, std::move(body));
}

}  // namespace cisamr::geometry
