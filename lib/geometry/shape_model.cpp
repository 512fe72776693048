// The parts of the shape interface shared by several families (contract in
// shape_model.hpp and README.md).
#include "geometry/shape_model.hpp"

#include <algorithm>

#include "geometry/shapes.hpp"

namespace cisamr::geometry {

void CurveModel::boundary_meetings(const ShapeModel<2>& other, const Vec2& /*p*/, std::vector<Vec2>& out) const {
  const int samples = meeting_samples();
  for (int piece = 0; piece < piece_count(); ++piece) {
    Vec2 prev = curve_point(piece, 0);
    int prev_side = other.classify(prev);
    if (prev_side == 0) out.push_back(prev);
    for (int i = 1; i <= samples; ++i) {
      double s1 = double(i) / samples;
      const Vec2 cur = curve_point(piece, s1);
      const int cur_side = other.classify(cur);
      if (cur_side == 0) out.push_back(cur);
      else if (prev_side != 0 && cur_side != prev_side) {
        double s0 = double(i - 1) / samples;
        Vec2 mid = cur;
        for (int iter = 0; iter < 64; ++iter) {
          const double sm = 0.5 * (s0 + s1);
          if (sm <= s0 || sm >= s1) break;
          mid = curve_point(piece, sm);
          const int ms = other.classify(mid);
          if (ms == 0) break;
          if (ms == prev_side) s0 = sm;
          else s1 = sm;
        }
        out.push_back(mid);
      }
      prev = cur;
      prev_side = cur_side;
    }
  }
}

void CurveModel::sampled_nearest_points(const Vec2& p, int samples, std::vector<Vec2>& out) const {
  std::vector<double> d2(samples + 1);
  auto dist2 = [&](int piece, double s) {
    const Vec2 q = curve_point(piece, s);
    return (q[0] - p[0]) * (q[0] - p[0]) + (q[1] - p[1]) * (q[1] - p[1]);
  };
  for (int piece = 0; piece < piece_count(); ++piece) {
    for (int i = 0; i <= samples; ++i) d2[i] = dist2(piece, double(i) / samples);
    for (int i = 0; i <= samples; ++i) {
      if ((i > 0 && d2[i] > d2[i - 1]) || (i < samples && d2[i] > d2[i + 1])) continue;
      double lo = double(std::max(i - 1, 0)) / samples, hi = double(std::min(i + 1, samples)) / samples;
      constexpr double g = 0.6180339887498949;
      double x1 = hi - g * (hi - lo), x2 = lo + g * (hi - lo);
      double f1 = dist2(piece, x1), f2 = dist2(piece, x2);
      for (int iter = 0; iter < 80 && hi - lo > 1e-17; ++iter) {
        if (f1 <= f2) {
          hi = x2, x2 = x1, f2 = f1, x1 = hi - g * (hi - lo), f1 = dist2(piece, x1);
        } else {
          lo = x1, x1 = x2, f1 = f2, x2 = lo + g * (hi - lo), f2 = dist2(piece, x2);
        }
      }
      out.push_back(curve_point(piece, f1 <= f2 ? x1 : x2));
      out.push_back(curve_point(piece, double(i) / samples));
    }
  }
}

std::vector<Vec3> SurfaceModel::boundary_points(int per_axis) const {
  return shape_boundary_samples(descriptor(), box_diagonal(box()) / per_axis);
}

bool finite(const Vec2& v) { return std::isfinite(v[0]) && std::isfinite(v[1]); }
bool finite(const Vec3& v) { return std::isfinite(v[0]) && std::isfinite(v[1]) && std::isfinite(v[2]); }

bool orthonormal(const Rotation3& r) {
  for (int i = 0; i < 3; ++i)
    for (int j = 0; j < 3; ++j) {
      double s = 0;
      for (int k = 0; k < 3; ++k) s += r[k][i] * r[k][j];
      if (!std::isfinite(s) || std::abs(s - (i == j ? 1.0 : 0.0)) > 1e-9) return false;
    }
  return true;
}

void quadric_y_extent(const double (&M)[3][3], const Vec3& c, double rhs, double x, std::vector<double>& out) {
  const double dx = x - c[0];
  double A, B, C;
  if (M[2][2] > 1e-12) {
    A = M[1][1] - M[1][2] * M[1][2] / M[2][2];
    B = M[0][1] * dx - M[0][2] * M[1][2] * dx / M[2][2];
    C = M[0][0] * dx * dx - M[0][2] * M[0][2] * dx * dx / M[2][2];
  } else {
    A = M[1][1], B = M[0][1] * dx, C = M[0][0] * dx * dx;
  }
  const double disc = B * B - A * (C - rhs);
  if (A > 1e-12 && disc > 0) {
    out.push_back(c[1] + (-B - std::sqrt(disc)) / A);
    out.push_back(c[1] + (-B + std::sqrt(disc)) / A);
  }
}

}  // namespace cisamr::geometry
