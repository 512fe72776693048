#pragma once
// The scene description (DESIGN.md §5) as plain data: what io reads and pack writes.
// No geometry is evaluated here; see oracle.hpp for the queries.
#include <array>
#include <memory>
#include <cstdlib>
#include <cstdint>
#include <string>
#include <variant>
#include <vector>

#include "core/types.hpp"

namespace cisamr::geometry {

using Rotation3 = std::array<std::array<double, 3>, 3>;  // row-major, applied as R·x

// The rotation of the unit quaternion w + xi + yj + zk.
inline Rotation3 quaternion_rotation(double w, double x, double y, double z) {
  return {{{1 - 2 * (y * y + z * z), 2 * (x * y - z * w), 2 * (x * z + y * w)},
           {2 * (x * y + z * w), 1 - 2 * (x * x + z * z), 2 * (y * z - x * w)},
           {2 * (x * z - y * w), 2 * (y * z + x * w), 1 - 2 * (x * x + y * y)}}};
}

// ---- 2D shapes ----
struct Circle {
  Vec2 center{};
  double radius = 0;
};
struct Ellipse {
  Vec2 center{};
  Vec2 semi_axes{};  // along the rotated x and y axes
  double angle = 0;  // radians, counter-clockwise
};
struct Polygon {
  std::vector<Vec2> vertices;  // closed implicitly, either orientation, simple
};
struct NurbsCurve {  // closed rational curve of any degree
  int degree = 0;
  std::vector<double> knots;        // size = control_points.size() + degree + 1
  std::vector<Vec2> control_points;
  std::vector<double> weights;      // empty = all 1
};

// ---- 3D shapes ----
struct Sphere {
  Vec3 center{};
  double radius = 0;
};
struct Ellipsoid {
  Vec3 center{};
  Vec3 semi_axes{};
  Rotation3 rotation{{{1, 0, 0}, {0, 1, 0}, {0, 0, 1}}};  // columns: the body axes in the world
};
struct Cylinder {  // finite, flat caps
  Vec3 start{}, end{};
  double radius = 0;
};
struct StlSurface {
  std::string file;  // resolved path (relative names are resolved against the scene file)
  double scale = 1;
  Rotation3 rotation{{{1, 0, 0}, {0, 1, 0}, {0, 0, 1}}};
  Vec3 translate{};
  // The surface as read from `file` (io fills it; geometry never opens files): triangles
  // in the file's own coordinates, before scale, rotation and translation.
  std::vector<std::array<Vec3, 3>> triangles;
};
struct NurbsPatch {
  std::array<int, 2> degree{};
  std::vector<double> knots_u, knots_v;
  std::vector<Vec3> control_points;  // u fastest
  std::vector<double> weights;
};
struct NurbsSurface {  // closed: the patches together bound a volume
  std::vector<NurbsPatch> patches;
  // Placement of the control points, as for STL: x' = rotation·(scale·x) + translate
  // (weights unchanged: rational B-splines are invariant under affine maps).
  double scale = 1;
  Rotation3 rotation{{{1, 0, 0}, {0, 1, 0}, {0, 0, 1}}};
  Vec3 translate{};
};

struct BrepData;  // brep_data.hpp
// Solids of a STEP file, one inclusion for all those selected, placed as STL surfaces are
// (x' = rotation·(scale·x) + translate, x in the file's millimetres).
struct StepSolids {
  std::string file;         // resolved path
  std::vector<int> solids;  // indices in the file's solid order; empty: every solid
  double scale = 1;
  Rotation3 rotation{{{1, 0, 0}, {0, 1, 0}, {0, 0, 1}}};
  Vec3 translate{};
  // The file as imported (io fills it; geometry never opens files); null where the reader
  // defers loading.
  std::shared_ptr<const BrepData> brep;
};

using Shape = std::variant<Circle, Ellipse, Polygon, NurbsCurve, Sphere, Ellipsoid, Cylinder,
                           StlSurface, NurbsSurface, StepSolids>;

struct Inclusion {
  Shape shape;
  int phase = 2;   // phase id
  int levels = 0;  // SAMR levels R_k
};

struct Phase {
  int id = 1;
  std::string name;
  bool is_void = false;
};

struct SceneDesc {
  std::string source;  // file the scene came from, for error messages ("" if built in code)
  int dimension = 2;
  std::array<double, 3> domain_min{}, domain_max{};
  // Per axis: the domain is a period of the material along it (an inclusion crossing the
  // face enters again from the opposite one). Only the first `dimension` entries count.
  std::array<bool, 3> periodic{};
  double h = 1;    // background element size
  int levels = 0;  // default SAMR levels of an inclusion
  std::vector<Phase> phases;
  int matrix_phase = 1;
  std::vector<Inclusion> inclusions;

