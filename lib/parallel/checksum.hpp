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

struct CanonicalTriangle {
  std::array<std::uint64_t, 6> xy{};  // coordinate bits, rotated so the smallest vertex is first
  std::int32_t phase = 0;
  auto operator<=>(const CanonicalTriangle&) const = default;
};

// The triangles of `m`, each rotated (orientation kept) to start at its smallest vertex
// (by coordinate bits), sorted. Two meshes are the same set of elements iff these agree.
std::vector<CanonicalTriangle> canonical_triangles(const mesh::Mesh2& m);

// Σ over triangles of a 64-bit hash of the canonical triangle, modulo 2^64.
std::uint64_t mesh_checksum2(const mesh::Mesh2& m);

// Collective: the checksum of the union of every rank's cells.
std::uint64_t mesh_checksum2(const Comm& comm, const mesh::Mesh2& piece);

}  // namespace cisamr::parallel
