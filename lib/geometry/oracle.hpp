#pragma once
// The geometry oracle: every geometric question the mesher asks about a scene, in 2D
// (Oracle<2>, circles/ellipses/polygons/NURBS curves) and 3D (Oracle<3>, spheres/
// ellipsoids/cylinders/STL surfaces). One implementation for both dimensions over the
// shape interface of shape_model.hpp; CGAL lives behind this header (pimpl).
//
// Phases are referred to by *index* into SceneDesc::phases (not by id), so that a set of
// phases fits in a PhaseMask. Inclusions are referred to by their index in
// SceneDesc::inclusions.
//
// Determinism contract (partition invariance depends on it): every answer depends only
// on the arguments and on the inclusions involved, never on the candidate list beyond
// which inclusions it contains, nor on call order, nor on threads. In particular
// crossings(a, b, ...) returns bit-identical doubles for the same (a, b) whatever extra
// candidates are passed. Callers orient segments canonically (from the smaller lattice
// key) so that both neighbours ask the same question.
#include <cstdint>
#include <memory>
#include <span>
#include <vector>

#include "core/types.hpp"
#include "geometry/crossing.hpp"
#include "geometry/scene.hpp"

namespace cisamr::geometry {

template <int Dim>
class Oracle {
 public:
  using Point = Vec<Dim>;

  // Builds the shape models and the AABB tree over inclusion boxes. Validates the
  // geometry and throws InputError(scene.source, "inclusions[i]...", ...) for: an unknown
  // phase, a shape of the other dimension, degenerate or invalid shapes (non-positive
  // radius/semi-axis, polygon with < 3 vertices or self-intersecting, bad NURBS
  // knots/weights/degree, curve not closed, zero-length cylinder, rotation not
  // orthonormal, an STL surface that is open, non-manifold, self-intersecting or
  // inconsistently oriented: the message names the file and the first bad face), and
  // overlapping inclusions of different phases (the message names both).
  explicit Oracle(const SceneDesc& scene);
  ~Oracle();
  Oracle(Oracle&&) noexcept;
  Oracle& operator=(Oracle&&) noexcept;

  const SceneDesc& scene() const;
  int inclusion_count() const;
  int phase_count() const;
  int matrix_phase() const;                    // phase index of the matrix
  int phase_of(std::int32_t inclusion) const;  // phase index
  int levels_of(std::int32_t inclusion) const;
  // Same-phase inclusions that overlap (transitively) form one interface group; the
  // group id is the smallest inclusion index in it.
  int interface_group(std::int32_t inclusion) const;
  Box<Dim> bounding_box(std::int32_t inclusion) const;  // tight or loose by rounding

  // Inclusions whose bounding box meets the closed box, ascending. CGAL AABB tree.
  void candidates(const Box<Dim>& box, std::vector<std::int32_t>& out) const;

  // Does the boundary of `inclusion` meet the closed box? Conservative: never false when
  // it does; may be true when the boundary passes within ~1e-12·(box size).
  bool boundary_touches(std::int32_t inclusion, const Box<Dim>& box) const;

  // Phases whose closed region contains p (bit = phase index): one bit in the interior of
  // a phase, two or more on an interface. Exact for circles, polygons, spheres,
  // cylinders and STL surfaces.
  PhaseMask closure_phases(const Point& p, std::span<const std::int32_t> candidates) const;

  // The phase index at p if p is interior to one phase; on an interface, the phase of
  // the lowest-index inclusion whose boundary holds p.
  int phase_at(const Point& p, std::span<const std::int32_t> candidates) const;

  // Where the open segment a→b changes phase, ascending in t. Tangential touches and
  // boundaries inside same-phase unions are not crossings. Output is cleared first.
  void crossings(const Point& a, const Point& b, std::span<const std::int32_t> candidates,
                 std::vector<Crossing>& out) const;

  // Area (2D) or volume (3D) of each phase inside the domain (voids included): exact for
  // inclusions inside the domain without overlaps; otherwise accurate to 1e-9 relative.
  std::vector<double> phase_measures() const;

  // Distance from p to the closed region of a phase (0 inside or on its boundary).
  double distance_to_phase(const Point& p, int phase_index) const;

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

// Throws what constructing Oracle<Dim>(scene) throws for an unknown phase or an invalid
// shape, the same message for the same first fault, and keeps nothing. For the paths
// that never build the whole scene's oracle (partitioning, the distributed mesher), so
// that every path refuses the same scenes alike. STL surfaces without triangles are
// skipped: they are checked where their file is read. (Overlaps of different phases are
// not checked here.)
template <int Dim>
void validate_inclusions(const SceneDesc& scene);

extern template class Oracle<2>;
extern template class Oracle<3>;
using Oracle2 = Oracle<2>;
using Oracle3 = Oracle<3>;

}  // namespace cisamr::geometry
