#pragma once
// What both dimensions' refined grids keep per forest cell: the inclusions whose boundary
// may meet it (samr2.hpp, samr3.hpp say how closely), in an append-only pool where a
// refined cell's children append the part of its list that still applies.
#include <cstdint>
#include <span>
#include <vector>

namespace cisamr::samr {

struct TouchLists {
  std::vector<std::int32_t> touch_begin;
  std::vector<std::uint16_t> touch_count;
  std::vector<std::int32_t> touch_pool;

  std::span<const std::int32_t> touched(std::int32_t c) const {
    return {touch_pool.data() + touch_begin[static_cast<std::size_t>(c)], touch_count[static_cast<std::size_t>(c)]};
  }
  bool is_cut(std::int32_t c) const { return touch_count[static_cast<std::size_t>(c)] > 0; }
};

}  // namespace cisamr::samr
