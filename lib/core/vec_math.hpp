#pragma once
// Small vector arithmetic on Vec2 / Vec3, written out component by component so that
// every caller evaluates the same floating-point operations in the same order (node
// positions and crossing parameters depend on it bit for bit). Plain overloads rather
// than templates: they win over std::norm and friends found by argument-dependent lookup.
#include <cmath>

#include "core/types.hpp"

namespace cisamr {

inline Vec2 add(const Vec2& a, const Vec2& b) { return {a[0] + b[0], a[1] + b[1]}; }
inline Vec3 add(const Vec3& a, const Vec3& b) { return {a[0] + b[0], a[1] + b[1], a[2] + b[2]}; }

inline Vec2 sub(const Vec2& a, const Vec2& b) { return {a[0] - b[0], a[1] - b[1]}; }
inline Vec3 sub(const Vec3& a, const Vec3& b) { return {a[0] - b[0], a[1] - b[1], a[2] - b[2]}; }

inline Vec2 scale(const Vec2& a, double s) { return {a[0] * s, a[1] * s}; }
inline Vec3 scale(const Vec3& a, double s) { return {a[0] * s, a[1] * s, a[2] * s}; }

inline double dot(const Vec2& a, const Vec2& b) { return a[0] * b[0] + a[1] * b[1]; }
inline double dot(const Vec3& a, const Vec3& b) { return a[0] * b[0] + a[1] * b[1] + a[2] * b[2]; }

// Euclidean length as sqrt(dot(a, a)) (not std::hypot: callers rely on this rounding).
inline double norm(const Vec2& a) { return std::sqrt(dot(a, a)); }
inline double norm(const Vec3& a) { return std::sqrt(dot(a, a)); }

inline Vec3 cross(const Vec3& a, const Vec3& b) {
  return {a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0]};
}

}  // namespace cisamr
