#pragma once
// Phase volumes of a 3D scene for the property suites, by sampling (the oracle's own
// integration of clipped or overlapping shapes takes seconds per scene).
#include <cmath>
#include <cstdint>
#include <variant>
#include <vector>

#include "geometry/oracle.hpp"

namespace cisamr::testing {

// Reference phase volumes: exact from the oracle when every inclusion is a sphere apart
// from the others (closed forms); otherwise the midpoint rule on a grid of h/6 with
// phase_at (relative error ~1e-3 on the resolved scenes where volumes are checked, well
// below the 10 % asserted; the oracle's own integration of clipped or overlapping shapes
// takes seconds per scene).
// `closed_form` false: always sample (periodic scenes clip every sphere across a face).
inline std::vector<double> reference_volumes(const geometry::Oracle3& oracle, bool closed_form = true) {
  const geometry::SceneDesc& s = oracle.scene();
  for (int i = 0; i < oracle.inclusion_count(); ++i)
    closed_form = closed_form && oracle.interface_group(i) == i &&
                  std::holds_alternative<geometry::Sphere>(s.inclusions[std::size_t(i)].shape);
  if (closed_form) return oracle.phase_measures();
  std::vector<double> volume(s.phases.size(), 0.0);
  const double step = s.h / 6;
  int n[3];
  for (int d = 0; d < 3; ++d) n[d] = static_cast<int>(std::lround((s.domain_max[d] - s.domain_min[d]) / step));
  double size[3];
  for (int d = 0; d < 3; ++d) size[d] = (s.domain_max[d] - s.domain_min[d]) / n[d];
  const double cell = size[0] * size[1] * size[2];
  std::vector<std::int32_t> candidates;
  for (int i = 0; i < n[0]; ++i)
    for (int j = 0; j < n[1]; ++j) {
      // One candidate query per column.
      const Box3 column{{s.domain_min[0] + i * size[0], s.domain_min[1] + j * size[1], s.domain_min[2]},
                        {s.domain_min[0] + (i + 1) * size[0], s.domain_min[1] + (j + 1) * size[1], s.domain_max[2]}};
      oracle.candidates(column, candidates);
      for (int k = 0; k < n[2]; ++k) {
        const Vec3 p{s.domain_min[0] + (i + 0.5) * size[0], s.domain_min[1] + (j + 0.5) * size[1],
                     s.domain_min[2] + (k + 0.5) * size[2]};
        volume[std::size_t(oracle.phase_at(p, candidates))] += cell;
      }
    }
  return volume;
}

}  // namespace cisamr::testing
