#pragma once
// Periodicity of a mesh, checked from coordinates alone (independent of the mesher's keys
// and bookkeeping): along each periodic axis a, the boundary facets with every node on the
// min face, moved onto the max face (x_a := max_a, the other coordinates untouched), are
// exactly the boundary facets on the max face, bit for bit.
#include <array>
#include <cstdint>
#include <functional>
#include <string>

#include "core/types.hpp"
#include "mesh/simplex_mesh.hpp"

namespace cisamr::quality {

struct PeriodicAxisReport {
  int axis = 0;
  std::int64_t min_facets = 0, max_facets = 0;  // boundary facets on the min and max face
  std::int64_t unmatched = 0;  // facets of either face with no exact translate on the other
  std::int64_t facing_void = 0;  // facets whose translate lies in a void (no element there): not failures
  std::int64_t near_face_nodes = 0;  // nodes within 1e-9 of the box size of a face, not on it
  Vec3 first_unmatched{};      // the centroid of one unmatched facet (when unmatched > 0)
};

struct PeriodicReport {
  std::vector<PeriodicAxisReport> axes;  // one per periodic axis
  bool ok = true;
};

// `box`: the coordinates of the faces (the mesher's face box: min, and min + N·h).
// `in_void` (optional, from the scene): whether a point lies in a void phase. A facet of
// one face whose translate lies on a void region of the other face has no partner there
// (the void's elements are not in the mesh), and is counted apart, not as a failure.
template <int Dim>
PeriodicReport check_periodic(const mesh::SimplexMesh<Dim>& m, const Box<Dim>& box, const std::array<bool, Dim>& axes,
                              const std::function<bool(const Vec<Dim>&)>& in_void = {});

std::string periodic_summary(const PeriodicReport& r);

}  // namespace cisamr::quality
