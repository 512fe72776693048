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

CanonicalTriangle canonical(const mesh::Mesh2& m, std::size_t c) {
  std::array<std::array<std::uint64_t, 2>, 3> v;
  for (int k = 0; k < 3; ++k) {
    const auto n = static_cast<std::size_t>(m.cell_nodes[3 * c + static_cast<std::size_t>(k)]);
    v[static_cast<std::size_t>(k)] = {bits(m.coords[2 * n]), bits(m.coords[2 * n + 1])};
  }
  const auto first = static_cast<std::size_t>(std::min_element(v.begin(), v.end()) - v.begin());
  CanonicalTriangle t;
  for (std::size_t k = 0; k < 3; ++k) {
    t.xy[2 * k] = v[(first + k) % 3][0];
    t.xy[2 * k + 1] = v[(first + k) % 3][1];
  }
  t.phase = m.cell_phase[c];
  return t;
}

std::uint64_t mix(std::uint64_t x) {
  x += 0x9e3779b97f4a7c15ull;
  x = (x ^ (x >> 30)) * 0xbf58476d1ce4e5b9ull;
  x = (x ^ (x >> 27)) * 0x94d049bb133111ebull;
  return x ^ (x >> 31);
}

}  // namespace

std::vector<CanonicalTriangle> canonical_triangles(const mesh::Mesh2& m) {
  std::vector<CanonicalTriangle> out(m.cell_count());
  for (std::size_t c = 0; c < out.size(); ++c) out[c] = canonical(m, c);
  std::sort(out.begin(), out.end());
  return out;
}

std::uint64_t mesh_checksum2(const mesh::Mesh2& m) {
  std::uint64_t sum = 0;
  for (std::size_t c = 0; c < m.cell_count(); ++c) {
    const CanonicalTriangle t = canonical(m, c);
    std::uint64_t h = mix(static_cast<std::uint64_t>(t.phase));
    for (std::uint64_t x : t.xy) h = mix(h ^ x);
    sum += h;
  }
  return sum;
}

std::uint64_t mesh_checksum2(const Comm& comm, const mesh::Mesh2& piece) {
  return allreduce_sum_u64(comm, mesh_checksum2(piece));
}

}  // namespace cisamr::parallel
