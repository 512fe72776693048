#pragma once
// Periodic links of a mesh (docs/periodic-design.md §3.3 "Periodic links", §5): which node
// on a periodic max face is the copy of which node on the min face. The writers turn them
// into constraints (Abaqus *EQUATION, Gmsh $Periodic, VTU periodic_master).
//
// Along a periodic axis a the node on the a-max face is the exact translate of its partner on
// the a-min face: x_a = fl(min_a + T_a) = faces.max[a] and every other coordinate is
// bit-equal. The master is therefore found by EXACT coordinate equality (a hash of the bit
// patterns, -0.0 taken as +0.0 so that the hash agrees with ==), never within a tolerance.
// That is legitimate because the mesh is periodic by construction: the mesher builds each
// max-face entity as the image of one canonical entity (the lattice is a torus), so the
// pairing exists exactly and this only reads it back. A tolerance would hide a mesh that is
// not periodic (and could pair the wrong nodes on fine meshes); a missing partner is a
// failure instead. quality::check_periodic verifies periodicity independently (facets,
// not nodes) and shares no code with this.
#include <array>
#include <bit>
#include <cstdint>
#include <vector>

#include "core/types.hpp"
#include "mesh/simplex_mesh.hpp"

namespace cisamr::mesh {

// A node on at least one periodic max face.
template <int Dim>
struct PeriodicSlave {
  LocalId node = -1;
  std::uint8_t shift = 0;  // bit a: the node lies on the max face of periodic axis a
  // Per axis a in `shift`: the single-axis master, the node with x_a moved to the min face
  // and the other coordinates unchanged (itself on another max face when the slave lies on
  // an edge or corner); -1 on the other axes.
  std::array<LocalId, Dim> axis_master{};
  // The full master: every shifted coordinate moved to the min face. Never a slave (the far
  // corner's master is CORNER0).
  LocalId master = -1;
};

template <int Dim>
struct PeriodicLinks {
  std::array<bool, Dim> axes{};
  std::vector<PeriodicSlave<Dim>> slaves;  // ascending node
  // With `voids`: nodes on a max face with no node at their full translate (only void cells
  // touch it across the period: the material there is a free surface, no constraint).
  std::vector<LocalId> unpaired;
  std::size_t slave_count() const { return slaves.size(); }
};

// The links of `m` for the box whose faces lie at faces.min / faces.max (the exact
// coordinates of the nodes on the faces: driver::face_box) along the periodic `axes`.
// With cohesive cells (node_phase set) masters are matched per phase. A slave without its
// single-axis or full master, or two nodes on a min face at the same position (and phase), throws MeshingError naming the node (global id when the mesh has them, else its
// index) and its coordinates: the mesh is not periodic. With `voids` (the scene has void
// phases) a node whose translate is absent is legitimate: a void fills the other side, its
// material meets the void across the period. It is then not a slave (`unpaired`), and a
// missing single-axis master is -1. O(n) expected (one hash table of the min-face nodes). Needs the whole mesh: a piece of a parallel run may lack masters
// (parallel::periodic_masters resolves those).
template <int Dim>
PeriodicLinks<Dim> periodic_links(const SimplexMesh<Dim>& m, const Box<Dim>& faces, const std::array<bool, Dim>& axes,
                                  bool voids = false);

// The helpers the links (and lib/parallel's exchange) are made of.
// Bit pattern of one coordinate as it is matched: -0.0 as +0.0.
inline std::uint64_t coordinate_bits(double x) {
  return std::bit_cast<std::uint64_t>(x == 0 ? 0.0 : x);
}
// Bit a set when `p` lies on the max face of periodic axis a.
template <int Dim>
std::uint8_t periodic_shift(const double* p, const Box<Dim>& faces, const std::array<bool, Dim>& axes) {
  std::uint8_t shift = 0;
  for (int a = 0; a < Dim; ++a)
    if (axes[static_cast<std::size_t>(a)] && p[a] == faces.max[a]) shift |= static_cast<std::uint8_t>(1u << a);
  return shift;
}
// The matching key of the point `p` with the axes of `shift` moved to the min face, and the
// node's phase: with cohesive cells a node's copies share a position, and each copy's
// master is the copy of its own phase (0 for a mesh without cohesive cells).
template <int Dim>
using PeriodicKey = std::array<std::uint64_t, Dim + 1>;
template <int Dim>
PeriodicKey<Dim> periodic_key(const double* p, const Box<Dim>& faces, std::uint8_t shift, std::int32_t phase = 0) {
  PeriodicKey<Dim> key;
  for (int a = 0; a < Dim; ++a)
    key[static_cast<std::size_t>(a)] = coordinate_bits((shift >> a) & 1 ? faces.min[a] : p[a]);
  key[Dim] = static_cast<std::uint32_t>(phase);
  return key;
}
// A node's phase for its periodic key.
template <int Dim>
std::int32_t periodic_phase(const SimplexMesh<Dim>& m, std::size_t node) {
  return m.node_phase.empty() ? 0 : m.node_phase[node];
}
// Whether a node at `p` can be a master: on the min face of some periodic axis.
template <int Dim>
bool on_periodic_min_face(const double* p, const Box<Dim>& faces, const std::array<bool, Dim>& axes) {
  for (int a = 0; a < Dim; ++a)
    if (axes[static_cast<std::size_t>(a)] && p[a] == faces.min[a]) return true;
  return false;
}

}  // namespace cisamr::mesh
