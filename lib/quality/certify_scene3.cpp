// Certification of a 3D mesh against a scene: domain and expected volume (domain minus
// the exact void volumes) from the oracle, and 3D phase fidelity. Apart from
// certify_scene.cpp so that 2D programs do not link the 3D oracle.
#include <algorithm>
#include <cstdio>

#include "geometry/oracle.hpp"
#include "geometry/scene.hpp"
#include "quality/certificate.hpp"

namespace cisamr::quality {

Certificate certify(const mesh::Mesh3& m, const geometry::Oracle3& oracle, const CertifyOptions& options) {
  const geometry::SceneDesc& scene = oracle.scene();
  Box3 domain;
  for (int d = 0; d < 3; ++d) domain.min[d] = scene.domain_min[d], domain.max[d] = scene.domain_max[d];
  CertifyOptions o = options;
  o.allow_inner_boundary =
      std::any_of(scene.phases.begin(), scene.phases.end(), [](const geometry::Phase& p) { return p.is_void; });
  const std::vector<double> volumes = oracle.phase_measures();
  double expected = (domain.max[0] - domain.min[0]) * (domain.max[1] - domain.min[1]) * (domain.max[2] - domain.min[2]);
  for (std::size_t k = 0; k < scene.phases.size() && k < volumes.size(); ++k)
    if (scene.phases[k].is_void) expected -= volumes[k];
  o.expected_measure = expected;
  if (o.allow_inner_boundary) o.measure_tolerance = std::max(o.measure_tolerance, kVoidMeasureTolerance);

  Certificate c = certify<3>(m, domain, o);
  c.scene_source = scene.source;
  c.domain_from_scene = true;
  for (const geometry::Phase& p : scene.phases) c.phase_names.emplace_back(p.id, p.name);
  if (o.allow_inner_boundary) {
    char buf[200];
    std::snprintf(buf, sizeof buf,
                  "the scene has voids: total volume checked to %g only (void boundaries are polyhedral); "
                  "open facets inside the domain are checked to lie on a void instead",
                  o.measure_tolerance);
    c.notes.push_back(buf);
  }
  const double tol = options.fidelity_tolerance >= 0 ? options.fidelity_tolerance : default_fidelity_tolerance(scene);
  c.fidelity = check_fidelity(m, oracle, tol, volumes);
  return c;
}

}  // namespace cisamr::quality
