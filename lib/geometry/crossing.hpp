#pragma once
// One phase change along a segment: the answer type of Oracle2/Oracle3::crossings.
#include <cstdint>

namespace cisamr::geometry {

struct Crossing {
  double t = 0;            // parameter in (0,1) along a→b
  std::int32_t inclusion = -1;  // the inclusion whose boundary is crossed (smallest id on ties)
  std::int32_t from_phase = -1; // phase index just before t
  std::int32_t to_phase = -1;   // phase index just after t
};

}  // namespace cisamr::geometry
