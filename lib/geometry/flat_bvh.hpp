#pragma once
// A flat bounding-volume hierarchy over indexed boxes (private to lib/geometry): median
// split on the longest extent of the box centres, leaves of at most 4 items, ties broken
// by item index, so the tree depends only on the boxes (not on the library's sort);
// traversal with a fixed-size stack and no allocation. Used for the faces of STL meshes
// (stl_mesh.cpp) and the shells of NURBS surface bodies.
#include <algorithm>
#include <cstdint>
#include <numeric>
#include <span>
#include <vector>

#include "core/types.hpp"

namespace cisamr::geometry {

template <int Dim>
class FlatBvh {
 public:
  struct Node {
    Box<Dim> box;
    std::int32_t first = 0, count = 0;  // leaf: items order[first, first+count)
    std::int32_t left = -1, right = -1; // inner node: children
  };

  // Builds over items 0 … boxes.size() − 1 (boxes[i] is item i's box).
  void build(std::span<const Box<Dim>> boxes) {
    const auto n = static_cast<std::int32_t>(boxes.size());
    nodes_.clear();
    order_.resize(boxes.size());
    std::iota(order_.begin(), order_.end(), 0);
    if (n == 0) return;
    nodes_.reserve(2 * boxes.size() / kLeafSize + 2);
    build_node(boxes, 0, n);
  }

  bool empty() const { return nodes_.empty(); }
  const Box<Dim>& box() const { return nodes_[0].box; }  // of all items; not empty()

  // Visits the nodes whose box passes `enter` and calls `visit(item)` on the items of
  // the leaves among them, in a fixed order; stops when `visit` returns true.
  template <class Enter, class Visit>
  void traverse(Enter&& enter, Visit&& visit) const {
    if (nodes_.empty()) return;
    std::int32_t stack[kMaxStack];
    int top = 0;
    stack[top++] = 0;
    while (top > 0) {
      const Node& n = nodes_[stack[--top]];
      if (!enter(n.box)) continue;
      if (n.count > 0) {
        for (std::int32_t i = n.first; i < n.first + n.count; ++i)
          if (visit(order_[i])) return;
      } else {
        stack[top++] = n.right;
        stack[top++] = n.left;
      }
    }
  }

 private:
  static constexpr int kLeafSize = 4;
  static constexpr int kMaxStack = 128;  // depth ≈ log2(items / 4) + 1

  std::int32_t build_node(std::span<const Box<Dim>> boxes, std::int32_t first, std::int32_t count) {
    const auto id = static_cast<std::int32_t>(nodes_.size());
    nodes_.push_back({});
    Box<Dim> b = boxes[order_[first]];
    Box<Dim> cb{};  // box of the centres
    for (int k = 0; k < Dim; ++k) cb.min[k] = cb.max[k] = 0.5 * (b.min[k] + b.max[k]);
    for (std::int32_t i = first; i < first + count; ++i) {
      const Box<Dim>& fb = boxes[order_[i]];
      for (int k = 0; k < Dim; ++k) {
        b.min[k] = std::min(b.min[k], fb.min[k]);
        b.max[k] = std::max(b.max[k], fb.max[k]);
        const double c = 0.5 * (fb.min[k] + fb.max[k]);
        cb.min[k] = std::min(cb.min[k], c);
        cb.max[k] = std::max(cb.max[k], c);
      }
    }
    nodes_[id].box = b;
    if (count <= kLeafSize) {
      nodes_[id].first = first;
      nodes_[id].count = count;
      return id;
    }
    int axis = 0;
    for (int k = 1; k < Dim; ++k)
      if (cb.max[k] - cb.min[k] > cb.max[axis] - cb.min[axis]) axis = k;
    const std::int32_t half = count / 2;
    std::nth_element(order_.begin() + first, order_.begin() + first + half, order_.begin() + first + count,
                     [&](std::int32_t x, std::int32_t y) {
                       const double cx = boxes[x].min[axis] + boxes[x].max[axis];
                       const double cy = boxes[y].min[axis] + boxes[y].max[axis];
                       return cx != cy ? cx < cy : x < y;
                     });
    const std::int32_t l = build_node(boxes, first, half);
    const std::int32_t r = build_node(boxes, first + half, count - half);
    nodes_[id].left = l;
    nodes_[id].right = r;
    return id;
  }

  std::vector<Node> nodes_;           // nodes_[0] is the root
  std::vector<std::int32_t> order_;   // item ids in leaf order
};

}  // namespace cisamr::geometry
