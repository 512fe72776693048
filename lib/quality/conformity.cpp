// Conformity check (DESIGN.md §2.1): nodes, cells, facets, T-junctions and total measure.
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <limits>
#include <string>

#include "mesh/metrics.hpp"
#include "quality/cell_geometry.hpp"
#include "quality/facet_table.hpp"
#include "quality/pieces_internal.hpp"
#include "quality/quality.hpp"

namespace cisamr::quality {
namespace {

constexpr std::size_t kExamplesPerKind = 3;
constexpr std::size_t kExamplesTotal = 24;

template <int Dim>
std::string point_text(const mesh::SimplexMesh<Dim>& m, LocalId n) {
  char buf[96];
  if constexpr (Dim == 2)
    std::snprintf(buf, sizeof buf, "%d (%.10g, %.10g)", n, m.coords[2 * std::size_t(n)],
                  m.coords[2 * std::size_t(n) + 1]);
  else
    std::snprintf(buf, sizeof buf, "%d (%.10g, %.10g, %.10g)", n, m.coords[3 * std::size_t(n)],
                  m.coords[3 * std::size_t(n) + 1], m.coords[3 * std::size_t(n) + 2]);
  return buf;
}

template <int Dim, class Ids>
std::string nodes_text(const mesh::SimplexMesh<Dim>& m, const Ids& ids) {
  std::string s;
  for (LocalId n : ids) s += (s.empty() ? "" : ", ") + point_text(m, n);
  return s;
}

// Keeps at most a few examples of each kind of problem.
class Examples {
 public:
  explicit Examples(std::vector<std::string>& out) : out_(out) {}
  bool wants(const char* kind) {
    if (out_.size() >= kExamplesTotal) return false;
    std::size_t& n = counts_[kind];
    return n++ < kExamplesPerKind;
  }
  void add(std::string s) { out_.push_back(std::move(s)); }

 private:
  std::vector<std::string>& out_;
  struct Counts {
    std::vector<std::pair<std::string, std::size_t>> v;
    std::size_t& operator[](const std::string& k) {
      for (auto& [key, n] : v)
        if (key == k) return n;
      v.emplace_back(k, 0);
      return v.back().second;
    }
  } counts_;
};

// ---- near-duplicate nodes: a hash grid of cells 2·eps wide ----------------------------
// A node at fractional position f in its cell can only be within eps of nodes in its own
// cell or in the neighbour on the side f points to (f < 1/2: below, else above), so
// 2^Dim cells are probed per node.
template <int Dim>
class NodeGrid {
 public:
  NodeGrid(const mesh::SimplexMesh<Dim>& m, const Vec<Dim>& origin, double cell)
      : m_(m), origin_(origin), cell_(cell) {
    const std::size_t n = m.node_count();
    std::size_t capacity = 16;
    while (capacity < 2 * n) capacity *= 2;
    slots_.assign(capacity, -1);
    next_.assign(n, -1);
    keys_.resize(n * Dim);
    for (std::size_t i = 0; i < n; ++i) {
      for (int d = 0; d < Dim; ++d) keys_[i * Dim + d] = key_of(m.coords[i * Dim + d], d);
      std::size_t s = find_slot(&keys_[i * Dim]);
      next_[i] = slots_[s];
      slots_[s] = static_cast<LocalId>(i);
    }
  }

  // Calls visit(j) for every node j in the cells that may hold nodes within eps of i.
  template <class Visit>
  void near(std::size_t i, Visit&& visit) const {
    std::array<std::int64_t, Dim> side;
    for (int d = 0; d < Dim; ++d) {
      const double u = (m_.coords[i * Dim + d] - origin_[d]) / cell_;
      side[d] = (u - std::floor(u) < 0.5) ? -1 : 1;
    }
    for (int corner = 0; corner < (1 << Dim); ++corner) {
      std::array<std::int64_t, Dim> key;
      for (int d = 0; d < Dim; ++d) key[d] = keys_[i * Dim + d] + (((corner >> d) & 1) ? side[d] : 0);
      const LocalId head = slots_[find_slot(key.data())];
      for (LocalId j = head; j >= 0; j = next_[j]) visit(static_cast<std::size_t>(j));
    }
  }

