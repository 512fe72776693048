#include "quality/periodic.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstring>

#include "quality/facet_table.hpp"

namespace cisamr::quality {

template <int Dim>
PeriodicReport check_periodic(const mesh::SimplexMesh<Dim>& m, const Box<Dim>& box, const std::array<bool, Dim>& axes,
                              const std::function<bool(const Vec<Dim>&)>& in_void) {
  using Point = std::array<double, Dim>;
  using Facet = std::array<Point, Dim>;  // points sorted lexicographically
  PeriodicReport report;
  // Boundary facets: used by one cell only.
  std::vector<detail::FacetNodes<Dim>> boundary;
  detail::for_each_facet<Dim>(m, detail::valid_cells(m),
                              [&](const detail::FacetNodes<Dim>& nodes, std::span<const detail::FacetUse> uses) {
                                if (uses.size() == 1) boundary.push_back(nodes);
                              });
  const auto coord = [&](LocalId n, int d) { return m.coords[static_cast<std::size_t>(n) * Dim + static_cast<std::size_t>(d)]; };
  const auto less = [](const Facet& a, const Facet& b) { return std::memcmp(a.data(), b.data(), sizeof(Facet)) < 0; };
  // Whether some cell holds point p (brute force: only for the few facets left unmatched).
  // A hole there is a void's: the facet has no partner because the other side has no cells.
  const auto covered = [&](const Vec<Dim>& p) {
    for (std::size_t c = 0; c < m.cell_count(); ++c) {
      const LocalId* v = m.cell(c);
      std::array<Vec<Dim>, Dim + 1> x;
      for (int k = 0; k <= Dim; ++k)
        for (int d = 0; d < Dim; ++d) x[static_cast<std::size_t>(k)][d] = coord(v[k], d);
      // p = x0 + Σ λ_k (x_k − x0): solve by Cramer's rule, all λ ≥ 0 and Σ ≤ 1 (to rounding).
      double a[Dim][Dim], rhs[Dim];
      for (int d = 0; d < Dim; ++d) {
        rhs[d] = p[d] - x[0][d];
        for (int k = 0; k < Dim; ++k) a[d][k] = x[static_cast<std::size_t>(k + 1)][d] - x[0][d];
      }
      const auto det = [&](int replaced) {
        double b[Dim][Dim];
        for (int d = 0; d < Dim; ++d)
          for (int k = 0; k < Dim; ++k) b[d][k] = k == replaced ? rhs[d] : a[d][k];
        if constexpr (Dim == 2) return b[0][0] * b[1][1] - b[0][1] * b[1][0];
        else
          return b[0][0] * (b[1][1] * b[2][2] - b[1][2] * b[2][1]) - b[0][1] * (b[1][0] * b[2][2] - b[1][2] * b[2][0]) +
                 b[0][2] * (b[1][0] * b[2][1] - b[1][1] * b[2][0]);
      };
      const double whole = det(-1);
      if (whole == 0) continue;
      double sum = 0;
      bool inside = true;
      for (int k = 0; k < Dim && inside; ++k) {
        const double lambda = det(k) / whole;
        inside = lambda >= -1e-12;
        sum += lambda;
      }
      if (inside && sum <= 1 + 1e-12) return true;
    }
    return false;
  };
  for (int a = 0; a < Dim; ++a) {
    if (!axes[static_cast<std::size_t>(a)]) continue;
    PeriodicAxisReport r;
    r.axis = a;
    std::vector<Facet> from_min, on_max;
    for (const auto& f : boundary) {
      bool all_min = true, all_max = true;
      for (LocalId n : f) all_min &= coord(n, a) == box.min[a], all_max &= coord(n, a) == box.max[a];
      if (!all_min && !all_max) continue;
      Facet facet;
      for (int k = 0; k < Dim; ++k) {
        for (int d = 0; d < Dim; ++d) facet[static_cast<std::size_t>(k)][static_cast<std::size_t>(d)] = coord(f[static_cast<std::size_t>(k)], d);
        if (all_min) facet[static_cast<std::size_t>(k)][static_cast<std::size_t>(a)] = box.max[a];  // the translate
      }
      std::sort(facet.begin(), facet.end(), [](const Point& p, const Point& q) { return std::memcmp(p.data(), q.data(), sizeof(Point)) < 0; });
      (all_min ? from_min : on_max).push_back(facet);
    }
    r.min_facets = static_cast<std::int64_t>(from_min.size());
    r.max_facets = static_cast<std::int64_t>(on_max.size());
    std::sort(from_min.begin(), from_min.end(), less);
    std::sort(on_max.begin(), on_max.end(), less);
    std::vector<Facet> difference;
    std::set_symmetric_difference(from_min.begin(), from_min.end(), on_max.begin(), on_max.end(),
                                  std::back_inserter(difference), less);
    // A facet left over on one face: its translate on the other face, just inside the
    // domain, in a void? (Its own side is in the mesh: the other side must be void.)
    const double inward = 1e-7 * (box.max[a] - box.min[a]);
    for (const Facet& f : difference) {
      Vec<Dim> centre{};
      for (const Point& p : f)
        for (int d = 0; d < Dim; ++d) centre[d] += p[static_cast<std::size_t>(d)] / Dim;
      const bool is_max = std::binary_search(on_max.begin(), on_max.end(), f, less);
      Vec<Dim> across = centre;
      across[a] = is_max ? box.min[a] + inward : box.max[a] - inward;
      if ((in_void && in_void(across)) || !covered(across)) {
        ++r.facing_void;
        continue;
      }
      if (r.unmatched++ == 0)
        for (int d = 0; d < Dim; ++d) r.first_unmatched[d] = centre[d];
    }
    // Flatness: a node meant for a face but off it by rounding would escape the match above.
    const double tol = 1e-9 * std::max(box.max[a] - box.min[a], 1e-300);
    for (std::size_t n = 0; n < m.node_count(); ++n) {
      const double x = coord(static_cast<LocalId>(n), a);
      if ((x != box.min[a] && std::abs(x - box.min[a]) <= tol) || (x != box.max[a] && std::abs(x - box.max[a]) <= tol))
        ++r.near_face_nodes;
    }
    report.ok = report.ok && r.unmatched == 0 && r.near_face_nodes == 0;
    report.axes.push_back(r);
  }
  return report;
}

std::string periodic_summary(const PeriodicReport& r) {
  std::string s = r.ok ? "ok" : "FAILED";
  for (const PeriodicAxisReport& a : r.axes) {
    char buf[240];
    std::snprintf(buf, sizeof buf, "; %c: %lld facets on the max face, %lld unmatched", "xyz"[a.axis],
                  static_cast<long long>(a.max_facets), static_cast<long long>(a.unmatched));
    s += buf;
    if (a.facing_void)
      std::snprintf(buf, sizeof buf, " (%lld facing a void across the period)", static_cast<long long>(a.facing_void)), s += buf;
    if (a.unmatched)
      std::snprintf(buf, sizeof buf, " (one at %.9g %.9g %.9g)", a.first_unmatched[0], a.first_unmatched[1], a.first_unmatched[2]), s += buf;
    if (a.near_face_nodes)
      std::snprintf(buf, sizeof buf, ", %lld nodes off the face by rounding", static_cast<long long>(a.near_face_nodes)), s += buf;
  }
  return s;
}

template PeriodicReport check_periodic<2>(const mesh::SimplexMesh<2>&, const Box<2>&, const std::array<bool, 2>&,
                                          const std::function<bool(const Vec<2>&)>&);
template PeriodicReport check_periodic<3>(const mesh::SimplexMesh<3>&, const Box<3>&, const std::array<bool, 3>&,
                                          const std::function<bool(const Vec<3>&)>&);

}  // namespace cisamr::quality
