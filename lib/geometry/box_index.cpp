// CGAL's AABB tree and Box_intersection_d behind box_index.hpp.
#include "geometry/box_index.hpp"

#include <CGAL/AABB_traits.h>
#include <CGAL/AABB_tree.h>
#include <CGAL/Exact_predicates_inexact_constructions_kernel.h>
#include <CGAL/box_intersection_d.h>

#include <algorithm>
#include <iterator>
#include <vector>

namespace cisamr::geometry {
namespace {
using K = CGAL::Exact_predicates_inexact_constructions_kernel;

// A 2D box embedded at z ∈ [-1, 1]: CGAL's AABB tree is 3D.
struct BoxPrimitive {
  using Id = std::int32_t;
  using Point = K::Point_3;
  using Datum = K::Iso_cuboid_3;
  BoxPrimitive() = default;
  BoxPrimitive(Id id, const Box2& b)
      : id_(id), box_(K::Point_3(b.min[0], b.min[1], -1), K::Point_3(b.max[0], b.max[1], 1)) {}
  // CGAL builds primitives from the input iterator.
  explicit BoxPrimitive(std::vector<BoxPrimitive>::iterator it) : BoxPrimitive(*it) {}
  Id id() const { return id_; }
  const Datum& datum() const { return box_; }
  Point reference_point() const { return box_.min(); }
  Id id_ = -1;
  Datum box_;
};
using BoxTraits = CGAL::AABB_traits<K, BoxPrimitive>;
using BoxTree = CGAL::AABB_tree<BoxTraits>;

template <int Dim>
std::vector<std::pair<std::int32_t, std::int32_t>> box_pairs(const std::vector<Box<Dim>>& boxes) {
  using BoxD = CGAL::Box_intersection_d::Box_with_info_d<double, Dim, std::int32_t>;
  std::vector<BoxD> items;
  items.reserve(boxes.size());
  for (std::size_t k = 0; k < boxes.size(); ++k) {
    double lo[Dim], hi[Dim];
    for (int d = 0; d < Dim; ++d) lo[d] = boxes[k].min[d], hi[d] = boxes[k].max[d];
    items.emplace_back(lo, hi, static_cast<std::int32_t>(k));
  }
  std::vector<std::pair<std::int32_t, std::int32_t>> pairs;
  CGAL::box_self_intersection_d(
      items.begin(), items.end(),
      [&](const BoxD& x, const BoxD& y) {
        std::int32_t i = x.info(), j = y.info();
        if (i > j) std::swap(i, j);
        pairs.emplace_back(i, j);
      },
      std::ptrdiff_t(10), CGAL::Box_intersection_d::CLOSED);
  std::sort(pairs.begin(), pairs.end());
  pairs.erase(std::unique(pairs.begin(), pairs.end()), pairs.end());
  return pairs;
}
}  // namespace

struct BoxIndex2::Tree {
  BoxTree tree;
  bool empty = true;
};

BoxIndex2::BoxIndex2(const std::vector<Box2>& boxes) : tree_(std::make_unique<Tree>()) {
  std::vector<BoxPrimitive> prims;
  prims.reserve(boxes.size());
  for (std::size_t k = 0; k < boxes.size(); ++k)
    prims.emplace_back(static_cast<std::int32_t>(k), boxes[k]);
  if (!prims.empty()) {
    tree_->tree.insert(prims.begin(), prims.end());
    tree_->tree.build();
    tree_->empty = false;
  }
}
BoxIndex2::~BoxIndex2() = default;
BoxIndex2::BoxIndex2(BoxIndex2&&) noexcept = default;
BoxIndex2& BoxIndex2::operator=(BoxIndex2&&) noexcept = default;

void BoxIndex2::query(const Box2& box, std::vector<std::int32_t>& out) const {
  out.clear();
  if (tree_->empty) return;
  const K::Iso_cuboid_3 q(K::Point_3(box.min[0], box.min[1], 0),
                          K::Point_3(box.max[0], box.max[1], 0));
  tree_->tree.all_intersected_primitives(q, std::back_inserter(out));
  std::sort(out.begin(), out.end());
}

std::vector<std::pair<std::int32_t, std::int32_t>> overlapping_box_pairs(
    const std::vector<Box2>& boxes) {
  return box_pairs<2>(boxes);
}
std::vector<std::pair<std::int32_t, std::int32_t>> overlapping_box_pairs(
    const std::vector<Box3>& boxes) {
  return box_pairs<3>(boxes);
}

struct BoxIndex3::Tree {
  BoxTree tree;
  bool empty = true;
};

BoxIndex3::BoxIndex3(const std::vector<Box3>& boxes) : tree_(std::make_unique<Tree>()) {
  std::vector<BoxPrimitive> prims;
  prims.reserve(boxes.size());
  for (std::size_t k = 0; k < boxes.size(); ++k) {
    BoxPrimitive bp;
    bp.id_ = static_cast<std::int32_t>(k);
    const Box3& b = boxes[k];
    bp.box_ = K::Iso_cuboid_3(K::Point_3(b.min[0], b.min[1], b.min[2]), K::Point_3(b.max[0], b.max[1], b.max[2]));
    prims.push_back(bp);
  }
  if (!prims.empty()) {
    tree_->tree.insert(prims.begin(), prims.end());
    tree_->tree.build();
    tree_->empty = false;
  }
}
BoxIndex3::~BoxIndex3() = default;
BoxIndex3::BoxIndex3(BoxIndex3&&) noexcept = default;
BoxIndex3& BoxIndex3::operator=(BoxIndex3&&) noexcept = default;

void BoxIndex3::query(const Box3& box, std::vector<std::int32_t>& out) const {
  out.clear();
  if (tree_->empty) return;
  const K::Iso_cuboid_3 q(K::Point_3(box.min[0], box.min[1], box.min[2]),
                          K::Point_3(box.max[0], box.max[1], box.max[2]));
  tree_->tree.all_intersected_primitives(q, std::back_inserter(out));
  std::sort(out.begin(), out.end());
}

}  // namespace cisamr::geometry
