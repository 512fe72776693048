#pragma once
// What both dimensions' refined grids keep per forest cell: the inclusions whose boundary
// may meet it (samr2.hpp, samr3.hpp say how closely), in an append-only pool where a
// refined cell's children append the part of its list that still applies; and per coarse
// cell of the range, the candidates the later stages ask the oracle about.
#include <cstdint>
#include <span>
#include <vector>

namespace cisamr::samr {

struct TouchLists {
  std::vector<std::int32_t> touch_begin;
  std::vector<std::uint16_t> touch_count;
  std::vector<std::int32_t> touch_pool;

  // Not after release_lists().
  std::span<const std::int32_t> touched(std::int32_t c) const {
    return {touch_pool.data() + touch_begin[static_cast<std::size_t>(c)], touch_count[static_cast<std::size_t>(c)]};
  }
  bool is_cut(std::int32_t c) const { return touch_count[static_cast<std::size_t>(c)] > 0; }
  // After refinement the later stages ask only whether a cell is cut: the lists go (a sixth
  // of the 3D mesher's peak memory, validation/bench/MEMORY.md), the counts stay.
  void release_lists() {
    std::vector<std::int32_t>().swap(touch_begin);
    std::vector<std::int32_t>().swap(touch_pool);
  }
  // Appends the next cell's list: those of cell `parent`'s inclusions whose boundary touches
  // `box` (the cell's closed bounding box; oracle.boundary_touches(k, box)). Returns its
  // length. Both dimensions' refinements make their children's lists this way.
  template <class Oracle, class Box>
  std::uint16_t append_touching(const Oracle& oracle, std::int32_t parent, const Box& box) {
    const std::int32_t begin = touch_begin[static_cast<std::size_t>(parent)];
    const std::uint16_t count = touch_count[static_cast<std::size_t>(parent)];
    touch_begin.push_back(static_cast<std::int32_t>(touch_pool.size()));
    std::uint16_t n = 0;
    for (std::uint16_t i = 0; i < count; ++i) {
      const std::int32_t k = touch_pool[static_cast<std::size_t>(begin + i)];
      if (oracle.boundary_touches(k, box)) {
        touch_pool.push_back(k);
        ++n;
      }
    }
    touch_count.push_back(n);
    return n;
  }
};

// Per coarse cell of the range (2D: the forest's roots; 3D: the cubes, x fastest): the
// inclusions whose bounding box meets the closed cell, ascending (CSR).
struct CellCandidates {
  std::vector<std::int32_t> begin;  // cells + 1
  std::vector<std::int32_t> list;

  std::span<const std::int32_t> of(std::int64_t cell) const {
    const auto b = static_cast<std::size_t>(begin[static_cast<std::size_t>(cell)]);
    const auto e = static_cast<std::size_t>(begin[static_cast<std::size_t>(cell) + 1]);
    return {list.data() + b, e - b};
  }
};

}  // namespace cisamr::samr
