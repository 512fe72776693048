// Certification against a scene, 2D and 3D: the domain, the expected measure (domain minus
// the exact void measures) and phase fidelity come from the scene's oracle. Kept apart
// from certificate.cpp so that users of the scene-free certificate do not link the oracles.
#include <algorithm>
#include <cstdio>

#include "geometry/periodic.hpp"
#include "quality/certificate.hpp"
#include "quality/pieces_internal.hpp"
#include "quality/scene_queries.hpp"

namespace cisamr::quality {
namespace {

template <int Dim>
double box_measure(const Box<Dim>& b) {
  double v = 1;
  for (int d = 0; d < Dim; ++d) v *= b.max[d] - b.min[d];
  return v;
}

// How the certificate's note names the total measure and the meshed void boundaries.
template <int Dim>
constexpr const char* kMeasureName = Dim == 2 ? "measure" : "volume";
template <int Dim>
constexpr const char* kMeshedBoundary = Dim == 2 ? "polygonal" : "polyhedral";

}  // namespace

namespace detail {

template <int Dim>
SceneTerms<Dim> scene_terms(const geometry::Oracle<Dim>& oracle, const CertifyOptions& options) {
  const geometry::SceneDesc& scene = oracle.scene();
  SceneTerms<Dim> t;
  t.domain = scene_domain<Dim>(scene);
  CertifyOptions& o = t.options;
  o = options;
  o.allow_inner_boundary =
      std::any_of(scene.phases.begin(), scene.phases.end(), [](const geometry::Phase& p) { return p.is_void; });
  t.exact_measures = oracle.phase_measures();
  double expected = box_measure(t.domain);
  for (std::size_t k = 0; k < scene.phases.size() && k < t.exact_measures.size(); ++k)
    if (scene.phases[k].is_void) expected -= t.exact_measures[k];
  o.expected_measure = expected;
  if (o.allow_inner_boundary) {
    o.measure_tolerance = std::max(o.measure_tolerance, kVoidMeasureTolerance);
    char buf[200];
    std::snprintf(buf, sizeof buf,
                  "the scene has voids: total %s checked to %g only (void boundaries are %s); "
                  "open facets inside the domain are checked to lie on a void instead",
                  kMeasureName<Dim>, o.measure_tolerance, kMeshedBoundary<Dim>);
    t.void_note = buf;
  }
  t.fidelity_tolerance = options.fidelity_tolerance >= 0 ? options.fidelity_tolerance : default_fidelity_tolerance(scene);
  return t;
}

template SceneTerms<2> scene_terms<2>(const geometry::Oracle<2>&, const CertifyOptions&);
template SceneTerms<3> scene_terms<3>(const geometry::Oracle<3>&, const CertifyOptions&);

}  // namespace detail

template <int Dim>
Certificate certify(const mesh::SimplexMesh<Dim>& m, const geometry::Oracle<Dim>& oracle, const CertifyOptions& options) {
  const geometry::SceneDesc& scene = oracle.scene();
  const detail::SceneTerms<Dim> terms = detail::scene_terms<Dim>(oracle, options);
  const Box<Dim>& domain = terms.domain;
  Certificate c = certify<Dim>(m, domain, terms.options);
  c.scene_source = scene.source;
  c.domain_from_scene = true;
  for (const geometry::Phase& p : scene.phases) c.phase_names.emplace_back(p.id, p.name);
  if (!terms.void_note.empty()) c.notes.push_back(terms.void_note);
  c.fidelity = check_fidelity<Dim>(m, oracle, terms.fidelity_tolerance, terms.exact_measures);
  if (scene.any_periodic()) {
    // The faces where the mesher puts them: min, and min + N·h (the period) on a periodic axis.
    Box<Dim> faces = domain;
    std::array<bool, Dim> axes{};
    const Vec3 period = geometry::periods(scene);
    for (int d = 0; d < Dim; ++d) {
      axes[static_cast<std::size_t>(d)] = scene.periodic[static_cast<std::size_t>(d)];
      if (axes[static_cast<std::size_t>(d)]) faces.max[d] = faces.min[d] + period[d];
    }
    std::vector<std::int32_t> candidates;
    const auto in_void = [&](const Vec<Dim>& p) {
      Box<Dim> at;
      at.min = at.max = p;
      oracle.candidates(at, candidates);
      return scene.phases[static_cast<std::size_t>(oracle.phase_at(p, candidates))].is_void;
    };
    c.periodic = check_periodic<Dim>(m, faces, axes, in_void);
  }
  return c;
}

template Certificate certify<2>(const mesh::SimplexMesh<2>&, const geometry::Oracle<2>&, const CertifyOptions&);
template Certificate certify<3>(const mesh::SimplexMesh<3>&, const geometry::Oracle<3>&, const CertifyOptions&);

}  // namespace cisamr::quality
