#pragma once
// Periodic images of inclusions (docs/periodic-design.md §1). A periodic scene lists each
// inclusion once; the mesher meshes the torus, whose cells near a face see the geometry
// that wraps in from the opposite face. Those copies are ordinary inclusions of an
// expanded scene: the listed ones first (same indices), then every image whose box comes
// within `reach` of the domain, in (listed index, shift) order, so every rank builds the
// same scene.
#include <span>

#include "core/types.hpp"
#include "geometry/scene.hpp"

namespace cisamr::geometry {

// How far beyond a periodic face the mesher needs the images of inclusions: the reach of
// the effective-level rules at the coarsest level and a margin. Every stage evaluates a
// cell in its canonical frame, inside the domain.
inline double periodic_reach(const SceneDesc& scene) { return 10 * scene.h; }

// The period of the domain along each axis (its extent; 0 on axes that are not periodic).
Vec3 periods(const SceneDesc& scene);

// The scene with the images of every inclusion whose box, shifted by a whole number of
// periods along the periodic axes, meets the domain grown by `reach` on those axes. Sets
// image_base, image_shift and images_expanded. An Oracle built from a periodic scene
// expands it itself; call this only to hold the expanded scene (the parallel mesher). `known`: boxes of inclusions whose shape cannot give one
// (an STL surface not loaded on this rank); empty: from the shapes. A scene with no
// periodic axis comes back unchanged (and with no image lists).
SceneDesc expand_periodic(const SceneDesc& scene, double reach, std::span<const Box3> known = {});

// The boxes of an expanded scene's inclusions from the listed ones' `known` boxes.
std::vector<Box3> expanded_boxes(const SceneDesc& expanded, std::span<const Box3> known);

// How many images of an expanded scene enter the domain (their box meets its interior): the
// copies a user sees wrap in, not those kept only for the reach beyond the faces.
std::int64_t images_in_domain(const SceneDesc& expanded, std::span<const Box3> known);

}  // namespace cisamr::geometry