 private:
  std::int64_t key_of(double x, int d) const {
    const double u = std::floor((x - origin_[d]) / cell_);
    constexpr double kLimit = 4.0e18;
    if (!(u > -kLimit)) return std::numeric_limits<std::int64_t>::min() / 2;  // NaN too
    if (!(u < kLimit)) return std::numeric_limits<std::int64_t>::max() / 2;
    return static_cast<std::int64_t>(u);
  }
  // The slot holding this cell's chain, or the empty slot where it would go.
  std::size_t find_slot(const std::int64_t* key) const {
    std::uint64_t h = 0x9e3779b97f4a7c15ull;
    for (int d = 0; d < Dim; ++d) {
      h ^= static_cast<std::uint64_t>(key[d]) + 0x9e3779b97f4a7c15ull + (h << 6) + (h >> 2);
      h *= 0xff51afd7ed558ccdull;
    }
    h ^= h >> 33;
    const std::size_t mask = slots_.size() - 1;
    for (std::size_t s = h & mask;; s = (s + 1) & mask) {
      const LocalId head = slots_[s];
      if (head < 0) return s;
      bool same = true;
      for (int d = 0; d < Dim; ++d) same = same && keys_[std::size_t(head) * Dim + d] == key[d];
      if (same) return s;
    }
  }