  // Periodic images of inclusions (geometry::expand_periodic): image_base[k] is the listed
  // inclusion that inclusion k is an image of (−1 for a listed one), image_shift[k] its
  // shift in periods per axis. Empty for a scene as read.
  std::vector<std::int32_t> image_base;
  bool images_expanded = false;  // set by expand_periodic (a subset of such a scene keeps it)
  std::vector<std::array<std::int8_t, 3>> image_shift;

  // Where each listed inclusion came from in the scene file, when that is not simply
  // inclusions[k]: a `step` entry of several solids is one inclusion per solid, and a subset
  // scene (parallel/ghost.hpp) keeps its inclusions' names. entry[k] is the index in the
  // file's `inclusions` array, entry_solid[k] the solid of that entry's STEP file (−1: the
  // whole entry). Both empty: inclusion k is entry k.
  std::vector<std::int32_t> entry;
  std::vector<std::int32_t> entry_solid;

  bool any_periodic() const {
    for (int d = 0; d < dimension; ++d)
      if (periodic[static_cast<std::size_t>(d)]) return true;
    return false;
  }
  // The listed inclusion behind inclusion k (k itself unless k is an image).
  std::size_t listed(std::size_t k) const {
    return k < image_base.size() && image_base[k] >= 0 ? static_cast<std::size_t>(image_base[k]) : k;
  }

  // Index of the phase with this id in `phases`, or -1.
  int phase_index(int id) const {
    for (std::size_t i = 0; i < phases.size(); ++i)
      if (phases[i].id == id) return static_cast<int>(i);
    return -1;
  }
};

// Field path of inclusion i for error messages: "inclusions[i]".
// The scene's void phases as a mask over phase indices (the cells of a void phase are not
// part of the mesh).
inline PhaseMask void_phase_mask(const SceneDesc& scene) {
  PhaseMask m = 0;
  for (std::size_t k = 0; k < scene.phases.size() && k < 64; ++k)
    if (scene.phases[k].is_void) m |= PhaseMask{1} << k;
  return m;
}

inline std::string inclusion_field(std::size_t i) { return "inclusions[" + std::to_string(i) + "]"; }

// The field path of listed inclusion k of a scene as the file names it: "inclusions[e]", or
// "inclusions[e] (solid s)" for one solid of a `step` entry of several.
inline std::string inclusion_field(const SceneDesc& scene, std::size_t k) {
  if (k >= scene.entry.size()) return inclusion_field(k);
  std::string field = inclusion_field(static_cast<std::size_t>(scene.entry[k]));
  if (k < scene.entry_solid.size() && scene.entry_solid[k] >= 0) field += " (solid " + std::to_string(scene.entry_solid[k]) + ")";
  return field;
}

// The same for inclusion k of a scene with periodic images: a listed inclusion by its field,
// an image as "the periodic image (+x-2y) of inclusions[i]".
inline std::string inclusion_name(const SceneDesc& scene, std::size_t k) {
  const std::size_t base = scene.listed(k);
  if (base == k) return inclusion_field(scene, k);
  std::string shift;
  for (int d = 0; d < 3; ++d) {
    const int s = scene.image_shift[k][static_cast<std::size_t>(d)];
    if (s == 0) continue;  // "+x", "-2y": the shift in periods along each axis
    shift += std::string(s > 0 ? "+" : "-") + (std::abs(s) > 1 ? std::to_string(std::abs(s)) : "") + "xyz"[d];
  }
  return "the periodic image (" + shift + ") of " + inclusion_field(scene, base);
}

}  // namespace cisamr::geometry
