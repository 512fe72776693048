#pragma once
// Search structures over axis-aligned boxes (private to lib/geometry; CGAL behind).
#include <cstdint>
#include <memory>
#include <utility>
#include <vector>

#include "core/types.hpp"

namespace cisamr::geometry {

// CGAL AABB tree over 2D boxes (embedded at z ∈ [-1,1] in CGAL's 3D tree).
class BoxIndex2 {
 public:
  explicit BoxIndex2(const std::vector<Box2>& boxes);
  ~BoxIndex2();
  BoxIndex2(BoxIndex2&&) noexcept;
  BoxIndex2& operator=(BoxIndex2&&) noexcept;
  // Indices of the boxes that meet the closed query box, ascending.
  void query(const Box2& box, std::vector<std::int32_t>& out) const;

 private:
  struct Tree;
  std::unique_ptr<Tree> tree_;
};

// Every pair (i < j) of boxes that meet (closed), sorted; CGAL Box_intersection_d.
std::vector<std::pair<std::int32_t, std::int32_t>> overlapping_box_pairs(
    const std::vector<Box2>& boxes);

// CGAL AABB tree over 3D boxes.
class BoxIndex3 {
 public:
  explicit BoxIndex3(const std::vector<Box3>& boxes);
  ~BoxIndex3();
  BoxIndex3(BoxIndex3&&) noexcept;
  BoxIndex3& operator=(BoxIndex3&&) noexcept;
  // Indices of the boxes that meet the closed query box, ascending.
  void query(const Box3& box, std::vector<std::int32_t>& out) const;

 private:
  struct Tree;
  std::unique_ptr<Tree> tree_;
};

// Every pair (i < j) of 3D boxes that meet (closed), sorted; CGAL Box_intersection_d.
std::vector<std::pair<std::int32_t, std::int32_t>> overlapping_box_pairs(
    const std::vector<Box3>& boxes);

}  // namespace cisamr::geometry