  const mesh::SimplexMesh<Dim>& m_;
  Vec<Dim> origin_;
  double cell_;
  std::vector<LocalId> slots_, next_;
  std::vector<std::int64_t> keys_;
};

// `border` (optional): pairs of two nodes marked there are left to check_border_conformity.
template <int Dim>
void find_duplicate_nodes(const mesh::SimplexMesh<Dim>& m, const Box<Dim>& domain, double eps,
                          ConformityReport& r, Examples& ex, const std::vector<bool>* border = nullptr) {
  const std::size_t n = m.node_count();
  if (n == 0) return;
  if (!(eps > 0)) eps = std::numeric_limits<double>::min();
  NodeGrid<Dim> grid(m, domain.min, 2 * eps);
  for (std::size_t i = 0; i < n; ++i) {
    const double* pi = &m.coords[i * Dim];
    std::size_t twin = n;
    double gap = 0;
    grid.near(i, [&](std::size_t j) {
      if (j >= i || twin < n || (border && (*border)[i] && (*border)[j])) return;
      double dmax = 0;
      for (int d = 0; d < Dim; ++d) dmax = std::max(dmax, std::abs(pi[d] - m.coords[j * Dim + d]));
      if (dmax <= eps) {
        twin = j;
        gap = dmax;
      }
    });
    if (twin == n) continue;
    ++r.duplicate_nodes;
    if (ex.wants("duplicate")) {
      char buf[64];
      std::snprintf(buf, sizeof buf, gap == 0 ? " (exact)" : " (%.3g apart)", gap);
      ex.add("duplicate node " + point_text(m, LocalId(i)) + " of node " + point_text(m, LocalId(twin)) + buf);
    }
  }
}

// ---- T-junctions: nodes of open facets lying inside another open facet ----------------

// Is p in the closed facet minus its vertices, within tol (absolute)?
inline bool on_facet(const Vec2& p, const std::array<Vec2, 2>& f, double tol) {
  const double ab[2] = {f[1][0] - f[0][0], f[1][1] - f[0][1]};
  const double ap[2] = {p[0] - f[0][0], p[1] - f[0][1]};
  const double l2 = ab[0] * ab[0] + ab[1] * ab[1];
  if (!(l2 > 0)) return false;
  const double t = (ap[0] * ab[0] + ap[1] * ab[1]) / l2;
  const double l = std::sqrt(l2);
  if (t * l <= tol || (1 - t) * l <= tol) return false;
  const double cross = ab[0] * ap[1] - ab[1] * ap[0];
  return std::abs(cross) / l <= tol;
}

inline bool on_facet(const Vec3& p, const std::array<Vec3, 3>& f, double tol) {
  auto sub = [](const Vec3& a, const Vec3& b) { return Vec3{a[0] - b[0], a[1] - b[1], a[2] - b[2]}; };
  auto cross = [](const Vec3& a, const Vec3& b) {
    return Vec3{a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0]};
  };
  auto dot = [](const Vec3& a, const Vec3& b) { return a[0] * b[0] + a[1] * b[1] + a[2] * b[2]; };
  const Vec3 n = cross(sub(f[1], f[0]), sub(f[2], f[0]));
  const double n2 = dot(n, n);
  if (!(n2 > 0)) return false;
  const double nlen = std::sqrt(n2);
  if (std::abs(dot(sub(p, f[0]), n)) / nlen > tol) return false;
  for (int k = 0; k < 3; ++k)
    if (mesh::distance<3>(p, f[k]) <= tol) return false;  // a vertex, not a hanging node
  // Barycentric coordinates from the sub-triangles; each must be >= -tol in length units
  // (the signed distance from p to the opposite edge's line).
  for (int k = 0; k < 3; ++k) {
    const Vec3& a = f[(k + 1) % 3];
    const Vec3& b = f[(k + 2) % 3];
    const Vec3 e = sub(b, a);
    const double elen = std::sqrt(dot(e, e));
    if (!(elen > 0)) return false;
    // Signed distance inside the triangle, measured in its plane.
    const double inside = dot(cross(e, sub(p, a)), n) / (nlen * elen);
    if (inside < -tol) return false;
  }
  return true;
}

template <int Dim>
void find_hanging_nodes(const mesh::SimplexMesh<Dim>& m, const std::vector<detail::FacetNodes<Dim>>& open,
                        ConformityReport& r, Examples& ex) {
  if (open.empty()) return;
  std::vector<LocalId> nodes;
  for (const auto& f : open) nodes.insert(nodes.end(), f.begin(), f.end());
  std::sort(nodes.begin(), nodes.end());
  nodes.erase(std::unique(nodes.begin(), nodes.end()), nodes.end());

  // Uniform grid over the nodes, cells about one facet wide.
  Box<Dim> box;
  box.min = box.max = m.point(nodes[0]);
  for (LocalId n : nodes)
    for (int d = 0; d < Dim; ++d) {
      box.min[d] = std::min(box.min[d], m.coords[std::size_t(n) * Dim + d]);
      box.max[d] = std::max(box.max[d], m.coords[std::size_t(n) * Dim + d]);
    }
  double mean_length = 0;
  for (const auto& f : open) mean_length += detail::longest_edge(m, f.data(), Dim);
  mean_length /= static_cast<double>(open.size());
  double cell = mean_length > 0 ? mean_length : 1.0;
  std::array<std::size_t, Dim> dims;
  const std::size_t max_cells = 4 * nodes.size() + 64;
  for (;;) {
    std::size_t total = 1;
    for (int d = 0; d < Dim; ++d) {
      const double cells = std::floor((box.max[d] - box.min[d]) / cell) + 1;
      dims[d] = cells < 1e9 ? static_cast<std::size_t>(cells) : std::size_t(1e9);
      total = std::min<std::size_t>(total * dims[d], std::size_t(1) << 40);
    }
    if (total <= max_cells) break;
    cell *= 2;
  }
  auto coord_cell = [&](double x, int d) {
    const double u = std::floor((x - box.min[d]) / cell);
    return static_cast<std::size_t>(std::clamp(u, 0.0, double(dims[d] - 1)));
  };
  auto flat = [&](const std::array<std::size_t, Dim>& c) {
    std::size_t k = 0;
    for (int d = Dim - 1; d >= 0; --d) k = k * dims[d] + c[d];
    return k;
  };
  std::size_t total = 1;
  for (int d = 0; d < Dim; ++d) total *= dims[d];
  std::vector<std::size_t> start(total + 1, 0);
  std::vector<std::size_t> node_cell(nodes.size());
  for (std::size_t i = 0; i < nodes.size(); ++i) {
    std::array<std::size_t, Dim> c;
    for (int d = 0; d < Dim; ++d) c[d] = coord_cell(m.coords[std::size_t(nodes[i]) * Dim + d], d);
    node_cell[i] = flat(c);
    ++start[node_cell[i] + 1];
  }
  for (std::size_t k = 0; k < total; ++k) start[k + 1] += start[k];
  std::vector<LocalId> in_cell(nodes.size());
  {
    std::vector<std::size_t> fill(start.begin(), start.end() - 1);
    for (std::size_t i = 0; i < nodes.size(); ++i) in_cell[fill[node_cell[i]]++] = nodes[i];
  }

  std::vector<LocalId> hanging;
  for (const auto& f : open) {
    std::array<Vec<Dim>, Dim> pts;
    for (int k = 0; k < Dim; ++k) pts[k] = m.point(f[k]);
    const double tol = kOnFacetTolerance * detail::longest_edge(m, f.data(), Dim);
    std::array<std::size_t, Dim> lo, hi;
    for (int d = 0; d < Dim; ++d) {
      double a = pts[0][d], b = pts[0][d];
      for (int k = 1; k < Dim; ++k) a = std::min(a, pts[k][d]), b = std::max(b, pts[k][d]);
      lo[d] = coord_cell(a - tol, d);
      hi[d] = coord_cell(b + tol, d);
    }
    std::array<std::size_t, Dim> c = lo;
    for (;;) {
      const std::size_t k = flat(c);
      for (std::size_t i = start[k]; i < start[k + 1]; ++i) {
        const LocalId v = in_cell[i];
        if (std::find(f.begin(), f.end(), v) != f.end()) continue;
        if (!on_facet(m.point(v), pts, tol)) continue;
        hanging.push_back(v);
        if (ex.wants("hanging")) ex.add("hanging node " + point_text(m, v) + " inside open facet " + nodes_text(m, f));
      }
      int d = 0;
      while (d < Dim && c[d] == hi[d]) c[d] = lo[d], ++d;
      if (d == Dim) break;
      ++c[d];
    }
  }
  std::sort(hanging.begin(), hanging.end());
  r.hanging_nodes = static_cast<std::size_t>(std::unique(hanging.begin(), hanging.end()) - hanging.begin());
}

// Cells: node references, orientation, measure; marks the nodes they use.
template <int Dim>
void check_cells(const mesh::SimplexMesh<Dim>& m, const std::vector<bool>& valid, ConformityReport& r, Examples& ex,
                 std::vector<bool>& used) {
  used.assign(m.node_count(), false);
  double measure = 0;
  for (std::size_t c = 0; c < m.cell_count(); ++c) {
    const LocalId* cn = m.cell(c);
    if (!valid[c]) {
      ++r.bad_node_references;
      if (ex.wants("bad")) {
        std::string ids;
        for (int k = 0; k <= Dim; ++k) ids += (k ? ", " : "") + std::to_string(cn[k]);
        ex.add("cell " + std::to_string(c) + " names a node that does not exist: " + ids);
      }
      continue;
    }
    for (int k = 0; k <= Dim; ++k) used[std::size_t(cn[k])] = true;
    const double s = detail::signed_measure(m, cn);
    measure += std::abs(s);
    const double l = detail::longest_edge(m, cn, Dim + 1);
    const double scale = Dim == 2 ? l * l : l * l * l;
    if (!(std::abs(s) > kDegenerateTolerance * scale)) {
      ++r.degenerate_cells;
      if (ex.wants("degenerate"))
        ex.add("degenerate cell " + std::to_string(c) + ": " + nodes_text(m, std::span<const LocalId>(cn, Dim + 1)));
    } else if (s < 0) {
      ++r.inverted_cells;
      if (ex.wants("inverted"))
        ex.add("inverted cell " + std::to_string(c) + ": " + nodes_text(m, std::span<const LocalId>(cn, Dim + 1)));
    }
  }
  r.measure += measure;
}

// Unused nodes (those `skip` marks are counted elsewhere).
template <int Dim>
void count_unused(const mesh::SimplexMesh<Dim>& m, const std::vector<bool>& used, const std::vector<bool>* skip,
                  ConformityReport& r, Examples& ex) {
  for (std::size_t n = 0; n < m.node_count(); ++n)
    if (!used[n] && !(skip && (*skip)[n])) {
      ++r.unused_nodes;
      if (ex.wants("unused")) ex.add("unused node " + point_text(m, LocalId(n)));
    }
}

// A facet shared by `uses` cells: counted, and kept in `open_inside` when open off the box.
template <int Dim>
void classify_facet(const mesh::SimplexMesh<Dim>& m, const detail::FacetNodes<Dim>& f,
                    std::span<const detail::FacetUse> uses, const Box<Dim>& domain, double box_tol,
                    bool allow_inner_boundary, ConformityReport& r, Examples& ex,
                    std::vector<detail::FacetNodes<Dim>>& open_inside) {
  if (uses.size() > 2) {
    ++r.non_manifold_facets;
    if (ex.wants("non-manifold"))
      ex.add("facet " + nodes_text(m, f) + " shared by " + std::to_string(uses.size()) + " cells (first " +
             std::to_string(uses[0].cell) + ", " + std::to_string(uses[1].cell) + ", " +
             std::to_string(uses[2].cell) + ")");
  } else if (uses.size() == 2) {
    if (uses[0].odd == uses[1].odd) {
      ++r.mismatched_orientation_facets;
      if (ex.wants("orientation"))
        ex.add("facet " + nodes_text(m, f) + " has the same orientation in cells " + std::to_string(uses[0].cell) +
               " and " + std::to_string(uses[1].cell));
    }
  } else if (detail::facet_on_box<Dim>(m, f, domain, box_tol)) {
    ++r.boundary_facets;
  } else {
    open_inside.push_back(f);
    if (allow_inner_boundary) {
      ++r.inner_boundary_facets;
    } else {
      ++r.open_facets_inside;
      if (ex.wants("open"))
        ex.add("open facet inside the domain " + nodes_text(m, f) + " of cell " + std::to_string(uses[0].cell));
    }
  }
}

void finish_conformity(ConformityReport& r, double expected_measure, double measure_tolerance, Examples& ex) {
  r.expected_measure = expected_measure;
  r.measure_tolerance = measure_tolerance;
  if (expected_measure >= 0) {
    const double diff = std::abs(r.measure - expected_measure);
    r.measure_error = expected_measure > 0 ? diff / expected_measure : diff;
    if (!(r.measure_error <= measure_tolerance) && ex.wants("measure")) {
      char buf[160];
      std::snprintf(buf, sizeof buf, "total measure %.12g differs from the expected %.12g (relative %.3g)",
                    r.measure, expected_measure, r.measure_error);
      ex.add(buf);
    }
  }
  r.ok = r.duplicate_nodes == 0 && r.degenerate_cells == 0 && r.inverted_cells == 0 &&
         r.bad_node_references == 0 && r.non_manifold_facets == 0 &&
         r.mismatched_orientation_facets == 0 && r.open_facets_inside == 0 && r.hanging_nodes == 0 &&
         r.unused_nodes == 0 && (expected_measure < 0 || r.measure_error <= measure_tolerance);
}

}  // namespace

