#pragma once
// Convex bodies given by their support function, and a GJK distance decision between two
// of them. This is the packer's exact overlap check: for circles, ellipses, spheres,
// ellipsoids, cylinders and convex polygons the support function is exact, so the answer
// is exact up to a relative 1e-10 and errs on the side of "too close". Non-convex
// particles (star polygons, NURBS blobs, STL grains) are represented by the convex hull
// of their points (control points for NURBS), which contains them: conservative.
#include <cstdint>
#include <vector>

#include "core/types.hpp"
#include "geometry/scene.hpp"

namespace cisamr::pack {

struct ConvexBody {
  enum class Kind : std::uint8_t { ball, ellipsoid, cylinder, hull };
  Kind kind = Kind::ball;
  Vec3 center{};  // ball, ellipsoid: centre; cylinder: one end of the axis; hull: unused
  Vec3 end{};     // cylinder: other end of the axis
  double radius = 0;            // ball, cylinder
  Vec3 semi_axes{};             // ellipsoid (an ellipse has semi_axes[2] = 0)
  geometry::Rotation3 rotation{{{1, 0, 0}, {0, 1, 0}, {0, 0, 1}}};  // ellipsoid body axes (columns)
  std::vector<Vec3> points;     // hull
  double bound_radius = 0;      // radius of a ball around `reference` containing the body
  Vec3 reference{};             // a point inside the body

  // The point of the body (moved by `offset`) farthest along direction d.
  Vec3 support(const Vec3& d, const Vec3& offset) const;
};

// Is the distance between a (moved by offset_a) and b (moved by offset_b) smaller than
// `gap`? With gap = 0: do they intersect (touching counts)? Undecided cases (distance
// within 1e-10 relative of gap, or iteration limit) answer true.
bool convex_within(const ConvexBody& a, const Vec3& offset_a, const ConvexBody& b,
                   const Vec3& offset_b, double gap);

// A lower and an upper bound of the distance (0 when they intersect), for tests/reports.
struct DistanceBounds {
  double lower = 0, upper = 0;
};
DistanceBounds convex_distance(const ConvexBody& a, const Vec3& offset_a, const ConvexBody& b,
                               const Vec3& offset_b, double tolerance);

}  // namespace cisamr::pack
