// STL surfaces: build, validation and exact queries (contract in stl_mesh.hpp).
#include "geometry/stl_mesh.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <numeric>

#include "core/vec_math.hpp"
#include "geometry/box_index.hpp"
#include "geometry/predicates3.hpp"

namespace cisamr::geometry::stl {
namespace {

Box3 face_box(const Mesh& m, std::int32_t f) {
  const auto& t = m.faces[f];
  Box3 b{m.vertices[t[0]], m.vertices[t[0]]};
  for (int i = 1; i < 3; ++i)
    for (int k = 0; k < 3; ++k) {
      b.min[k] = std::min(b.min[k], m.vertices[t[i]][k]);
      b.max[k] = std::max(b.max[k], m.vertices[t[i]][k]);
    }
  return b;
}

bool in_box(const Vec3& p, const Box3& b) {
  return p[0] >= b.min[0] && p[0] <= b.max[0] && p[1] >= b.min[1] && p[1] <= b.max[1] &&
         p[2] >= b.min[2] && p[2] <= b.max[2];
}

Vec2 yz(const Vec3& v) { return {v[1], v[2]}; }

// Orientation of (u, v, q') in the (y, z) plane, q' = q + (0, ε, ε²) symbolically.
int perturbed_orientation(const Vec3& u, const Vec3& v, const Vec3& q) {
  const int o = exact::orientation(yz(u), yz(v), yz(q));
  if (o != 0) return o;
  if (v[2] != u[2]) return u[2] > v[2] ? 1 : -1;
  if (v[1] != u[1]) return v[1] > u[1] ? 1 : -1;
  return 0;
}

// Is p (on the plane of the non-degenerate triangle a, b, c) inside the closed triangle?
bool coplanar_point_in_triangle(const Vec3& a, const Vec3& b, const Vec3& c, const Vec3& p) {
  const Vec3 n = cross(sub(b, a), sub(c, a));
  int axes[3] = {0, 1, 2};
  std::sort(axes, axes + 3, [&](int x, int y) { return std::abs(n[x]) > std::abs(n[y]); });
  for (int drop : axes) {
    const int i = (drop + 1) % 3, j = (drop + 2) % 3;
    auto pr = [&](const Vec3& v) { return Vec2{v[i], v[j]}; };
    const int s = exact::orientation(pr(a), pr(b), pr(c));
    if (s == 0) continue;
    const int o1 = exact::orientation(pr(a), pr(b), pr(p)), o2 = exact::orientation(pr(b), pr(c), pr(p)),
              o3 = exact::orientation(pr(c), pr(a), pr(p));
    return o1 * s >= 0 && o2 * s >= 0 && o3 * s >= 0;
  }
  return false;
}

double point_triangle_distance2(const Vec3& p, const Vec3& a, const Vec3& b, const Vec3& c) {
  // Ericson, Real-Time Collision Detection §5.1.5.
  const Vec3 ab = sub(b, a), ac = sub(c, a), ap = sub(p, a);
  auto d2 = [&](const Vec3& q) { const Vec3 d = sub(p, q); return dot(d, d); };
  const double d1 = dot(ab, ap), d2v = dot(ac, ap);
  if (d1 <= 0 && d2v <= 0) return d2(a);
  const Vec3 bp = sub(p, b);
  const double d3 = dot(ab, bp), d4 = dot(ac, bp);
  if (d3 >= 0 && d4 <= d3) return d2(b);
  const double vc = d1 * d4 - d3 * d2v;
  if (vc <= 0 && d1 >= 0 && d3 <= 0) {
    const double v = d1 / (d1 - d3);
    return d2({a[0] + v * ab[0], a[1] + v * ab[1], a[2] + v * ab[2]});
  }
  const Vec3 cp = sub(p, c);
  const double d5 = dot(ab, cp), d6 = dot(ac, cp);
  if (d6 >= 0 && d5 <= d6) return d2(c);
  const double vb = d5 * d2v - d1 * d6;
  if (vb <= 0 && d2v >= 0 && d6 <= 0) {
    const double w = d2v / (d2v - d6);
    return d2({a[0] + w * ac[0], a[1] + w * ac[1], a[2] + w * ac[2]});
  }
  const double va = d3 * d6 - d5 * d4;
  if (va <= 0 && (d4 - d3) >= 0 && (d5 - d6) >= 0) {
    const double w = (d4 - d3) / ((d4 - d3) + (d5 - d6));
    return d2({b[0] + w * (c[0] - b[0]), b[1] + w * (c[1] - b[1]), b[2] + w * (c[2] - b[2])});
  }
  const double denom = 1 / (va + vb + vc), v = vb * denom, w = vc * denom;
  return d2({a[0] + ab[0] * v + ac[0] * w, a[1] + ab[1] * v + ac[1] * w, a[2] + ab[2] * v + ac[2] * w});
}

std::string face_problem(const std::string& what, std::int64_t face) {
  return what + " (face " + std::to_string(face) + ")";
}

// Self-intersection of two faces beyond what their shared vertices allow.
bool faces_conflict(const Mesh& m, std::int32_t f, std::int32_t g) {
  const auto& A = m.faces[f];
  const auto& B = m.faces[g];
  int shared = 0, sa[3] = {-1, -1, -1}, sb[3] = {-1, -1, -1};
  for (int i = 0; i < 3; ++i)
    for (int j = 0; j < 3; ++j)
      if (A[i] == B[j]) sa[shared] = i, sb[shared] = j, ++shared;
  const auto& V = m.vertices;
  if (shared == 0)
    return exact::triangles_intersect(V[A[0]], V[A[1]], V[A[2]], V[B[0]], V[B[1]], V[B[2]]);
  if (shared >= 2) {
    if (shared == 3) return true;  // duplicate face
    // Sharing an edge: they overlap only when folded flat onto each other.
    const Vec3& u = V[A[sa[0]]];
    const Vec3& v = V[A[sa[1]]];
    const Vec3& p = V[A[3 - sa[0] - sa[1]]];
    const Vec3& q = V[B[3 - sb[0] - sb[1]]];
    if (exact::orientation(u, v, p, q) != 0) return false;
    // Coplanar: folded iff p and q lie on the same side of the line uv.
    const Vec3 n = cross(sub(v, u), sub(p, u));
    int drop = 0;
    for (int k = 1; k < 3; ++k)
      if (std::abs(n[k]) > std::abs(n[drop])) drop = k;
    const int i = (drop + 1) % 3, j = (drop + 2) % 3;
    auto pr = [&](const Vec3& x) { return Vec2{x[i], x[j]}; };
    return exact::orientation(pr(u), pr(v), pr(p)) * exact::orientation(pr(u), pr(v), pr(q)) > 0;
  }
  // One shared vertex w: the far edge of either face must miss the other face...
  const Vec3& w = V[A[sa[0]]];
  const Vec3& a1 = V[A[(sa[0] + 1) % 3]];
  const Vec3& a2 = V[A[(sa[0] + 2) % 3]];
  const Vec3& b1 = V[B[(sb[0] + 1) % 3]];
  const Vec3& b2 = V[B[(sb[0] + 2) % 3]];
  if (exact::segment_triangle_intersect(b1, b2, w, a1, a2) || exact::segment_triangle_intersect(a1, a2, w, b1, b2))
    return true;
  // ...and an edge from w lying in the other face's plane must not enter its corner.
  auto in_corner = [&](const Vec3& c1, const Vec3& c2, const Vec3& d) {
    if (exact::orientation(w, c1, c2, d) != 0) return false;
    const Vec3 n = cross(sub(c1, w), sub(c2, w));
    int drop = 0;
    for (int k = 1; k < 3; ++k)
      if (std::abs(n[k]) > std::abs(n[drop])) drop = k;
    const int i = (drop + 1) % 3, j = (drop + 2) % 3;
    auto pr = [&](const Vec3& x) { return Vec2{x[i], x[j]}; };
    const int s = exact::orientation(pr(w), pr(c1), pr(c2));
    return exact::orientation(pr(w), pr(c1), pr(d)) * s > 0 && exact::orientation(pr(w), pr(d), pr(c2)) * s > 0;
  };
  const Vec3 bm{0.5 * (b1[0] + b2[0]), 0.5 * (b1[1] + b2[1]), 0.5 * (b1[2] + b2[2])};
  return in_corner(a1, a2, b1) || in_corner(a1, a2, b2) || in_corner(a1, a2, bm) || in_corner(b1, b2, a1) ||
         in_corner(b1, b2, a2);
}

// The hierarchy, box and size of an indexed mesh, then (with `validate`) its checks.
std::string finish(Mesh& m, bool validate) {
  const std::size_t nf = m.faces.size();
  std::vector<Box3> boxes(nf);
  for (std::size_t f = 0; f < nf; ++f) boxes[f] = face_box(m, static_cast<std::int32_t>(f));
  m.bvh.build(boxes);
  m.box = m.bvh.box();
  m.size = std::sqrt(dot(sub(m.box.max, m.box.min), sub(m.box.max, m.box.min)));
  if (!validate) return "";

  for (std::size_t f = 0; f < nf; ++f) {
    const auto& t = m.faces[f];
    if (t[0] == t[1] || t[1] == t[2] || t[0] == t[2] ||
        exact::collinear(m.vertices[t[0]], m.vertices[t[1]], m.vertices[t[2]]))
      return face_problem("zero-area face", static_cast<std::int64_t>(f));
  }
  // Edges: each undirected edge must have exactly two faces, traversing it oppositely.
  struct Edge {
    std::int32_t lo, hi, face;
    bool forward;
  };
  std::vector<Edge> edges;
  edges.reserve(3 * nf);
  for (std::size_t f = 0; f < nf; ++f)
    for (int i = 0; i < 3; ++i) {
      const std::int32_t u = m.faces[f][i], v = m.faces[f][(i + 1) % 3];
      edges.push_back({std::min(u, v), std::max(u, v), static_cast<std::int32_t>(f), u < v});
    }
  std::sort(edges.begin(), edges.end(), [](const Edge& x, const Edge& y) {
    if (x.lo != y.lo) return x.lo < y.lo;
    if (x.hi != y.hi) return x.hi < y.hi;
    return x.face < y.face;
  });
  std::int64_t open_face = -1, nonmanifold_face = -1;
  std::vector<int> conflicts(nf, 0);
  for (std::size_t i = 0; i < edges.size();) {
    std::size_t j = i;
    while (j < edges.size() && edges[j].lo == edges[i].lo && edges[j].hi == edges[i].hi) ++j;
    const std::size_t count = j - i;
    if (count == 1) {
      if (open_face < 0 || edges[i].face < open_face) open_face = edges[i].face;
    } else if (count > 2) {
      if (nonmanifold_face < 0 || edges[i].face < nonmanifold_face) nonmanifold_face = edges[i].face;
    } else if (edges[i].forward == edges[i + 1].forward) {
      ++conflicts[edges[i].face];
      ++conflicts[edges[i + 1].face];
    }
    i = j;
  }
  if (open_face >= 0) return face_problem("surface is not closed (a boundary edge)", open_face);
  if (nonmanifold_face >= 0) return face_problem("non-manifold edge (more than two faces)", nonmanifold_face);
  // The face with the most conflicting edges is the flipped one (lowest id on ties).
  const auto worst = std::max_element(conflicts.begin(), conflicts.end());
  if (*worst > 0)
    return face_problem("inconsistently oriented neighbouring faces", worst - conflicts.begin());
  for (auto [f, g] : overlapping_box_pairs(boxes))
    if (faces_conflict(m, f, g))
      return "self-intersecting (faces " + std::to_string(f) + " and " + std::to_string(g) + ")";
  return "";
}

}  // namespace

std::string build(const StlSurface& s, Mesh& m, bool validate) {
  m = Mesh{};
  const std::size_t nf = s.triangles.size();
  if (nf == 0) return "no triangles";
  for (std::size_t f = 0; f < nf; ++f)
    for (const Vec3& v : s.triangles[f])
      if (!std::isfinite(v[0]) || !std::isfinite(v[1]) || !std::isfinite(v[2]))
        return face_problem("coordinates must be finite", static_cast<std::int64_t>(f));
  // Merge identical vertices (file coordinates, exact equality).
  std::vector<std::int64_t> corner(3 * nf);
  std::iota(corner.begin(), corner.end(), 0);
  auto coord = [&](std::int64_t c) -> const Vec3& { return s.triangles[c / 3][c % 3]; };
  std::sort(corner.begin(), corner.end(), [&](std::int64_t x, std::int64_t y) {
    const Vec3 &a = coord(x), &b = coord(y);
    return a != b ? a < b : x < y;
  });
  m.faces.assign(nf, {0, 0, 0});
  for (std::size_t i = 0; i < corner.size(); ++i) {
    if (i == 0 || coord(corner[i]) != coord(corner[i - 1])) {
      const Vec3& v = coord(corner[i]);
      Vec3 w{};
      for (int r = 0; r < 3; ++r)
        w[r] = s.rotation[r][0] * (s.scale * v[0]) + s.rotation[r][1] * (s.scale * v[1]) +
               s.rotation[r][2] * (s.scale * v[2]) + s.translate[r];
      m.vertices.push_back(w);
    }
    m.faces[corner[i] / 3][corner[i] % 3] = static_cast<std::int32_t>(m.vertices.size() - 1);
  }
  return finish(m, validate);
}

std::string build_indexed(std::vector<Vec3> vertices, std::vector<std::array<std::int32_t, 3>> faces, Mesh& m,
                          bool validate) {
  m = Mesh{};
  if (faces.empty()) return "no triangles";
  for (std::size_t f = 0; f < faces.size(); ++f)
    for (std::int32_t v : faces[f]) {
      if (v < 0 || static_cast<std::size_t>(v) >= vertices.size())
        return face_problem("vertex index out of range", static_cast<std::int64_t>(f));
      if (!std::isfinite(vertices[v][0]) || !std::isfinite(vertices[v][1]) || !std::isfinite(vertices[v][2]))
        return face_problem("coordinates must be finite", static_cast<std::int64_t>(f));
    }
  m.vertices = std::move(vertices);
  m.faces = std::move(faces);
  return finish(m, validate);
}

int side(const Mesh& m, const Vec3& p) {
  if (m.bvh.empty() || !in_box(p, m.box)) return -1;
  bool inside = false, on = false;
  // Ray p + λ·(1, 0, 0), λ > 0, with p perturbed to (x, y + ε, z + ε²) in the (y, z)
  // tests: it never meets an edge or vertex, so the parity of the faces it pierces is
  // exact. A face holding p is found on the way (p lies in the closed projection).
  m.bvh.traverse(
      [&](const Box3& b) {
        return p[1] >= b.min[1] && p[1] <= b.max[1] && p[2] >= b.min[2] && p[2] <= b.max[2] && p[0] <= b.max[0];
      },
      [&](std::int32_t f) {
        const auto& t = m.faces[f];
        const Vec3 &a = m.vertices[t[0]], &b = m.vertices[t[1]], &c = m.vertices[t[2]];
        const double ymin = std::min({a[1], b[1], c[1]}), ymax = std::max({a[1], b[1], c[1]});
        const double zmin = std::min({a[2], b[2], c[2]}), zmax = std::max({a[2], b[2], c[2]});
        if (p[1] < ymin || p[1] > ymax || p[2] < zmin || p[2] > zmax || p[0] > std::max({a[0], b[0], c[0]}))
          return false;
        const int o1 = perturbed_orientation(a, b, p), o2 = perturbed_orientation(b, c, p),
                  o3 = perturbed_orientation(c, a, p);
        if (o1 != 0 && o1 == o2 && o2 == o3) {
          const int s = exact::orientation(a, b, c, p);
          if (s == 0) {
            on = true;
            return true;
          }
          if (-s == o1) inside = !inside;
          return false;
        }
        if (p[0] >= std::min({a[0], b[0], c[0]}) && exact::orientation(a, b, c, p) == 0 &&
            coplanar_point_in_triangle(a, b, c, p)) {
          on = true;
          return true;
        }
        return false;
      });
  if (on) return 0;
  return inside ? 1 : -1;
}

void segment_hits(const Mesh& m, const Vec3& a, const Vec3& b, std::vector<double>& ts) {
  if (m.bvh.empty()) return;
  const Vec3 d = sub(b, a);
  const double slack = 1e-12 * m.size;
  auto meets = [&](const Box3& bx) {
    // Slab test against the slightly inflated box.
    double t0 = 0, t1 = 1;
    for (int k = 0; k < 3; ++k) {
      const double lo = bx.min[k] - slack, hi = bx.max[k] + slack;
      if (d[k] == 0) {
        if (a[k] < lo || a[k] > hi) return false;
      } else {
        double ta = (lo - a[k]) / d[k], tb = (hi - a[k]) / d[k];
        if (ta > tb) std::swap(ta, tb);
        t0 = std::max(t0, ta);
        t1 = std::min(t1, tb);
        if (t0 > t1) return false;
      }
    }
    return true;
  };
  m.bvh.traverse(meets, [&](std::int32_t f) {
    const auto& t = m.faces[f];
    const Vec3 &v0 = m.vertices[t[0]], &v1 = m.vertices[t[1]], &v2 = m.vertices[t[2]];
    for (int k = 0; k < 3; ++k) {
      const double lo = std::min({v0[k], v1[k], v2[k]}), hi = std::max({v0[k], v1[k], v2[k]});
      if (std::max(a[k], b[k]) < lo || std::min(a[k], b[k]) > hi) return false;
    }
    const int sa = exact::orientation(v0, v1, v2, a), sb = exact::orientation(v0, v1, v2, b);
    if (sa * sb >= 0) return false;  // not strictly across the plane
    const int o1 = exact::orientation(a, b, v0, v1), o2 = exact::orientation(a, b, v1, v2),
              o3 = exact::orientation(a, b, v2, v0);
    if ((o1 < 0 || o2 < 0 || o3 < 0) && (o1 > 0 || o2 > 0 || o3 > 0)) return false;
    const Vec3 n = cross(sub(v1, v0), sub(v2, v0));
    const double da = dot(n, sub(a, v0)), db = dot(n, sub(b, v0));
    const double tt = da / (da - db);
    ts.push_back(std::clamp(tt, std::numeric_limits<double>::denorm_min(),
                            1 - std::numeric_limits<double>::epsilon() * 0.5));
    return false;
  });
}

bool touches_box(const Mesh& m, const Box3& box) {
  bool hit = false;
  m.bvh.traverse(
      [&](const Box3& b) { return boxes_overlap(b, box); },
      [&](std::int32_t f) {
        const auto& t = m.faces[f];
        if (!boxes_overlap(face_box(m, f), box)) return false;
        hit = exact::triangle_box_intersect(m.vertices[t[0]], m.vertices[t[1]], m.vertices[t[2]], box);
        return hit;
      });
  return hit;
}

double volume(const Mesh& m) {
  double v = 0;
  const Vec3& o = m.box.min;  // a nearby origin keeps the sum well conditioned
  for (const auto& t : m.faces)
    v += dot(sub(m.vertices[t[0]], o), cross(sub(m.vertices[t[1]], o), sub(m.vertices[t[2]], o)));
  return std::abs(v) / 6;
}

double surface_area(const Mesh& m) {
  double a = 0;
  for (const auto& t : m.faces) {
    const Vec3 n = cross(sub(m.vertices[t[1]], m.vertices[t[0]]), sub(m.vertices[t[2]], m.vertices[t[0]]));
    a += std::sqrt(dot(n, n));
  }
  return 0.5 * a;
}

double distance_to_surface(const Mesh& m, const Vec3& p) {
  double best2 = std::numeric_limits<double>::infinity();
  m.bvh.traverse(
      [&](const Box3& b) {
        double d2 = 0;
        for (int k = 0; k < 3; ++k) {
          const double e = std::max({b.min[k] - p[k], 0.0, p[k] - b.max[k]});
          d2 += e * e;
        }
        return d2 < best2;
      },
      [&](std::int32_t f) {
        const auto& t = m.faces[f];
        best2 = std::min(best2, point_triangle_distance2(p, m.vertices[t[0]], m.vertices[t[1]], m.vertices[t[2]]));
        return false;
      });
  return std::sqrt(best2);
}

void edge_crossings_at_x(const Mesh& m, double x0, std::vector<double>& ys) {
  for (const auto& t : m.faces)
    for (int i = 0; i < 3; ++i) {
      const Vec3& u = m.vertices[t[i]];
      const Vec3& v = m.vertices[t[(i + 1) % 3]];
      if ((u[0] - x0) * (v[0] - x0) > 0 || u[0] == v[0]) continue;
      const double s = (x0 - u[0]) / (v[0] - u[0]);
      ys.push_back(u[1] + s * (v[1] - u[1]));
    }
}

}  // namespace cisamr::geometry::stl
