#include "parallel/checksum.hpp"

#include <algorithm>
#include <cstring>

#include "parallel/exchange.hpp"

namespace cisamr::parallel {
namespace {

std::uint64_t bits(double v) {
  if (v == 0) v = 0;  // -0 and +0 are the same point
  std::uint64_t b;
  std::memcpy(&b, &v, sizeof b);
  return b;
}

// Even permutations of the cell's vertices: the rotations of a triangle; for a tet, each
// vertex first followed by a rotation of the other three in their oriented order.
template <int Dim>
constexpr auto kEvenPermutations = [] {
  if constexpr (Dim == 2) {
    return std::array<std::array<int, 3>, 3>{{{0, 1, 2}, {1, 2, 0}, {2, 0, 1}}};
  } else {
    return std::array<std::array<int, 4>, 12>{{{0, 1, 2, 3}, {0, 2, 3, 1}, {0, 3, 1, 2}, {1, 0, 3, 2},
                                               {1, 3, 2, 0}, {1, 2, 0, 3}, {2, 0, 1, 3}, {2, 1, 3, 0},
                                               {2, 3, 0, 1}, {3, 0, 2, 1}, {3, 2, 1, 0}, {3, 1, 0, 2}}};
  }
}();

// The even permutation (its index in kEvenPermutations) starting with vertex `lead` and,
// for a tet, going on with vertex `second` (each pair of distinct vertices starts exactly
// one; a triangle's lead alone picks its rotation, `second` is ignored).
template <int Dim>
constexpr auto kEvenByLeadAndSecond = [] {
  std::array<std::array<int, Dim + 1>, Dim + 1> at{};
  for (std::size_t i = 0; i < kEvenPermutations<Dim>.size(); ++i) {
    const auto& perm = kEvenPermutations<Dim>[i];
    if constexpr (Dim == 2)
      at[static_cast<std::size_t>(perm[0])].fill(static_cast<int>(i));
    else
      at[static_cast<std::size_t>(perm[0])][static_cast<std::size_t>(perm[1])] = static_cast<int>(i);
  }
  return at;
}();

template <int Dim>
CanonicalSimplex<Dim> canonical(const mesh::SimplexMesh<Dim>& m, std::size_t c) {
  constexpr int kCorners = Dim + 1;
  std::array<std::array<std::uint64_t, Dim>, kCorners> v;
  for (int k = 0; k < kCorners; ++k) {
    const auto n = static_cast<std::size_t>(m.cell_nodes[kCorners * c + static_cast<std::size_t>(k)]);
    for (int d = 0; d < Dim; ++d) v[static_cast<std::size_t>(k)][static_cast<std::size_t>(d)] = bits(m.coords[Dim * n + d]);
  }
  CanonicalSimplex<Dim> best;
  best.phase = m.cell_phase[c];
  // With distinct vertices the smallest even permutation starts at the smallest vertex and
  // goes on with the smallest of the others (each is second in exactly one rotation that
  // starts there): two scans and a table instead of comparing every permutation (the
  // checksum of a 190 M-tet mesh took seconds per rank). A cell with coincident vertices
  // searches them all.
  const auto less = [&](int a, int b) { return v[static_cast<std::size_t>(a)] < v[static_cast<std::size_t>(b)]; };
  bool distinct = true;
  for (int a = 0; a < kCorners; ++a)
    for (int b = a + 1; b < kCorners; ++b) distinct = distinct && v[static_cast<std::size_t>(a)] != v[static_cast<std::size_t>(b)];
  if (distinct) {
    int lead = 0;
    for (int k = 1; k < kCorners; ++k)
      if (less(k, lead)) lead = k;
    int second = -1;
    for (int k = 0; k < kCorners; ++k)
      if (k != lead && (second < 0 || less(k, second))) second = k;
    const auto& pick = kEvenPermutations<Dim>[kEvenByLeadAndSecond<Dim>[static_cast<std::size_t>(lead)][static_cast<std::size_t>(second)]];
    for (int k = 0; k < kCorners; ++k)
      for (int d = 0; d < Dim; ++d)
        best.xyz[static_cast<std::size_t>(Dim * k + d)] = v[static_cast<std::size_t>(pick[static_cast<std::size_t>(k)])][static_cast<std::size_t>(d)];
    return best;
  }
  bool first = true;
  for (const auto& perm : kEvenPermutations<Dim>) {
    CanonicalSimplex<Dim> t;
    for (int k = 0; k < kCorners; ++k)
      for (int d = 0; d < Dim; ++d) t.xyz[static_cast<std::size_t>(Dim * k + d)] = v[static_cast<std::size_t>(perm[k])][static_cast<std::size_t>(d)];
    if (first || t.xyz < best.xyz) best = t;
    first = false;
  }
  best.phase = m.cell_phase[c];
  return best;
}

std::uint64_t mix(std::uint64_t x) {
  x += 0x9e3779b97f4a7c15ull;
  x = (x ^ (x >> 30)) * 0xbf58476d1ce4e5b9ull;
  x = (x ^ (x >> 27)) * 0x94d049bb133111ebull;
  return x ^ (x >> 31);
}

}  // namespace

template <int Dim>
std::vector<CanonicalSimplex<Dim>> canonical_simplices(const mesh::SimplexMesh<Dim>& m) {
  std::vector<CanonicalSimplex<Dim>> out(m.cell_count());
  for (std::size_t c = 0; c < out.size(); ++c) out[c] = canonical(m, c);
  std::sort(out.begin(), out.end());
  return out;
}

// A cohesive cell as its bottom's coordinate bits (3D: rotated to start at the smallest
// vertex, orientation kept) and its two phases: the same whichever partition emitted it.
// 0 for a mesh without cohesive cells, so the checksums of bulk meshes are unchanged.
template <int Dim>
std::uint64_t cohesive_term(const mesh::SimplexMesh<Dim>& m, std::size_t c) {
  std::array<std::array<std::uint64_t, Dim>, Dim> bottom;
  for (int k = 0; k < Dim; ++k) {
    const auto n = static_cast<std::size_t>(m.cohesive.cell(c)[k]);
    for (int d = 0; d < Dim; ++d) bottom[static_cast<std::size_t>(k)][static_cast<std::size_t>(d)] = bits(m.coords[Dim * n + d]);
  }
  std::size_t first = 0;
  if constexpr (Dim == 3)
    for (std::size_t k = 1; k < 3; ++k)
      if (bottom[k] < bottom[first]) first = k;
  std::uint64_t h = mix(0xc0e5u ^ mix(static_cast<std::uint64_t>(m.cohesive.phase[2 * c])) ^
                        static_cast<std::uint64_t>(m.cohesive.phase[2 * c + 1]));
  for (std::size_t k = 0; k < Dim; ++k)
    for (std::uint64_t x : bottom[(first + k) % Dim]) h = mix(h ^ x);
  return h;
}

template <int Dim>
std::uint64_t mesh_checksum(const mesh::SimplexMesh<Dim>& m) {
  std::uint64_t sum = 0;
  for (std::size_t c = 0; c < m.cohesive.count(); ++c) sum += cohesive_term(m, c);
  // Each cell's hash is a chain of dependent mixes; the chains of four cells advance side by
  // side (the same values), so that the processor overlaps them instead of waiting on one
  // multiply after another.
  const auto hash_cells = [&]<std::size_t kLanes>(std::size_t first) {
    std::array<CanonicalSimplex<Dim>, kLanes> t;
    std::array<std::uint64_t, kLanes> h;
    for (std::size_t l = 0; l < kLanes; ++l) t[l] = canonical(m, first + l), h[l] = mix(static_cast<std::uint64_t>(t[l].phase));
    for (std::size_t k = 0; k < t[0].xyz.size(); ++k)
      for (std::size_t l = 0; l < kLanes; ++l) h[l] = mix(h[l] ^ t[l].xyz[k]);
    for (std::size_t l = 0; l < kLanes; ++l) sum += h[l];
  };
  std::size_t c = 0;
  for (; c + 4 <= m.cell_count(); c += 4) hash_cells.template operator()<4>(c);
  for (; c < m.cell_count(); ++c) hash_cells.template operator()<1>(c);
  return sum;
}

std::uint64_t sum_over_ranks(const Comm& comm, std::uint64_t local) { return allreduce_sum_u64(comm, local); }

template <int Dim>
std::uint64_t mesh_checksum(const Comm& comm, const mesh::SimplexMesh<Dim>& piece) {
  return allreduce_sum_u64(comm, mesh_checksum(piece));
}

template std::vector<CanonicalSimplex<2>> canonical_simplices(const mesh::SimplexMesh<2>&);
template std::vector<CanonicalSimplex<3>> canonical_simplices(const mesh::SimplexMesh<3>&);
template std::uint64_t mesh_checksum(const mesh::SimplexMesh<2>&);
template std::uint64_t mesh_checksum(const mesh::SimplexMesh<3>&);
template std::uint64_t mesh_checksum(const Comm&, const mesh::SimplexMesh<2>&);
template std::uint64_t mesh_checksum(const Comm&, const mesh::SimplexMesh<3>&);

}  // namespace cisamr::parallel
