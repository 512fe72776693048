#pragma once
// The solids of a STEP file as plain data (docs/nurbs-step-design.md §3.2): what
// `import_step` (step_import.hpp) delivers, with no OpenCASCADE type in it. Every face is
// a B-spline surface with its trimming loops in the surface's (u, v); every solid carries
// a welded, closed, outward-oriented triangle mesh of its faces, each triangle with the
// face it stands for and the (u, v) of its corners, so that the exact surface and the mesh
// can be related without OCCT. Coordinates are OCCT's millimetres, as read.
#include <array>
#include <cstdint>
#include <vector>

#include "core/types.hpp"
#include "geometry/scene.hpp"

namespace cisamr::geometry {

// One edge of a trimming loop: a rational B-spline curve in a face's (u, v), clamped
// (first and last knots of multiplicity degree + 1), traversed from its first knot to its
// last. An open curve: `NurbsCurve` (scene.hpp) has the same fields but stands for a
// closed one.
struct BrepCurve2 {
  int degree = 0;
  std::vector<double> knots;        // size = control_points.size() + degree + 1
  std::vector<Vec2> control_points;
  std::vector<double> weights;      // one per control point (all 1 for a polynomial curve)
};

struct BrepFace {
  // The face's surface, non-periodic and clamped, with its location applied. `weights`
  // always holds one weight per control point (all 1 for a polynomial surface). An
  // analytic surface keeps its parameter range (a sphere's u in [0, 2π]) but not its
  // angle parametrisation (rational arcs of 120° or 90°): only the pcurves, the mesh's
  // (u, v) and this surface belong together, not the STEP file's own surface parameters.
  NurbsPatch surface;
  // Each wire of the face, a closed chain of pcurves: curve k ends where curve k + 1
  // starts (within the edge tolerances), the last where the first starts. The loops are
  // oriented for the surface's own normal (du × dv), whatever `reversed` says: the face
  // lies to the left, so an outer loop runs counter-clockwise in (u, v) and a hole
  // clockwise. A seam edge appears twice in its loop (once per side of the seam, in
  // opposite directions); a degenerated edge (a pole) appears as a curve along the pole's
  // side of the parameter rectangle.
  std::vector<std::vector<BrepCurve2>> loops;
  double tolerance = 0;       // the face's B-rep tolerance (BRep_Tool::Tolerance)
  double edge_tolerance = 0;  // the largest tolerance of its edges and vertices
  // The face's orientation in the solid is opposite to du × dv (TopAbs_REVERSED): the
  // solid's outward normal is −(du × dv) there.
  bool reversed = false;
};

struct BrepSolid {
  std::vector<BrepFace> faces;  // in TopExp_Explorer(solid, TopAbs_FACE) order
  // The mesh of the whole solid (BRepMesh on the converted faces): nodes welded by exact
  // coordinate equality, triangles degenerate after welding (at poles) dropped, every
  // triangle counter-clockwise seen from outside.
  std::vector<Vec3> vertices;
  std::vector<std::array<std::int32_t, 3>> triangles;
  std::vector<std::int32_t> triangle_face;            // index into `faces`, per triangle
  std::vector<std::array<Vec2, 3>> triangle_uv;       // (u, v) of each corner in its face's surface
  // Of the solid as read (its converted faces bound the same volume): the volume by
  // adaptive integration (BRepGProp, relative error 1e-12), the box tight around the exact
  // faces (BRepBndLib::AddOptimal, no tolerance added) and widened to every mesh vertex.
  double volume = 0;
  Box3 box;
};

struct BrepData {
  std::vector<BrepSolid> solids;  // in TopExp_Explorer(shape, TopAbs_SOLID) order
};

}  // namespace cisamr::geometry
