#pragma once
// Internal to lib/quality: what the checks against a scene read from it and its oracle,
// for either dimension.
#include <vector>

#include "core/types.hpp"
#include "geometry/scene.hpp"
#include "quality/quality.hpp"

namespace cisamr::quality::detail {

template <int Dim>
inline Box<Dim> scene_domain(const geometry::SceneDesc& scene) {
  Box<Dim> b;
  for (int d = 0; d < Dim; ++d) b.min[d] = scene.domain_min[d], b.max[d] = scene.domain_max[d];
  return b;
}

// The exact (or integrated) measure of each phase inside the domain, by phase index.
template <int Dim>
inline std::vector<double> exact_phase_measures(const OracleOf<Dim>& oracle) {
  if constexpr (Dim == 2)
    return oracle.phase_areas();
  else
    return oracle.phase_volumes();
}

}  // namespace cisamr::quality::detail
