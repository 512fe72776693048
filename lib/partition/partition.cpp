// Algorithm 1 of the paper (note §9), on the background lattice:
//   1. load field on the lattice (load_field.cpp);
//   2. over-decomposition into 2^d leaves per axis (≥ oversubscription·n leaves);
//   3. repeated merging of the two face-sharing boxes of least combined load (min-heap,
//      ties: smaller shared face, then ids), while more than n boxes remain;
//   4. [ours] face sliding: the most loaded box and a face-sharing partner re-cut their union
//      (along either axis) where the larger half is lightest, while that lowers the maximum;
//   5. several depths are tried; the lowest maximum load wins (then the smaller shared faces).
#include <algorithm>
#include <cmath>
#include <numeric>
#include <optional>
#include <queue>
#include <tuple>

#include "core/check.hpp"
#include "core/error.hpp"
#include "geometry/oracle.hpp"
#include "partition/load_field.hpp"
#include "partition/partition.hpp"

namespace cisamr::partition {
namespace {

using Index3 = std::array<std::int64_t, 3>;

struct RBox {  // a box in raster indices, half-open
  Index3 lo{}, hi{};
  double load = 0;
  double cost = 0;  // LoadField::box_cost: what the cuts balance
};

// Sets b's load and cost from the field.
void weigh(const LoadField& f, RBox& b) {
  b.load = f.box_load(b.lo, b.hi);
  b.cost = f.box_cost(b.lo, b.hi);
}

// Measure (length/area) of the face between two boxes that touch along `axis`.
double face_measure(const LoadField& f, const RBox& a, const RBox& b, int axis) {
  double m = 1;
  for (int d = 0; d < f.dim; ++d) {
    if (d == axis) continue;
    const double lo = std::max(f.coordinate(d, a.lo[d]), f.coordinate(d, b.lo[d]));
    const double hi = std::min(f.coordinate(d, a.hi[d]), f.coordinate(d, b.hi[d]));
    m *= std::max(0.0, hi - lo);
  }
  return m;
}

// Do a and b share a full face (same extent in every other axis)? Returns the axis or −1.
int full_face_axis(const LoadField& f, const RBox& a, const RBox& b) {
  for (int axis = 0; axis < f.dim; ++axis) {
    if (a.hi[axis] != b.lo[axis] && b.hi[axis] != a.lo[axis]) continue;
    bool same = true;
    for (int d = 0; d < f.dim; ++d)
      if (d != axis && (a.lo[d] != b.lo[d] || a.hi[d] != b.hi[d])) same = false;
    if (same) return axis;
  }
  return -1;
}

double max_cost(const std::vector<RBox>& boxes) {
  double m = 0;
  for (const auto& b : boxes) m = std::max(m, b.cost);
  return m;
}

double internal_faces(const LoadField& f, const std::vector<RBox>& boxes) {
  double s = 0;
  for (std::size_t i = 0; i < boxes.size(); ++i)
    for (std::size_t j = i + 1; j < boxes.size(); ++j)
      for (int axis = 0; axis < f.dim; ++axis)
        if (boxes[i].hi[axis] == boxes[j].lo[axis] || boxes[j].hi[axis] == boxes[i].lo[axis])
          s += face_measure(f, boxes[i], boxes[j], axis);
  return s;
}

// Leaf boundaries: k leaves along an axis of n raster cells.
std::vector<std::int64_t> splits(std::int64_t n, std::int64_t k) {
  std::vector<std::int64_t> s(k + 1);
  for (std::int64_t j = 0; j <= k; ++j) s[j] = j * n / k;
  return s;
}

// Steps 2–3 for one depth. Returns nothing when merging gets stuck above n boxes.
std::optional<std::vector<RBox>> merge_from_leaves(const LoadField& f, const Index3& leaves, int n, int* merges) {
  std::array<std::vector<std::int64_t>, 3> cut;
  for (int d = 0; d < 3; ++d) cut[d] = splits(f.n[d], leaves[d]);
  // Boxes in leaf indices (so faces compare as integers); loads from the field.
  struct LBox {
    Index3 lo, hi;
    double load;
    bool alive;
  };
  std::vector<LBox> boxes;
  for (std::int64_t k = 0; k < leaves[2]; ++k)
    for (std::int64_t j = 0; j < leaves[1]; ++j)
      for (std::int64_t i = 0; i < leaves[0]; ++i) {
        LBox b{{i, j, k}, {i + 1, j + 1, k + 1}, 0, true};
        b.load = f.box_load({cut[0][i], cut[1][j], cut[2][k]}, {cut[0][i + 1], cut[1][j + 1], cut[2][k + 1]});
        boxes.push_back(b);
      }
  const std::int64_t m0 = static_cast<std::int64_t>(boxes.size());
  // Union–find from leaves to their current box.
  std::vector<std::int64_t> parent(m0);
  std::iota(parent.begin(), parent.end(), 0);
  std::vector<std::int64_t> leaf_box(m0);
  std::iota(leaf_box.begin(), leaf_box.end(), 0);
  auto find = [&](std::int64_t x) {
    while (parent[x] != x) x = parent[x] = parent[parent[x]];
    return x;
  };
  std::vector<std::int64_t> box_of_root(m0);  // root leaf → box id
  std::iota(box_of_root.begin(), box_of_root.end(), 0);
  std::vector<std::int64_t> root_of_box(m0);
  std::iota(root_of_box.begin(), root_of_box.end(), 0);
  auto box_at = [&](const Index3& leaf) {
    return box_of_root[find(leaf[0] + leaves[0] * (leaf[1] + leaves[1] * leaf[2]))];
  };
  auto face_of = [&](const LBox& a, const LBox& b, int axis) {
    double m = 1;
    for (int d = 0; d < f.dim; ++d)
      if (d != axis) m *= f.coordinate(d, cut[d][a.hi[d]]) - f.coordinate(d, cut[d][a.lo[d]]);
    return m;
  };
  struct Entry {
    double load, face;
    std::int64_t a, b;
    int axis;
    bool operator>(const Entry& o) const {
      if (load != o.load) return load > o.load;
      if (face != o.face) return face > o.face;
      if (a != o.a) return a > o.a;
      return b > o.b;
    }
  };
  std::priority_queue<Entry, std::vector<Entry>, std::greater<Entry>> heap;
  auto push_partners = [&](std::int64_t id) {
    const LBox& a = boxes[id];
    for (int axis = 0; axis < f.dim; ++axis)
      for (int side = 0; side < 2; ++side) {
        Index3 probe = a.lo;
        probe[axis] = side ? a.hi[axis] : a.lo[axis] - 1;
        if (probe[axis] < 0 || probe[axis] >= leaves[axis]) continue;
        const std::int64_t other = box_at(probe);
        const LBox& b = boxes[other];
        bool full = side ? b.lo[axis] == a.hi[axis] : b.hi[axis] == a.lo[axis];
        for (int d = 0; d < f.dim && full; ++d)
          if (d != axis && (b.lo[d] != a.lo[d] || b.hi[d] != a.hi[d])) full = false;
        if (!full) continue;
        heap.push({a.load + b.load, face_of(a, b, axis), std::min(id, other), std::max(id, other), axis});
      }
  };
  for (std::int64_t id = 0; id < m0; ++id) push_partners(id);
  std::int64_t alive = m0;
  *merges = 0;
  while (alive > n && !heap.empty()) {
    const Entry e = heap.top();
    heap.pop();
    if (!boxes[e.a].alive || !boxes[e.b].alive) continue;
    LBox u{};
    for (int d = 0; d < 3; ++d) {
      u.lo[d] = std::min(boxes[e.a].lo[d], boxes[e.b].lo[d]);
      u.hi[d] = std::max(boxes[e.a].hi[d], boxes[e.b].hi[d]);
    }
    u.load = boxes[e.a].load + boxes[e.b].load;
    u.alive = true;
    boxes[e.a].alive = boxes[e.b].alive = false;
    const std::int64_t id = static_cast<std::int64_t>(boxes.size());
    boxes.push_back(u);
    const std::int64_t ra = root_of_box[e.a], rb = root_of_box[e.b];
    parent[rb] = ra;
    box_of_root[ra] = id;
    root_of_box.push_back(ra);
    --alive;
    ++*merges;
    push_partners(id);
  }
  if (alive > n) return std::nullopt;
  std::vector<RBox> out;
  for (const auto& b : boxes)
    if (b.alive) {
      RBox r;
      for (int d = 0; d < 3; ++d) {
        r.lo[d] = cut[d][b.lo[d]];
        r.hi[d] = cut[d][b.hi[d]];
      }
      weigh(f, r);
      out.push_back(r);
    }
  return out;
}

// Step 4: slide the faces of the costliest box (LoadField::box_cost: its load, plus its
// ghost's when the options give one). Each move re-cuts the union of that box and a
// full-face partner at the lattice line that minimises the costlier half; applied only when
// it lowers that box's cost, so the maximum never grows and the loop ends.
int rebalance(const LoadField& f, std::vector<RBox>& boxes) {
  int moves = 0;
  const int limit = 20 * static_cast<int>(boxes.size()) + 100;
  for (int iter = 0; iter < limit; ++iter) {
    std::size_t top = 0;
    for (std::size_t i = 1; i < boxes.size(); ++i)
      if (boxes[i].cost > boxes[top].cost) top = i;
    struct Move {
      double worst = INFINITY, face = INFINITY;
      std::size_t partner = 0;
      RBox first, second;
    } best;
    for (std::size_t j = 0; j < boxes.size(); ++j) {
      if (j == top || full_face_axis(f, boxes[top], boxes[j]) < 0) continue;
      RBox u;
      for (int d = 0; d < 3; ++d) {
        u.lo[d] = std::min(boxes[top].lo[d], boxes[j].lo[d]);
        u.hi[d] = std::max(boxes[top].hi[d], boxes[j].hi[d]);
      }
      for (int axis = 0; axis < f.dim; ++axis)
        for (std::int64_t c = u.lo[axis] + 1; c < u.hi[axis]; ++c) {
          RBox a = u, b = u;
          a.hi[axis] = c;
          b.lo[axis] = c;
          weigh(f, a);
          weigh(f, b);
          const double worst = std::max(a.cost, b.cost);
          const double face = face_measure(f, a, b, axis);
          if (worst < best.worst || (worst == best.worst && face < best.face)) best = {worst, face, j, a, b};
        }
    }
    if (!(best.worst < boxes[top].cost * (1 - 1e-12))) break;
    boxes[top] = best.first;
    boxes[best.partner] = best.second;
    ++moves;
  }
  return moves;
}

// A cut whose worse side is within this fraction of the best cut's is as good: of those, the
// one with the smaller face wins. Exact balance can ask for slabs a few cubes thick across
// the domain, whose ghost costs more memory than the balance gains time (E4 at 16
// partitions: imbalance 1.009 → 1.020, ghost 0.53 → 0.40 of the domain, peak memory per
// rank 2.01 → 1.46 GiB, the time within noise).
constexpr double kBalanceTolerance = 0.005;

// Algorithm 1's finer over-decompositions stop below this many leaves per part
// (PartitionOptions::extra_depths): 2D keeps its two extra depths (4 times the leaves
// each), 3D one (8 times).
constexpr std::int64_t kMaxLeavesPerPart = 512;

// Load-weighted recursive bisection: k parts in `box`; each cut (any axis, on a lattice
// line) minimises max(load_left / k_left, load_right / k_right), to kBalanceTolerance;
// among those, the smaller face.
void bisect(const LoadField& f, const RBox& box, int k, std::vector<RBox>& out) {
  if (k == 1) {
    out.push_back(box);
    return;
  }
  const int k1 = k / 2, k2 = k - k1;
  double best = INFINITY, best_face = INFINITY;
  RBox best_a, best_b;
  struct Cut {
    double worst, face;
    RBox a, b;
  };
  std::vector<Cut> cuts;
  for (int axis = 0; axis < f.dim; ++axis) {
    std::int64_t cross = 1;  // raster cells in a slab of thickness 1
    for (int d = 0; d < f.dim; ++d)
      if (d != axis) cross *= box.hi[d] - box.lo[d];
    for (std::int64_t c = box.lo[axis] + 1; c < box.hi[axis]; ++c) {
      if ((c - box.lo[axis]) * cross < k1 || (box.hi[axis] - c) * cross < k2) continue;
      RBox a = box, b = box;
      a.hi[axis] = c;
      b.lo[axis] = c;
      weigh(f, a);
      weigh(f, b);
      // A half's cost counts its own ghost beyond the box being cut, not yet the ghosts
      // between its own parts, which both halves will have alike.
      const double worst = std::max(a.cost / k1, b.cost / k2);
      const double face = face_measure(f, a, b, axis);
      cuts.push_back({worst, face, a, b});
      best = std::min(best, worst);
    }
  }
  for (const Cut& cut : cuts)
    if (cut.worst <= best * (1 + kBalanceTolerance) && cut.face < best_face) {
      best_face = cut.face;
      best_a = cut.a;
      best_b = cut.b;
    }
  if (!std::isfinite(best)) {  // too thin to cut: cannot happen when the box has ≥ k cells
    out.push_back(box);
    return;
  }
  CISAMR_CHECK(std::isfinite(best_face), "partition: no bisection cut chosen");
  bisect(f, best_a, k1, out);
  bisect(f, best_b, k2, out);
}

LoadField checked_field(const geometry::SceneDesc& scene, int n, const PartitionOptions& options,
                        std::span<const InclusionLoad> given = {}) {
  if (n < 1) throw InputError(scene.source, "n", "the number of partitions must be at least 1");
  if (scene.dimension != 2 && scene.dimension != 3)
    throw InputError(scene.source, "dimension", "must be 2 or 3");
  // The sequential mesher's checks (its oracle's), so that partitioning and the
  // distributed mesher refuse the same scenes with the same message.
  if (scene.dimension == 2)
    geometry::validate_inclusions<2>(scene);
  else
    geometry::validate_inclusions<3>(scene);
  LoadField f = build_load_field(scene, options, given);
  if (f.n[0] * f.n[1] * f.n[2] < n)
    throw InputError(scene.source, "n", "more partitions (" + std::to_string(n) + ") than lattice cells");
  return f;
}

// Boxes → Partition: ids ordered by (z, y, x) of the min corner, neighbours, inclusions.
Partition assemble(const LoadField& f, const geometry::SceneDesc& scene, std::vector<RBox> boxes, std::string method,
                   std::span<const InclusionLoad> given = {}) {
  // The boxes must tile the raster: none empty, their cells adding up to all of it (they
  // do not overlap by construction), or a partition's cells would be meshed by nobody.
  std::int64_t cells = 0;
  for (const RBox& b : boxes) {
    std::int64_t c = 1;
    for (int d = 0; d < f.dim; ++d) c *= b.hi[d] - b.lo[d];
    CISAMR_CHECK(c > 0, "partition: an empty box");
    cells += c;
  }
  CISAMR_CHECK(cells == f.n[0] * f.n[1] * f.n[2], "partition: the boxes do not tile the domain");
  std::sort(boxes.begin(), boxes.end(), [](const RBox& a, const RBox& b) {
    return std::tie(a.lo[2], a.lo[1], a.lo[0]) < std::tie(b.lo[2], b.lo[1], b.lo[0]);
  });
  Partition p;
  p.method = std::move(method);
  p.dimension = f.dim;
  p.domain = f.domain;
  if (f.dim == 2) p.domain.min[2] = p.domain.max[2] = 0;
  p.h = f.h;
  p.cells = f.lattice_cells;
  if (f.dim == 2) p.cells[2] = 1;
  p.periodic = f.periodic;
  p.load_exponent = f.exponent;
  p.total_load = f.total();
  p.ghost_weight = f.ghost_weight;
  p.ghost_cells = f.ghost_cells;
  for (std::size_t i = 0; i < boxes.size(); ++i) {
    Part part;
    part.id = part.rank = static_cast<int>(i);
    for (int d = 0; d < 3; ++d) {
      if (d < f.dim) {
        part.lattice_min[d] = f.lattice_index(d, boxes[i].lo[d]);
        part.lattice_max[d] = f.lattice_index(d, boxes[i].hi[d]);
        part.box.min[d] = f.domain.min[d] + part.lattice_min[d] * f.h;
        part.box.max[d] = f.domain.min[d] + part.lattice_max[d] * f.h;
      } else {
        part.lattice_min[d] = 0;
        part.lattice_max[d] = 1;
      }
    }
    part.load = boxes[i].load;
    part.cost = boxes[i].cost;
    p.parts.push_back(part);
  }
  // Neighbours: faces of positive measure, plus periodic ones across the domain.
  for (auto& a : p.parts)
    for (const auto& b : p.parts) {
      for (int axis = 0; axis < f.dim; ++axis)
        for (int side : {-1, +1})
          for (int wrap = 0; wrap < (f.periodic[static_cast<std::size_t>(axis)] ? 2 : 1); ++wrap) {
            const std::int64_t mine = side > 0 ? a.lattice_max[axis] : a.lattice_min[axis];
            std::int64_t theirs = side > 0 ? b.lattice_min[axis] : b.lattice_max[axis];
            std::int64_t shift_cells = 0;
            if (wrap) {  // the neighbour's image across the periodic face
              if (side > 0 && mine == f.lattice_cells[axis] && theirs == 0) shift_cells = f.lattice_cells[axis];
              else if (side < 0 && mine == 0 && theirs == f.lattice_cells[axis]) shift_cells = -f.lattice_cells[axis];
              else continue;
              theirs += shift_cells;
            } else if (a.id == b.id) {
              continue;
            }
            if (mine != theirs) continue;
            SharedFace face;
            face.part = b.id;
            face.axis = axis;
            face.side = side;
            face.periodic = wrap != 0;
            face.shift[axis] = shift_cells * f.h;
            bool positive = true;
            for (int d = 0; d < 3; ++d) {
              if (d == axis) {
                face.face.min[d] = face.face.max[d] = f.domain.min[d] + mine * f.h;
              } else if (d < f.dim) {
                const std::int64_t lo = std::max(a.lattice_min[d], b.lattice_min[d]);
                const std::int64_t hi = std::min(a.lattice_max[d], b.lattice_max[d]);
                if (hi <= lo) positive = false;
                face.face.min[d] = f.domain.min[d] + lo * f.h;
                face.face.max[d] = f.domain.min[d] + hi * f.h;
              }
            }
            if (positive) a.neighbours.push_back(face);
          }
    }
  for (auto& a : p.parts)
    std::sort(a.neighbours.begin(), a.neighbours.end(), [](const SharedFace& x, const SharedFace& y) {
      return std::tie(x.part, x.axis, x.side, x.periodic) < std::tie(y.part, y.axis, y.side, y.periodic);
    });
  // Inclusions whose bounding box (or a periodic image of it) meets the closed part box.
  for (std::size_t k = 0; k < scene.inclusions.size(); ++k) {
    const auto* stl = std::get_if<geometry::StlSurface>(&scene.inclusions[k].shape);
    const Box3 b = stl != nullptr && stl->triangles.empty() && k < given.size() ? given[k].box
                                                                                  : inclusion_box(scene.inclusions[k].shape);
    for (auto& part : p.parts) {
      bool hit = false;
      for (int sx = -1; sx <= 1 && !hit; ++sx)
        for (int sy = -1; sy <= 1 && !hit; ++sy)
          for (int sz = -1; sz <= 1 && !hit; ++sz) {
            const int s[3] = {sx, sy, f.dim == 3 ? sz : 0};
            if (f.dim == 2 && sz != 0) continue;
            if ((sx && !f.periodic[0]) || (sy && !f.periodic[1]) || (sz && !f.periodic[2])) continue;
            bool meets = true;
            for (int d = 0; d < f.dim; ++d) {
              const double L = f.domain.max[d] - f.domain.min[d];
              if (b.max[d] + s[d] * L < part.box.min[d] || b.min[d] + s[d] * L > part.box.max[d]) meets = false;
            }
            hit = meets;
          }
      if (hit) part.inclusions.push_back(static_cast<std::int32_t>(k));
    }
  }
  return p;
}

std::vector<RBox> uniform_boxes(const LoadField& f, int n) {
  // The factorisation of n with the smallest total internal face measure.
  std::array<std::int64_t, 3> best{1, 1, 1};
  double best_faces = INFINITY;
  const double L[3] = {f.domain.max[0] - f.domain.min[0], f.domain.max[1] - f.domain.min[1],
                       f.dim == 3 ? f.domain.max[2] - f.domain.min[2] : 1.0};
  for (std::int64_t gx = 1; gx <= n; ++gx) {
    if (n % gx) continue;
    for (std::int64_t gy = 1; gy <= n / gx; ++gy) {
      if ((n / gx) % gy) continue;
      const std::int64_t gz = n / gx / gy;
      if (f.dim == 2 && gz != 1) continue;
      const std::array<std::int64_t, 3> g{gx, gy, gz};
      bool fits = true;
      for (int d = 0; d < 3; ++d)
        if (g[d] > f.n[d]) fits = false;
      if (!fits) continue;
      const double faces = f.dim == 2 ? (gx - 1) * L[1] + (gy - 1) * L[0]
                                      : (gx - 1) * L[1] * L[2] + (gy - 1) * L[0] * L[2] + (gz - 1) * L[0] * L[1];
      if (faces < best_faces) { best_faces = faces; best = g; }
    }
  }
  if (!std::isfinite(best_faces)) throw InputError("", "n", "no uniform grid of " + std::to_string(n) + " boxes fits the lattice");
  std::array<std::vector<std::int64_t>, 3> cut;
  for (int d = 0; d < 3; ++d) cut[d] = splits(f.n[d], best[d]);
  std::vector<RBox> boxes;
  for (std::int64_t k = 0; k < best[2]; ++k)
    for (std::int64_t j = 0; j < best[1]; ++j)
      for (std::int64_t i = 0; i < best[0]; ++i) {
        RBox b{{cut[0][i], cut[1][j], cut[2][k]}, {cut[0][i + 1], cut[1][j + 1], cut[2][k + 1]}, 0};
        weigh(f, b);
        boxes.push_back(b);
      }
  return boxes;
}

}  // namespace

double Partition::max_load() const {
  double m = 0;
  for (const auto& p : parts) m = std::max(m, p.load);
  return m;
}

double Partition::mean_load() const { return parts.empty() ? 0 : total_load / parts.size(); }

double Partition::max_cost() const {
  double m = 0;
  for (const auto& p : parts) m = std::max(m, p.cost);
  return m;
}

double Partition::mean_cost() const {
  double s = 0;
  for (const auto& p : parts) s += p.cost;
  return parts.empty() ? 0 : s / static_cast<double>(parts.size());
}

double Partition::shared_face_measure() const {
  double s = 0;
  for (const auto& p : parts)
    for (const auto& nb : p.neighbours) {
      if (nb.periodic || nb.part < p.id) continue;
      double m = 1;
      for (int d = 0; d < dimension; ++d)
        if (d != nb.axis) m *= nb.face.max[d] - nb.face.min[d];
      s += m;
    }
  return s;
}

double total_load(const geometry::SceneDesc& scene, const PartitionOptions& options) {
  return build_load_field(scene, options).total();
}

Partition partition_domain(const geometry::SceneDesc& scene, int n, const PartitionOptions& options) {
  return partition_domain(scene, n, options, {});
}

Partition partition_domain(const geometry::SceneDesc& scene, int n, const PartitionOptions& options,
                           std::span<const InclusionLoad> given) {
  const LoadField f = checked_field(scene, n, options, given);
  auto leaves_at = [&](int depth) {
    Index3 l{1, 1, 1};
    for (int d = 0; d < f.dim; ++d) l[d] = std::min<std::int64_t>(std::int64_t{1} << depth, f.n[d]);
    return l;
  };
  auto count = [](const Index3& l) { return l[0] * l[1] * l[2]; };
  int depth0 = 0;
  while (count(leaves_at(depth0)) < std::int64_t{options.oversubscription} * n &&
         count(leaves_at(depth0 + 1)) > count(leaves_at(depth0)))
    ++depth0;
  struct Candidate {
    std::vector<RBox> boxes;
    double worst, faces;
    Index3 leaves;
    int merges, moves;
  };
  std::optional<Candidate> best;
  auto consider = [&](std::vector<RBox> boxes, const Index3& leaves, int merges) {
    const int moves = options.rebalance ? rebalance(f, boxes) : 0;
    Candidate c{std::move(boxes), 0, 0, leaves, merges, moves};
    c.worst = max_cost(c.boxes);
    c.faces = internal_faces(f, c.boxes);
    if (!best || c.worst < best->worst * (1 - 1e-12) ||
        (c.worst <= best->worst * (1 + 1e-12) && c.faces < best->faces))
      best = std::move(c);
  };
  using Method = PartitionOptions::Method;
  if (options.method != Method::merge) {
    std::vector<RBox> boxes;
    RBox all{{0, 0, 0}, f.n};
    weigh(f, all);
    bisect(f, all, n, boxes);
    if (static_cast<int>(boxes.size()) == n) consider(std::move(boxes), {0, 0, 0}, 0);
  }
  std::optional<Candidate> bisection = std::move(best);
  best.reset();
  Index3 previous{0, 0, 0};
  for (int depth = depth0; options.method != Method::bisection && depth <= depth0 + options.extra_depths; ++depth) {
    const Index3 leaves = leaves_at(depth);
    if (leaves == previous || count(leaves) < n) break;
    // Finer over-decompositions only below kMaxLeavesPerPart leaves per part: in 3D each
    // depth has 8 times the leaves, and the second extra one (2,048 to 4,096 per part) took
    // two thirds of the partitioning's time at 16 partitions and more without ever winning.
    if (depth > depth0 && count(leaves) >= kMaxLeavesPerPart * n) break;
    previous = leaves;
    int merges = 0;
    if (auto boxes = merge_from_leaves(f, leaves, n, &merges)) consider(std::move(*boxes), leaves, merges);
  }
  // Stuck everywhere (no face-sharing pair left above n boxes): coarser starts, then the
  // uniform grid (always a valid tiling) as the starting point of the face sliding.
  for (int depth = depth0 - 1; options.method != Method::bisection && !best && depth >= 0; --depth) {
    const Index3 leaves = leaves_at(depth);
    if (count(leaves) < n) break;
    int merges = 0;
    if (auto boxes = merge_from_leaves(f, leaves, n, &merges)) consider(std::move(*boxes), leaves, merges);
  }
  if (!best && options.method == Method::merge) consider(uniform_boxes(f, n), {0, 0, 0}, 0);
  std::string method = "algorithm1";
  if (bisection && (!best || bisection->worst < best->worst * (1 - 1e-12) ||
                    (bisection->worst <= best->worst * (1 + 1e-12) && bisection->faces < best->faces))) {
    best = std::move(bisection);
    method = "bisection";
  }
  if (!best) consider(uniform_boxes(f, n), {0, 0, 0}, 0);
  Partition p = assemble(f, scene, std::move(best->boxes), method, given);
  p.leaves = {static_cast<int>(best->leaves[0]), static_cast<int>(best->leaves[1]), static_cast<int>(best->leaves[2])};
  p.merges = best->merges;
  p.rebalance_moves = best->moves;
  return p;
}

Partition uniform_grid_partition(const geometry::SceneDesc& scene, int n, const PartitionOptions& options) {
  const LoadField f = checked_field(scene, n, options);
  return assemble(f, scene, uniform_boxes(f, n), "uniform-grid");
}

}  // namespace cisamr::partition
