#pragma once
// Order-free identity of a mesh as a set of elements (DESIGN.md §2.4): what partition
// invariance compares. An element is its vertex coordinates (bits) and its phase; node
// and cell numbering do not matter, orientation does.
#include <array>
#include <cstdint>
#include <vector>

#include "core/comm.hpp"
#include "mesh/simplex_mesh.hpp"

namespace cisamr::parallel {

template <int Dim>
struct CanonicalSimplex {
  // Coordinate bits of the Dim+1 vertices, in the even permutation (orientation kept) that
  // is lexicographically smallest: a triangle starts at its smallest vertex.
  std::array<std::uint64_t, Dim*(Dim + 1)> xyz{};
  std::int32_t phase = 0;
  auto operator<=>(const CanonicalSimplex&) const = default;
};
using CanonicalTriangle = CanonicalSimplex<2>;
using CanonicalTet = CanonicalSimplex<3>;

// The cells of `m` in canonical form, sorted. Two meshes are the same set of elements iff
// these agree.
template <int Dim>
std::vector<CanonicalSimplex<Dim>> canonical_simplices(const mesh::SimplexMesh<Dim>& m);
inline std::vector<CanonicalTriangle> canonical_triangles(const mesh::Mesh2& m) { return canonical_simplices(m); }
inline std::vector<CanonicalTet> canonical_tets(const mesh::Mesh3& m) { return canonical_simplices(m); }

// Σ over cells of a 64-bit hash of the canonical cell, modulo 2^64.
template <int Dim>
std::uint64_t mesh_checksum(const mesh::SimplexMesh<Dim>& m);
// Collective: the checksum of the union of every rank's cells.
template <int Dim>
std::uint64_t mesh_checksum(const Comm& comm, const mesh::SimplexMesh<Dim>& piece);
// Collective: the sum of every rank's `local` modulo 2^64 (checksums of disjoint cell sets add).
std::uint64_t sum_over_ranks(const Comm& comm, std::uint64_t local);

inline std::uint64_t mesh_checksum2(const mesh::Mesh2& m) { return mesh_checksum(m); }
inline std::uint64_t mesh_checksum2(const Comm& comm, const mesh::Mesh2& piece) { return mesh_checksum(comm, piece); }
inline std::uint64_t mesh_checksum3(const mesh::Mesh3& m) { return mesh_checksum(m); }
inline std::uint64_t mesh_checksum3(const Comm& comm, const mesh::Mesh3& piece) { return mesh_checksum(comm, piece); }

}  // namespace cisamr::parallel
