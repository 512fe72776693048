#pragma once
// Basic identifiers and small fixed-size vectors shared by every module.
#include <array>
#include <cstdint>

namespace cisamr {

using LocalId = std::int32_t;   // index into this process's arrays
using GlobalId = std::int64_t;  // id across all partitions and ranks
using PhaseMask = std::uint64_t;  // bit i = phase index i (at most 64 phases)

// Exactly one / two phases in a mask (bit tricks: std::popcount is a library call on
// baseline x86-64, and the 3D snapping guard asks this tens of millions of times).
constexpr bool single_bit(PhaseMask m) { return m != 0 && (m & (m - 1)) == 0; }
constexpr bool two_bits(PhaseMask m) { return m != 0 && single_bit(m & (m - 1)); }

template <int Dim>
using Vec = std::array<double, Dim>;
using Vec2 = Vec<2>;
using Vec3 = Vec<3>;

template <int Dim>
struct Box {
  Vec<Dim> min{};
  Vec<Dim> max{};
};
using Box2 = Box<2>;
using Box3 = Box<3>;

template <int Dim>
inline bool boxes_overlap(const Box<Dim>& a, const Box<Dim>& b) {
  for (int d = 0; d < Dim; ++d)
    if (a.max[d] < b.min[d] || b.max[d] < a.min[d]) return false;
  return true;
}

}  // namespace cisamr
