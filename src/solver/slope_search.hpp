#pragma once
// A line search on the slope of the step's energy along a Newton direction.
//
// With the element forces at their hysteresis targets, the Newton residual
// rho is the gradient of one step's energy (inertia, drag, gravity, contact
// and the bands' stop forces integrated over strain: the anchor is fixed for
// the step). Along z + a d its slope is g(a) = d . rho(z + a d): g(0) < 0, and
// the best step is where g crosses zero. The bands make g piecewise smooth:
// where an element reaches a band edge, or leaves it reversing, its stiffness
// jumps (inside the band it is `reversal` times the edge's), and Newton's
// tangent, taken on the element's branch at z, misjudges the step several
// times over. Halving from a = 1 spends evaluations on points no better than
// the last; the slopes already evaluated say where the crossing lies:
// regula falsi between the last point with g < 0 and the first with g > 0
// (Illinois: the end that stays has its slope halved, so that a kinked g,
// whose secant keeps falling short on one side, still closes in).
#include <algorithm>
#include <cmath>

namespace drape {

class SlopeSearch {
 public:
  static constexpr double kAccept = 0.25;  // accept |g(a)| <= kAccept |g(0)|
  static constexpr double kLongest = 4.0;  // the longest trial, a multiple of the Newton step
  static constexpr int kTrials = 8;        // then the caller backtracks as before

  explicit SlopeSearch(double g0) : g0_(g0), glo_(g0) {}

  // Whether the direction descends: else the search has nothing to follow.
  bool usable() const { return g0_ < 0 && std::isfinite(g0_); }
  // Whether a trial with slope g is flat enough to end the search.
  bool accepts(double g) const { return std::isfinite(g) && std::fabs(g) <= kAccept * std::fabs(g0_); }

  // The next trial after one at a with slope g (not accepted); 0 when the
  // search has run out (the longest step still descends: a is the best seen).
  double next(double a, double g) {
    if (std::isfinite(g) && g < 0) {
      alo_ = a;
      glo_ = g;
      if (side_ == -1) ghi_ *= 0.5;  // Illinois: the far end stayed twice
      side_ = -1;
      if (ahi_ < 0) return a < kLongest ? std::min(2 * a, kLongest) : 0.0;
    } else {  // past the crossing (or so far that the cost overflowed)
      ahi_ = a;
      ghi_ = std::isfinite(g) ? g : -glo_;
      if (side_ == 1) glo_ *= 0.5;
      side_ = 1;
    }
    return secant();
  }

 private:
  // The crossing of the chord between the bracket's ends, kept a tenth of
  // the bracket away from either.
  double secant() const {
    const double w = ahi_ - alo_;
    const double a = alo_ - glo_ * w / (ghi_ - glo_);
    return std::clamp(a, alo_ + 0.1 * w, ahi_ - 0.1 * w);
  }

  double g0_;
  double alo_ = 0, glo_;     // the furthest point still descending
  double ahi_ = -1, ghi_ = 0;  // the nearest point past the crossing (none yet: -1)
  int side_ = 0;             // which end the last trial replaced (-1 low, 1 high)
};

}  // namespace drape