template <int Dim>
Box<Dim> bounding_box(const mesh::SimplexMesh<Dim>& m) {
  Box<Dim> b;
  if (m.node_count() == 0) return b;
  b.min = b.max = m.point(0);
  for (std::size_t i = 0; i < m.node_count(); ++i)
    for (int d = 0; d < Dim; ++d) {
      b.min[d] = std::min(b.min[d], m.coords[i * Dim + d]);
      b.max[d] = std::max(b.max[d], m.coords[i * Dim + d]);
    }
  return b;
}

template <int Dim>
double box_diagonal(const Box<Dim>& b) {
  return mesh::distance<Dim>(b.min, b.max);
}

template <int Dim>
ConformityReport check_conformity(const mesh::SimplexMesh<Dim>& m, const Box<Dim>& domain,
                                  double expected_measure, bool allow_inner_boundary,
                                  double measure_tolerance) {
  ConformityReport r;
  Examples ex(r.examples);
  const double diagonal = box_diagonal(domain);
  const std::vector<bool> valid = detail::valid_cells(m);
  std::vector<bool> used;
  check_cells(m, valid, r, ex, used);
  count_unused(m, used, nullptr, r, ex);
  find_duplicate_nodes(m, domain, kNearDuplicateTolerance * diagonal, r, ex);
  const double box_tol = kOnBoxTolerance * diagonal;
  std::vector<detail::FacetNodes<Dim>> open_inside;
  detail::for_each_facet<Dim>(m, valid, [&](const detail::FacetNodes<Dim>& f, std::span<const detail::FacetUse> uses) {
    classify_facet<Dim>(m, f, uses, domain, box_tol, allow_inner_boundary, r, ex, open_inside);
  });
  find_hanging_nodes<Dim>(m, open_inside, r, ex);
  finish_conformity(r, expected_measure, measure_tolerance, ex);
  return r;
}

