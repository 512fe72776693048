#pragma once
// A small exact tet mesh for the tests: integer node coordinates, nodes merged by
// coordinates, and a conformity check by face matching (no floating point involved).
#include <algorithm>
#include <array>
#include <cstdint>
#include <map>
#include <string>
#include <vector>

#include "grid/tet_lattice.hpp"

namespace cisamr::grid::testing {

struct ExactMesh3 {
  std::vector<LatticePoint3> nodes;
  std::vector<std::array<std::int32_t, 4>> tets;
  std::map<LatticePoint3, std::int32_t> index;

  std::int32_t node(const LatticePoint3& p) {
    auto [it, inserted] = index.emplace(p, static_cast<std::int32_t>(nodes.size()));
    if (inserted) nodes.push_back(p);
    return it->second;
  }
  void add(const LatticePoint3& a, const LatticePoint3& b, const LatticePoint3& c, const LatticePoint3& d) {
    tets.push_back({node(a), node(b), node(c), node(d)});
  }
  std::int64_t orient(std::size_t t) const {
    const auto& n = tets[t];
    return tet::orient(nodes[n[0]], nodes[n[1]], nodes[n[2]], nodes[n[3]]);
  }
};

struct ConformityResult {
  std::size_t non_positive = 0;        // tets with orient <= 0
  std::size_t interior_unmatched = 0;  // faces used once, not on the box boundary
  std::size_t same_orientation = 0;    // faces used twice with the same orientation
  std::size_t over_used = 0;           // faces used three times or more
  std::size_t boundary_faces = 0;
  std::int64_t volume6 = 0;  // six times the total volume
  std::string first_problem;
  bool ok(std::int64_t expected_volume6) const {
    return non_positive == 0 && interior_unmatched == 0 && same_orientation == 0 && over_used == 0 &&
           volume6 == expected_volume6;
  }
};

// Faces shared by exactly two tets with opposite orientation, or lying on a face of the
// box [lo, hi]; every tet positive.
inline ConformityResult check_conformity(const ExactMesh3& m, const LatticePoint3& lo, const LatticePoint3& hi) {
  ConformityResult r;
  // Key: sorted node triple; value: list of orientation parities (+1 / -1).
  std::map<std::array<std::int32_t, 3>, std::vector<int>> faces;
  static constexpr int kFace[4][3] = {{1, 2, 3}, {0, 3, 2}, {0, 1, 3}, {0, 2, 1}};
  for (std::size_t t = 0; t < m.tets.size(); ++t) {
    const std::int64_t o = m.orient(t);
    if (o <= 0) {
      ++r.non_positive;
      if (r.first_problem.empty()) r.first_problem = "non-positive tet " + std::to_string(t);
    }
    r.volume6 += o;
    for (const auto& f : kFace) {
      std::array<std::int32_t, 3> v = {m.tets[t][f[0]], m.tets[t][f[1]], m.tets[t][f[2]]};
      // Parity of the permutation that sorts v.
      int parity = 1;
      for (int i = 0; i < 3; ++i)
        for (int j = i + 1; j < 3; ++j)
          if (v[i] > v[j]) parity = -parity;
      std::sort(v.begin(), v.end());
      faces[v].push_back(parity);
    }
  }
  for (const auto& [f, uses] : faces) {
    if (uses.size() == 1) {
      bool on_box = false;
      for (int d = 0; d < 3 && !on_box; ++d)
        for (std::int64_t plane : {lo[d], hi[d]}) {
          bool all = true;
          for (std::int32_t n : f) all = all && m.nodes[static_cast<std::size_t>(n)][d] == plane;
          on_box = on_box || all;
        }
      if (on_box) {
        ++r.boundary_faces;
      } else {
        ++r.interior_unmatched;
        if (r.first_problem.empty()) {
          r.first_problem = "unmatched face";
          for (std::int32_t n : f) {
            const auto& p = m.nodes[static_cast<std::size_t>(n)];
            r.first_problem += " (" + std::to_string(p[0]) + "," + std::to_string(p[1]) + "," + std::to_string(p[2]) + ")";
          }
        }
      }
    } else if (uses.size() == 2) {
      if (uses[0] == uses[1]) ++r.same_orientation;
    } else {
      ++r.over_used;
    }
  }
  return r;
}

}  // namespace cisamr::grid::testing
