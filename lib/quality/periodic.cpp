#include "quality/periodic.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstring>

#include "quality/facet_table.hpp"

namespace cisamr::quality {

template <int Dim>
PeriodicReport check_periodic(const mesh::SimplexMesh<Dim>& m, const Box<Dim>& box, const std::array<bool, Dim>& axes) {
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
    r.unmatched = static_cast<std::int64_t>(difference.size());
    if (!difference.empty())
      for (const Point& p : difference.front())
        for (int d = 0; d < Dim; ++d) r.first_unmatched[d] += p[static_cast<std::size_t>(d)] / Dim;
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
    std::snprintf(buf, sizeof buf, "; %c: %lld facets each side, %lld unmatched", "xyz"[a.axis],
                  static_cast<long long>(a.max_facets), static_cast<long long>(a.unmatched));
    s += buf;
    if (a.unmatched)
      std::snprintf(buf, sizeof buf, " (one at %.9g %.9g %.9g)", a.first_unmatched[0], a.first_unmatched[1], a.first_unmatched[2]), s += buf;
    if (a.near_face_nodes)
      std::snprintf(buf, sizeof buf, ", %lld nodes off the face by rounding", static_cast<long long>(a.near_face_nodes)), s += buf;
  }
  return s;
}

template PeriodicReport check_periodic<2>(const mesh::SimplexMesh<2>&, const Box<2>&, const std::array<bool, 2>&);
template PeriodicReport check_periodic<3>(const mesh::SimplexMesh<3>&, const Box<3>&, const std::array<bool, 3>&);

}  // namespace cisamr::quality