namespace detail {

// A facet (nodes ascending by local id, `odd` the parity of its cell's listing) by the
// nodes' global ids, ascending, with the parity relative to that order.
template <int Dim>
GlobalFacet<Dim> global_facet(const mesh::SimplexMesh<Dim>& m, const FacetNodes<Dim>& f, bool odd) {
  GlobalFacet<Dim> g;
  for (int k = 0; k < Dim; ++k) g.ids[k] = m.node_global_id[std::size_t(f[k])];
  for (int i = 0; i < Dim; ++i)
    for (int j = i; j > 0 && g.ids[j - 1] > g.ids[j]; --j) {
      std::swap(g.ids[j - 1], g.ids[j]);
      odd = !odd;
    }
  g.odd = odd;
  return g;
}

template <int Dim>
void check_piece_conformity(const mesh::SimplexMesh<Dim>& m, const std::vector<bool>& shared, const Box<Dim>& domain,
                            bool allow_inner_boundary, std::size_t cell_offset, ConformityReport& r,
                            PieceBorder<Dim>& border) {
  Examples ex(r.examples);
  const double diagonal = box_diagonal(domain);
  const std::vector<bool> valid = detail::valid_cells(m);
  check_cells(m, valid, r, ex, border.used);
  count_unused(m, border.used, &shared, r, ex);
  // Facets: those of shared nodes only may meet other pieces' (they are judged with all their
  // uses); the piece's own open facets off the box go to the border (hanging nodes).
  const double box_tol = kOnBoxTolerance * diagonal;
  std::vector<FacetNodes<Dim>> open_inside;
  for_each_facet<Dim>(m, valid, [&](const FacetNodes<Dim>& f, std::span<const FacetUse> uses) {
    if (std::all_of(f.begin(), f.end(), [&](LocalId n) { return shared[std::size_t(n)]; })) {
      for (const FacetUse& u : uses) {
        GlobalFacet<Dim> g = global_facet<Dim>(m, f, u.odd);
        g.cell = cell_offset + u.cell;
        border.shared_facets.push_back(g);
      }
      return;
    }
    // Not all shared: no other piece has it, so it is judged here; an open one off the box
    // goes to the border too (hanging nodes, void nodes).
    const std::size_t before = open_inside.size();
    classify_facet<Dim>(m, f, uses, domain, box_tol, allow_inner_boundary, r, ex, open_inside);
    if (open_inside.size() > before) {
      std::array<GlobalId, Dim> ids;
      for (int k = 0; k < Dim; ++k) ids[k] = m.node_global_id[std::size_t(f[k])];
      border.open_facets.push_back(ids);
    }
  });
  std::vector<bool> on_border = shared;
  border.open_nodes.clear();
  for (const FacetNodes<Dim>& f : open_inside)
    for (LocalId n : f)
      if (!on_border[std::size_t(n)]) {
        on_border[std::size_t(n)] = true;
        border.open_nodes.push_back(n);
      }
  std::sort(border.open_nodes.begin(), border.open_nodes.end());
  find_duplicate_nodes(m, domain, kNearDuplicateTolerance * diagonal, r, ex, &on_border);
}

template <int Dim>
std::vector<LocalId> check_border_conformity(const mesh::SimplexMesh<Dim>& border,
                                             std::vector<BorderFacetUse<Dim>>& shared_uses,
                                             const std::vector<FacetNodes<Dim>>& open_facets, const Box<Dim>& domain,
                                             bool allow_inner_boundary, ConformityReport& r) {
  Examples ex(r.examples);
  const double diagonal = box_diagonal(domain);
  const double box_tol = kOnBoxTolerance * diagonal;
  std::vector<FacetNodes<Dim>> open_inside;
  std::sort(shared_uses.begin(), shared_uses.end(), [](const BorderFacetUse<Dim>& a, const BorderFacetUse<Dim>& b) {
    return a.nodes != b.nodes ? a.nodes < b.nodes : a.use.cell < b.use.cell;
  });
  std::vector<FacetUse> uses;
  for (std::size_t i = 0; i < shared_uses.size();) {
    std::size_t j = i;
    uses.clear();
    while (j < shared_uses.size() && shared_uses[j].nodes == shared_uses[i].nodes) uses.push_back(shared_uses[j++].use);
    classify_facet<Dim>(border, shared_uses[i].nodes, std::span<const FacetUse>(uses), domain, box_tol,
                   allow_inner_boundary, r, ex, open_inside);
    i = j;
  }
  open_inside.insert(open_inside.end(), open_facets.begin(), open_facets.end());  // counted by their pieces
  find_duplicate_nodes(border, domain, kNearDuplicateTolerance * diagonal, r, ex);
  find_hanging_nodes<Dim>(border, open_inside, r, ex);
  std::vector<LocalId> nodes;
  for (const FacetNodes<Dim>& f : open_inside) nodes.insert(nodes.end(), f.begin(), f.end());
  std::sort(nodes.begin(), nodes.end());
  nodes.erase(std::unique(nodes.begin(), nodes.end()), nodes.end());
  return nodes;
}

void finish_piecewise_conformity(ConformityReport& r, double expected_measure, double measure_tolerance) {
  Examples ex(r.examples);
  finish_conformity(r, expected_measure, measure_tolerance, ex);
}

#define CISAMR_CONFORMITY_PARTS(D)                                                                              \
  template void check_piece_conformity<D>(const mesh::SimplexMesh<D>&, const std::vector<bool>&, const Box<D>&, \
                                          bool, std::size_t, ConformityReport&, PieceBorder<D>&);             \
  template std::vector<LocalId> check_border_conformity<D>(const mesh::SimplexMesh<D>&,                        \
                                                           std::vector<BorderFacetUse<D>>&,                     \
                                                           const std::vector<FacetNodes<D>>&, const Box<D>&,    \
                                                           bool, ConformityReport&);
CISAMR_CONFORMITY_PARTS(2)
CISAMR_CONFORMITY_PARTS(3)
#undef CISAMR_CONFORMITY_PARTS

}  // namespace detail

template Box<2> bounding_box<2>(const mesh::SimplexMesh<2>&);
template Box<3> bounding_box<3>(const mesh::SimplexMesh<3>&);
template double box_diagonal<2>(const Box<2>&);
template double box_diagonal<3>(const Box<3>&);
template ConformityReport check_conformity<2>(const mesh::SimplexMesh<2>&, const Box<2>&, double, bool, double);
template ConformityReport check_conformity<3>(const mesh::SimplexMesh<3>&, const Box<3>&, double, bool, double);

}  // namespace cisamr::quality
