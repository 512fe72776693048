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

}  // namespace cisamr::quality::detail
