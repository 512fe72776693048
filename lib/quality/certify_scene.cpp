// Certification against a scene: the domain, the expected measure and (2D) phase fidelity
// come from the scene. Kept apart from certificate.cpp so that users of the scene-free
// certificate do not link the geometry oracle.
#include <algorithm>
#include <cstdio>

#include "geometry/oracle.hpp"
#include "geometry/scene.hpp"
#include "quality/certificate.hpp"

namespace cisamr::quality {
namespace {

template <int Dim>
Box<Dim> scene_domain(const geometry::SceneDesc& scene) {
  Box<Dim> b;
  for (int d = 0; d < Dim; ++d) b.min[d] = scene.domain_min[d], b.max[d] = scene.domain_max[d];
  return b;
}

template <int Dim>
double box_measure(const Box<Dim>& b) {
  double v = 1;
  for (int d = 0; d < Dim; ++d) v *= b.max[d] - b.min[d];
  return v;
}

bool has_void(const geometry::SceneDesc& scene) {
  return std::any_of(scene.phases.begin(), scene.phases.end(), [](const geometry::Phase& p) { return p.is_void; });
}

void describe_scene(const geometry::SceneDesc& scene, Certificate& c) {
  c.scene_source = scene.source;
  c.domain_from_scene = true;
  for (const geometry::Phase& p : scene.phases) c.phase_names.emplace_back(p.id, p.name);
}

}  // namespace

Certificate certify(const mesh::Mesh2& m, const geometry::Oracle2& oracle, const CertifyOptions& options) {
  const geometry::SceneDesc& scene = oracle.scene();
  const Box2 domain = scene_domain<2>(scene);
  CertifyOptions o = options;
  o.allow_inner_boundary = has_void(scene);
  double expected = box_measure(domain);
  const std::vector<double> areas = oracle.phase_measures();
  for (std::size_t k = 0; k < scene.phases.size() && k < areas.size(); ++k)
    if (scene.phases[k].is_void) expected -= areas[k];
  o.expected_measure = expected;
  if (o.allow_inner_boundary) o.measure_tolerance = std::max(o.measure_tolerance, kVoidMeasureTolerance);

  Certificate c = certify<2>(m, domain, o);
  describe_scene(scene, c);
  if (o.allow_inner_boundary) {
    char buf[200];
    std::snprintf(buf, sizeof buf,
                  "the scene has voids: total measure checked to %g only (void boundaries are polygonal); "
                  "open facets inside the domain are checked to lie on a void instead",
                  o.measure_tolerance);
    c.notes.push_back(buf);
  }
  const double tol = options.fidelity_tolerance >= 0 ? options.fidelity_tolerance : default_fidelity_tolerance(scene);
  c.fidelity = check_fidelity(m, oracle, tol);
  return c;
}

Certificate certify(const mesh::Mesh3& m, const geometry::SceneDesc& scene, const CertifyOptions& options) {
  const Box3 domain = scene_domain<3>(scene);
  CertifyOptions o = options;
  o.allow_inner_boundary = has_void(scene);
  o.expected_measure = o.allow_inner_boundary ? -1 : box_measure(domain);
  Certificate c = certify<3>(m, domain, o);
  describe_scene(scene, c);
  if (o.allow_inner_boundary) {
    c.notes.erase(std::remove_if(c.notes.begin(), c.notes.end(),
                                 [](const std::string& n) { return n.rfind("total measure", 0) == 0; }),
                  c.notes.end());
    c.notes.push_back("the scene has voids: total volume not checked (certified without the geometry oracle)");
  }
  c.notes.push_back("phase fidelity not checked (certified without the geometry oracle)");
  return c;
}

}  // namespace cisamr::quality
