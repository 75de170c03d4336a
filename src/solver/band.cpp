#include "solver/band.hpp"

#include <algorithm>
#include <cmath>

namespace drape {

Band Band::tensile(const TensileKES& k, double compression) {
  Band b;
  b.tensile_ = true;
  b.kc_ = compression * k.fm / k.emt;
  b.emt_ = k.emt;
  if (!k.load.empty()) {
    b.kind_ = Kind::Table;
    b.load_ = k.load;
    b.unload_ = k.unload.empty() ? k.load : k.unload;
    return b;
  }
  b.kind_ = Kind::PowerLaw;
  b.fm_ = k.fm;
  // Area of Fm*(q/EMT)^n over [0, EMT] is Fm*EMT/(n+1): equate to WT and RT*WT.
  b.n_load_ = 2.0 / k.lt - 1.0;
  b.n_unload_ = 2.0 / (k.lt * k.rt) - 1.0;
  return b;
}

Band Band::linear(double slope, double half_width, const Curve& load, const Curve& unload) {
  Band b;
  if (!load.empty()) {
    b.kind_ = Kind::Table;
    b.load_ = load;
    b.unload_ = unload.empty() ? load : unload;
    return b;
  }
  b.kind_ = Kind::Linear;
  b.slope_ = slope;
  b.half_ = half_width;
  return b;
}

double interpolate(const Curve& c, double q, double* slope) {
  const auto& x = c.q;
  const auto& y = c.f;
  if (x.size() == 1) {
    *slope = 0;
    return y[0];
  }
  size_t k = std::upper_bound(x.begin(), x.end(), q) - x.begin();
  k = std::clamp<size_t>(k, 1, x.size() - 1);  // extrapolate with end segments
  const double s = (y[k] - y[k - 1]) / (x[k] - x[k - 1]);
  *slope = s;
  return y[k - 1] + s * (q - x[k - 1]);
}

BandValue Band::curve_at(double q) const {
  if (tensile_ && q <= 0) {
    // Quadratic onset over [-eps, 0], then the line: no kink at rest length,
    // where unloaded edges sit (the tension branch starts with slope 0 too).
    const double eps = kCompressionOnset * emt_;
    const double f = q < -eps ? kc_ * (q + 0.5 * eps) : -0.5 * kc_ * q * q / eps;
    const double s = q < -eps ? kc_ : -kc_ * q / eps;
    return {f, f, s, s};
  }
  switch (kind_) {
    case Kind::Linear:
      return {slope_ * q - half_, slope_ * q + half_, slope_, slope_};
    case Kind::Table: {
      double sl, su;
      const double fl = interpolate(load_, q, &sl);
      const double fu = interpolate(unload_, q, &su);
      // Branches may cross (a loop measured on both sides of zero): the band
      // is whatever lies between them.
      if (fl >= fu) return {fu, fl, su, sl};
      return {fl, fu, sl, su};
    }
    case Kind::PowerLaw: {
      if (q >= emt_) {
        const double s = n_load_ * fm_ / emt_;
        const double f = fm_ + s * (q - emt_);
        return {f, f, s, s};
      }
      const double t = q / emt_;
      const double hi = fm_ * std::pow(t, n_load_);
      const double lo = fm_ * std::pow(t, n_unload_);
      return {lo, hi, n_unload_ * lo / q, n_load_ * hi / q};
    }
  }
  return {0, 0, 0, 0};
}

}  // namespace drape
