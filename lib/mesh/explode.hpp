#pragma once
// The exploded view of a cohesive mesh (`cisamr mesh --explode F`, docs/cohesive-design.md
// §2.4): each region moved away from the domain's centre, so that the zero-thickness
// cohesive cells between regions open up in a viewer. For viewing only: the result is no
// longer conforming, and certify's coincidence check fails on it, as it should.
#include <vector>

#include "mesh/simplex_mesh.hpp"

namespace cisamr::mesh {

// A copy of `m.coords` in which every region is translated by (factor − 1)·(c_region −
// c_domain). A region is a connected component of the bulk cells through shared node ids:
// after the cohesive split these are the phase regions (the matrix, each inclusion or
// union of touching same-phase inclusions). c is the measure-weighted centroid (area in
// 2D, volume in 3D) of a region's cells, c_domain that of every bulk cell. Nodes used by
// no bulk cell stay where they are; factor 1 gives the coordinates back unchanged. One
// union-find over the cells, O(n α(n)).
template <int Dim>
std::vector<double> exploded_coords(const SimplexMesh<Dim>& m, double factor);

}  // namespace cisamr::mesh
