// Aspect-ratio statistics: one pass over the cells, histogram with fixed 0.1-wide bins,
// a bounded heap for the worst cells, and the extreme (dihedral) angles.
#include <algorithm>
#include <cmath>
#include <limits>

#include "mesh/metrics.hpp"
#include "quality/quality.hpp"

namespace cisamr::quality {
namespace {

constexpr double kRadToDeg = 180.0 / 3.14159265358979323846;

// Cosines of the extreme angles seen so far: the smallest angle has the largest cosine.
struct AngleRange {
  double cos_of_min_angle = -2;  // max cosine seen
  double cos_of_max_angle = 2;   // min cosine seen
  void add(double c) {
    if (!(c == c)) return;  // NaN: zero-length edge
    c = std::clamp(c, -1.0, 1.0);
    cos_of_min_angle = std::max(cos_of_min_angle, c);
    cos_of_max_angle = std::min(cos_of_max_angle, c);
  }
};

void add_triangle_angles(const Vec2& a, const Vec2& b, const Vec2& c, AngleRange& r) {
  const double ab[2] = {b[0] - a[0], b[1] - a[1]}, bc[2] = {c[0] - b[0], c[1] - b[1]},
               ca[2] = {a[0] - c[0], a[1] - c[1]};
  const double lab = ab[0] * ab[0] + ab[1] * ab[1], lbc = bc[0] * bc[0] + bc[1] * bc[1],
               lca = ca[0] * ca[0] + ca[1] * ca[1];
  if (!(lab > 0 && lbc > 0 && lca > 0)) return;
  // Angle at a is between ab and -ca, and so on.
  r.add(-(ab[0] * ca[0] + ab[1] * ca[1]) / std::sqrt(lab * lca));
  r.add(-(ab[0] * bc[0] + ab[1] * bc[1]) / std::sqrt(lab * lbc));
  r.add(-(bc[0] * ca[0] + bc[1] * ca[1]) / std::sqrt(lbc * lca));
}

// Adds the tet's dihedral angles to `r` and returns its aspect ratio, equal bit for bit to
// mesh::aspect_ratio(p[0], p[1], p[2], p[3]): the faces' cross products serve both (each
// face area there is half the norm of the same cross product, up to an exact sign flip,
// summed in the same order), which saves a third of the statistics' time.
double add_dihedral_angles_and_aspect(const Vec3* p, AngleRange& r) {
  // Outward normal of the face opposite vertex i (unnormalised).
  static constexpr int kFace[4][3] = {{1, 2, 3}, {0, 3, 2}, {0, 1, 3}, {0, 2, 1}};
  double n[4][3], len2[4];
  for (int i = 0; i < 4; ++i) {
    const Vec3 &a = p[kFace[i][0]], &b = p[kFace[i][1]], &c = p[kFace[i][2]];
    const double u[3] = {b[0] - a[0], b[1] - a[1], b[2] - a[2]};
    const double v[3] = {c[0] - a[0], c[1] - a[1], c[2] - a[2]};
    n[i][0] = u[1] * v[2] - u[2] * v[1];
    n[i][1] = u[2] * v[0] - u[0] * v[2];
    n[i][2] = u[0] * v[1] - u[1] * v[0];
    // Make it point away from vertex i whatever the cell's orientation.
    const double away = n[i][0] * (a[0] - p[i][0]) + n[i][1] * (a[1] - p[i][1]) +
                        n[i][2] * (a[2] - p[i][2]);
    if (away < 0)
      for (double& x : n[i]) x = -x;
    len2[i] = n[i][0] * n[i][0] + n[i][1] * n[i][1] + n[i][2] * n[i][2];
  }
  // The faces' norms serve both: four square roots and four divisions per tet instead of
  // ten and six (the statistics' loop waited on them).
  double norm[4], inverse[4];
  for (int k = 0; k < 4; ++k) {
    norm[k] = std::sqrt(len2[k]);
    inverse[k] = len2[k] > 0 ? 1 / norm[k] : 0;
  }
  for (int k = 0; k < 4; ++k)
    for (int l = k + 1; l < 4; ++l) {
      if (!(len2[k] > 0 && len2[l] > 0)) continue;
      // The dihedral angle at the edge shared by faces k and l.
      r.add(-(n[k][0] * n[l][0] + n[k][1] * n[l][1] + n[k][2] * n[l][2]) * inverse[k] * inverse[l]);
    }
  return mesh::aspect_ratio_with_faces(p[0], p[1], p[2], p[3],
                                       0.5 * norm[0] + 0.5 * norm[1] + 0.5 * norm[2] + 0.5 * norm[3]);
}

// Orders the heap so that its top is the *least* bad of the kept cells.
bool less_bad(const AspectStats::Worst& a, const AspectStats::Worst& b) {
  if (a.aspect_ratio != b.aspect_ratio) return a.aspect_ratio < b.aspect_ratio;
  return a.cell > b.cell;
}
bool worse_first(const AspectStats::Worst& a, const AspectStats::Worst& b) { return less_bad(b, a); }

// Histogram edge i: 1.0, 1.1, ... written as (10 + i) / 10 so each is the double nearest
// to the decimal value.
double edge(std::size_t i) { return static_cast<double>(10 + i) / 10.0; }
constexpr std::size_t kMaxRegularBins = 990;  // edge(990) = kHistogramMaxEdge
static_assert(kHistogramBinWidth == 0.1 && kHistogramMaxEdge == 100.0);

// Bin of a finite aspect ratio among [edge(i), edge(i+1)); kMaxRegularBins for >= 100.
std::size_t raw_bin(double ar) {
  if (!(ar > 1.0)) return 0;
  if (ar >= kHistogramMaxEdge) return kMaxRegularBins;
  auto i = static_cast<std::size_t>((ar - 1.0) * 10.0);
  if (i > 0 && ar < edge(i)) --i;
  else if (ar >= edge(i + 1)) ++i;
  return i;
}

}  // namespace

template <int Dim>
AspectStats aspect_statistics(const mesh::SimplexMesh<Dim>& m, double bound, int worst_count,
                              std::vector<double>* cell_aspect_ratio) {
  AspectStats s;
  s.bound = bound;
  s.count = m.cell_count();
  const std::size_t keep = worst_count > 0 ? static_cast<std::size_t>(worst_count) : 0;
  std::vector<std::size_t> raw;  // grows to the largest bin seen (at most ~1000 entries)
  std::size_t infinite = 0;
  double sum = 0;
  std::size_t finite = 0;
  double max_finite = 0;
  AngleRange angles;
  const std::size_t nodes = m.node_count();
  if (cell_aspect_ratio != nullptr) cell_aspect_ratio->resize(s.count);

  for (std::size_t c = 0; c < s.count; ++c) {
    const LocalId* cn = m.cell(c);
    bool valid = true;
    for (int k = 0; k <= Dim; ++k)
      if (cn[k] < 0 || static_cast<std::size_t>(cn[k]) >= nodes) valid = false;
    // A cell naming a missing node counts as degenerate (check_conformity reports it).
    double ar = std::numeric_limits<double>::infinity();
    if (valid) {
      if constexpr (Dim == 2) {
        ar = mesh::cell_aspect_ratio(m, c);
        add_triangle_angles(m.point(cn[0]), m.point(cn[1]), m.point(cn[2]), angles);
      } else {
        const Vec3 p[4] = {m.point(cn[0]), m.point(cn[1]), m.point(cn[2]), m.point(cn[3])};
        ar = add_dihedral_angles_and_aspect(p, angles);
      }
    }
    if (cell_aspect_ratio != nullptr) (*cell_aspect_ratio)[c] = ar;
    if (std::isfinite(ar)) {
      sum += ar;
      ++finite;
      const std::size_t b = raw_bin(ar);
      if (b >= raw.size()) raw.resize(b + 1, 0);
      ++raw[b];
      max_finite = std::max(max_finite, ar);
    } else {
      ++infinite;
    }
    if (!(ar <= bound)) ++s.above_bound;

    if (keep > 0 && (s.worst.size() < keep || less_bad(s.worst.front(), {c, ar, {}, 0}))) {
      AspectStats::Worst w;
      w.cell = c;
      w.aspect_ratio = ar;
      w.phase = c < m.cell_phase.size() ? m.cell_phase[c] : 0;
      if (valid)
        for (int k = 0; k <= Dim; ++k)
          for (int d = 0; d < Dim; ++d)
            w.centroid[d] += m.coords[static_cast<std::size_t>(cn[k]) * Dim + d] / (Dim + 1);
      if (s.worst.size() == keep) {
        std::pop_heap(s.worst.begin(), s.worst.end(), worse_first);
        s.worst.pop_back();
      }
      s.worst.push_back(w);
      std::push_heap(s.worst.begin(), s.worst.end(), worse_first);
    }
  }
  std::sort(s.worst.begin(), s.worst.end(), worse_first);
  s.max = infinite > 0 ? std::numeric_limits<double>::infinity() : max_finite;
  s.mean = finite > 0 ? sum / static_cast<double>(finite) : 0;
  if (angles.cos_of_min_angle >= -1) {
    s.min_angle_deg = std::acos(angles.cos_of_min_angle) * kRadToDeg;
    s.max_angle_deg = std::acos(angles.cos_of_max_angle) * kRadToDeg;
  }

  // Regular bins up to the first edge above max(bound, largest finite value), capped at
  // kHistogramMaxEdge; then the overflow bin.
  const double top = std::max(bound, max_finite);
  const std::size_t regular = std::min(raw_bin(top) + 1, kMaxRegularBins);
  s.bin_edges.resize(regular + 1);
  for (std::size_t i = 0; i <= regular; ++i) s.bin_edges[i] = edge(i);
  s.histogram.assign(regular + 1, 0);
  for (std::size_t i = 0; i < raw.size(); ++i) s.histogram[std::min(i, regular)] += raw[i];
  s.histogram[regular] += infinite;
  return s;
}

template AspectStats aspect_statistics<2>(const mesh::SimplexMesh<2>&, double, int, std::vector<double>*);
template AspectStats aspect_statistics<3>(const mesh::SimplexMesh<3>&, double, int, std::vector<double>*);

void add_histogram(AspectStats& total, const std::vector<double>& edges, const std::vector<std::size_t>& hist) {
  if (edges.size() > total.bin_edges.size()) {
    const std::size_t overflow = total.histogram.empty() ? 0 : total.histogram.back();
    if (!total.histogram.empty()) total.histogram.back() = 0;
    total.bin_edges = edges;
    total.histogram.resize(edges.size(), 0);
    total.histogram.back() += overflow;
  }
  for (std::size_t i = 0; i + 1 < hist.size(); ++i) total.histogram[i] += hist[i];
  if (!hist.empty()) total.histogram.back() += hist.back();
}

void merge_into(AspectStats& total, const AspectStats& part) {
  total.worst.clear();
  if (part.count == 0) return;
  if (total.count == 0) {
    const double bound = total.bound;
    total = part;
    total.worst.clear();
    if (bound > 0) total.bound = bound;
    return;
  }
  total.max = std::max(total.max, part.max);
  const double weighted = total.mean * static_cast<double>(total.count) + part.mean * static_cast<double>(part.count);
  total.count += part.count;
  total.mean = weighted / static_cast<double>(total.count);
  total.above_bound += part.above_bound;
  total.min_angle_deg = std::min(total.min_angle_deg, part.min_angle_deg);
  total.max_angle_deg = std::max(total.max_angle_deg, part.max_angle_deg);
  add_histogram(total, part.bin_edges, part.histogram);
}

}  // namespace cisamr::quality
