#pragma once
// Where a segment meets a circle (2D) or a sphere (3D): the exact part shared by
// predicates2.cpp and predicates3.cpp (private to them: it includes CGAL).
#include <CGAL/Interval_nt.h>
#include <CGAL/Mpzf.h>

#include "core/types.hpp"

namespace cisamr::geometry::exact::detail {

// The five terms of circle_hits_from_signs for the segment a→b and the ball (c, r), in NT:
// F(a), F(b), (a−c)·d, (b−c)·d and the discriminant, F(x) = r² − |x − c|², d = b − a.
template <int Dim, class NT>
void ball_segment_terms(const Vec<Dim>& a, const Vec<Dim>& b, const Vec<Dim>& c, double r, NT (&out)[5]) {
  NT f0 = NT(r) * NT(r), f1 = f0, ed = NT(0), fd = NT(0), dd = NT(0);
  for (int k = 0; k < Dim; ++k) {
    NT e = NT(a[k]) - NT(c[k]), f = NT(b[k]) - NT(c[k]), d = NT(b[k]) - NT(a[k]);
    f0 = f0 - e * e;
    f1 = f1 - f * f;
    ed = ed + e * d;
    fd = fd + f * d;
    dd = dd + d * d;
  }
  out[0] = f0;
  out[1] = f1;
  out[2] = ed;
  out[3] = fd;
  out[4] = ed * ed + dd * f0;
}

// Their exact signs: interval arithmetic first, Mpzf only when an interval holds zero.
template <int Dim>
void ball_segment_signs(const Vec<Dim>& a, const Vec<Dim>& b, const Vec<Dim>& c, double r, int (&s)[5]) {
  bool exact_needed = false;
  {
    CGAL::Protect_FPU_rounding<true> guard;
    CGAL::Interval_nt<false> iv[5];
    ball_segment_terms<Dim>(a, b, c, r, iv);
    for (int i = 0; i < 5; ++i) {
      if (iv[i].inf() > 0) s[i] = 1;
      else if (iv[i].sup() < 0) s[i] = -1;
      else if (iv[i].inf() == 0 && iv[i].sup() == 0) s[i] = 0;
      else exact_needed = true;
    }
  }
  if (exact_needed) {
    CGAL::Mpzf ev[5];
    ball_segment_terms<Dim>(a, b, c, r, ev);
    for (int i = 0; i < 5; ++i) s[i] = static_cast<int>(ev[i].sign());
  }
}

}  // namespace cisamr::geometry::exact::detail
