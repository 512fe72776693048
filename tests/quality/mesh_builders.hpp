#pragma once
// Small hand-made meshes for the quality tests: structured triangle and tetrahedral grids
// and helpers to break them on purpose.
#include <array>
#include <cmath>
#include <type_traits>
#include <utility>
#include <vector>

#include "mesh/metrics.hpp"
#include "mesh/simplex_mesh.hpp"

namespace cisamr::quality::testing {

template <int Dim>
LocalId add_node(mesh::SimplexMesh<Dim>& m, const std::type_identity_t<Vec<Dim>>& p) {
  m.coords.insert(m.coords.end(), p.begin(), p.end());
  m.node_global_id.push_back(static_cast<GlobalId>(m.node_count() - 1));
  return static_cast<LocalId>(m.node_count() - 1);
}
inline LocalId add_node(mesh::Mesh2& m, double x, double y) { return add_node(m, Vec2{x, y}); }
inline LocalId add_node(mesh::Mesh3& m, double x, double y, double z) { return add_node(m, Vec3{x, y, z}); }
template <int Dim>
void add_cell(mesh::SimplexMesh<Dim>& m, std::array<LocalId, Dim + 1> nodes, int phase = 1) {
  m.cell_nodes.insert(m.cell_nodes.end(), nodes.begin(), nodes.end());
  m.cell_phase.push_back(phase);
  m.cell_partition.push_back(0);
}
// Removes cell c (keeps nodes).
template <int Dim>
void remove_cell(mesh::SimplexMesh<Dim>& m, std::size_t c) {
  m.cell_nodes.erase(m.cell_nodes.begin() + static_cast<std::ptrdiff_t>(c * (Dim + 1)),
                     m.cell_nodes.begin() + static_cast<std::ptrdiff_t>((c + 1) * (Dim + 1)));
  m.cell_phase.erase(m.cell_phase.begin() + static_cast<std::ptrdiff_t>(c));
  m.cell_partition.erase(m.cell_partition.begin() + static_cast<std::ptrdiff_t>(c));
}

// nx × ny squares of side h from `origin`, each split into two counter-clockwise triangles
// along alternating diagonals. Node (i, j) has id j·(nx+1) + i; square (i, j) owns cells
// 2·(j·nx + i) and 2·(j·nx + i) + 1.
inline mesh::Mesh2 structured_triangles(int nx, int ny, double h = 1.0, Vec2 origin = {0, 0}) {
  mesh::Mesh2 m;
  for (int j = 0; j <= ny; ++j)
    for (int i = 0; i <= nx; ++i) add_node(m, origin[0] + h * i, origin[1] + h * j);
  auto id = [&](int i, int j) { return static_cast<LocalId>(j * (nx + 1) + i); };
  for (int j = 0; j < ny; ++j)
    for (int i = 0; i < nx; ++i) {
      const LocalId a = id(i, j), b = id(i + 1, j), c = id(i + 1, j + 1), d = id(i, j + 1);
      if ((i + j) % 2 == 0) {
        add_cell<2>(m, {a, b, c});
        add_cell<2>(m, {a, c, d});
      } else {
        add_cell<2>(m, {a, b, d});
        add_cell<2>(m, {b, c, d});
      }
    }
  return m;
}

// Appends the tet, swapping two nodes if needed so that it is positively oriented.
inline void add_positive_tet(mesh::Mesh3& m, std::array<LocalId, 4> t, int phase = 1) {
  if (mesh::signed_volume(m.point(t[0]), m.point(t[1]), m.point(t[2]), m.point(t[3])) < 0)
    std::swap(t[2], t[3]);
  add_cell<3>(m, t, phase);
}

// nx × ny × nz unit cubes, each split into 5 tetrahedra (4 corner tets + 1 central), the
// decomposition mirrored on alternate cubes so that shared faces get the same diagonal.
inline mesh::Mesh3 structured_tets(int nx, int ny, int nz) {
  mesh::Mesh3 m;
  for (int k = 0; k <= nz; ++k)
    for (int j = 0; j <= ny; ++j)
      for (int i = 0; i <= nx; ++i) add_node(m, i, j, k);
  auto id = [&](int i, int j, int k) { return static_cast<LocalId>((k * (ny + 1) + j) * (nx + 1) + i); };
  for (int k = 0; k < nz; ++k)
    for (int j = 0; j < ny; ++j)
      for (int i = 0; i < nx; ++i) {
        // v[b] = corner with bits (x, y, z) = b.
        LocalId v[8];
        for (int b = 0; b < 8; ++b) v[b] = id(i + (b & 1), j + (b >> 1 & 1), k + (b >> 2 & 1));
        // Central tet on the corners of even (or odd) bit parity.
        const bool even = (i + j + k) % 2 == 0;
        const int c0 = even ? 0 : 1, c1 = even ? 3 : 2, c2 = even ? 5 : 4, c3 = even ? 6 : 7;
        add_positive_tet(m, {v[c0], v[c1], v[c2], v[c3]});
        // One corner tet per corner of the other parity: the corner and its 3 neighbours.
        for (int b = 0; b < 8; ++b) {
          const bool parity = ((b & 1) + (b >> 1 & 1) + (b >> 2 & 1)) % 2 == 0;
          if (parity == even) continue;
          add_positive_tet(m, {v[b], v[b ^ 1], v[b ^ 2], v[b ^ 4]});
        }
      }
  return m;
}


// Keeps the cells `keep` says yes to, drops the nodes no kept cell uses; nodes keep their global ids.
template <int Dim, class Keep>
mesh::SimplexMesh<Dim> filtered(const mesh::SimplexMesh<Dim>& m, Keep keep) {
  mesh::SimplexMesh<Dim> out;
  std::vector<LocalId> new_id(m.node_count(), -1);
  for (std::size_t c = 0; c < m.cell_count(); ++c) {
    if (!keep(c)) continue;
    std::array<LocalId, Dim + 1> t;
    for (int k = 0; k <= Dim; ++k) {
      LocalId& n = new_id[m.cell(c)[k]];
      if (n < 0) {
        n = add_node(out, m.point(m.cell(c)[k]));
        out.node_global_id.back() = m.node_global_id[std::size_t(m.cell(c)[k])];
      }
      t[k] = n;
    }
    add_cell<Dim>(out, t, m.cell_phase[c]);
  }
  return out;
}

}  // namespace cisamr::quality::testing
