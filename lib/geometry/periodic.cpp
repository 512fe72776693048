#include "geometry/periodic.hpp"

#include <cmath>
#include <string>

#include "core/error.hpp"

#include "geometry/shapes.hpp"

namespace cisamr::geometry {
namespace {

// Images of one inclusion per periodic axis at most (a shift range of that many periods).
constexpr std::int64_t kMaxImagesPerAxis = 8;

// An inclusion's box: from its shape, or `known` for an STL surface this rank has not read.
Box3 box_of(const SceneDesc& scene, std::size_t k, std::span<const Box3> known) {
  const Shape& shape = scene.inclusions[k].shape;
  const auto* stl = std::get_if<StlSurface>(&shape);
  if (stl != nullptr && stl->triangles.empty() && k < known.size()) return known[k];
  return shape_bounding_box(shape);
}

}  // namespace

Vec3 periods(const SceneDesc& scene) {
  Vec3 t{0, 0, 0};
  for (int d = 0; d < scene.dimension; ++d) {
    const auto a = static_cast<std::size_t>(d);
    // The lattice's period: N·h, the same number the mesher adds to a node on the min face.
    if (scene.periodic[a]) t[d] = static_cast<double>(std::llround((scene.domain_max[a] - scene.domain_min[a]) / scene.h)) * scene.h;
  }
  return t;
}

SceneDesc expand_periodic(const SceneDesc& scene, double reach, std::span<const Box3> known) {
  SceneDesc out = scene;
  if (!scene.any_periodic()) return out;
  out.images_expanded = true;
  const Vec3 period = periods(scene);
  const std::size_t listed = scene.inclusions.size();
  out.image_base.assign(listed, -1);
  out.image_shift.assign(listed, {0, 0, 0});
  for (std::size_t k = 0; k < listed; ++k) {
    const Box3 box = box_of(scene, k, known);
    // Per axis, the shifts s with box + s·T meeting [min − reach, max + reach].
    std::array<std::int64_t, 3> lo{0, 0, 0}, hi{0, 0, 0};
    for (int d = 0; d < scene.dimension; ++d) {
      const auto a = static_cast<std::size_t>(d);
      if (!scene.periodic[a]) continue;
      lo[a] = static_cast<std::int64_t>(std::ceil((scene.domain_min[a] - reach - box.max[d]) / period[d]));
      hi[a] = static_cast<std::int64_t>(std::floor((scene.domain_max[a] + reach - box.min[d]) / period[d]));
      // Wider than a few periods, an inclusion would cover the whole cell with its own
      // images many times over: refuse it rather than expand an unbounded number.
      if (hi[a] - lo[a] > kMaxImagesPerAxis)
        throw InputError(scene.source, inclusion_field(scene, k),
                         std::string("spans more than ") + std::to_string(kMaxImagesPerAxis - 2) +
                             " periods of the periodic domain along " + "xyz"[d]);
    }
    for (std::int64_t sz = lo[2]; sz <= hi[2]; ++sz)
      for (std::int64_t sy = lo[1]; sy <= hi[1]; ++sy)
        for (std::int64_t sx = lo[0]; sx <= hi[0]; ++sx) {
          if (sx == 0 && sy == 0 && sz == 0) continue;
          const std::array<std::int64_t, 3> s{sx, sy, sz};
          Vec3 offset{0, 0, 0};
          for (int d = 0; d < 3; ++d) offset[d] = static_cast<double>(s[static_cast<std::size_t>(d)]) * period[d];
          Inclusion image = scene.inclusions[k];
          image.shape = translated(image.shape, offset);
          out.inclusions.push_back(std::move(image));
          out.image_base.push_back(static_cast<std::int32_t>(k));
          out.image_shift.push_back({static_cast<std::int8_t>(sx), static_cast<std::int8_t>(sy), static_cast<std::int8_t>(sz)});
        }
  }
  return out;
}

std::vector<Box3> expanded_boxes(const SceneDesc& expanded, std::span<const Box3> known) {
  const Vec3 period = periods(expanded);
  std::vector<Box3> boxes(expanded.inclusions.size());
  for (std::size_t k = 0; k < boxes.size(); ++k) {
    const std::size_t base = expanded.listed(k);
    Box3 b = box_of(expanded, base, known);
    if (base != k)
      for (int d = 0; d < 3; ++d) {
        const double offset = expanded.image_shift[k][static_cast<std::size_t>(d)] * period[d];
        b.min[d] += offset, b.max[d] += offset;
      }
    boxes[k] = b;
  }
  return boxes;
}

std::int64_t images_in_domain(const SceneDesc& expanded, std::span<const Box3> known) {
  const std::vector<Box3> boxes = expanded_boxes(expanded, known);
  std::int64_t count = 0;
  for (std::size_t k = 0; k < boxes.size(); ++k) {
    if (expanded.listed(k) == k) continue;
    bool enters = true;
    for (int d = 0; d < expanded.dimension; ++d)
      enters = enters && boxes[k].min[d] < expanded.domain_max[static_cast<std::size_t>(d)] &&
               boxes[k].max[d] > expanded.domain_min[static_cast<std::size_t>(d)];
    count += enters;
  }
  return count;
}

}  // namespace cisamr::geometry
