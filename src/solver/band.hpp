#pragma once
// A KES hysteresis band: the element force f (tension, moment, shear force)
// may lie anywhere between the lower curve lo(q) and the upper curve hi(q) of
// the generalized strain q at no cost; outside it the cost grows as the
// squared distance. Built from KES characteristic values or measured curves.
#include "solver/fabric.hpp"

namespace drape {

struct BandValue {
  double lo, hi;    // band bounds at q
  double dlo, dhi;  // their slopes d/dq
};

// Signed distance of f outside the band and its derivatives.
struct BandExcess {
  double r = 0;      // f - hi above, f - lo below, 0 inside
  double dr_dq = 0;  // -dhi or -dlo outside
};

class Band {
 public:
  Band() = default;
  // Stretch: q = strain. Loading curve Fm*(q/EMT)^n with n = 2/LT - 1, so its
  // area to EMT is WT; unloading Fm*(q/EMT)^m with area RT*WT. No tension in
  // compression; past EMT both follow the loading tangent.
  static Band tensile(const TensileKES& k);
  // Bending and shear: f = slope*q +- half_width, or measured curves.
  static Band linear(double slope, double half_width, const Curve& load = {},
                     const Curve& unload = {});

  BandValue at(double q) const;

  // The hysteresis (stop-operator) force for strain q given the force f1 the
  // element had at the start of the step: f1 while it stays inside the band,
  // else the band edge it was pushed past. Memory means: this, not f1.
  struct Stop {
    double f;     // target force
    double df_dq; // its slope (0 inside the band)
  };
  Stop stop(double f1, double q) const { return stop(f1, at(q)); }
  static Stop stop(double f1, const BandValue& v) {
    if (f1 > v.hi) return {v.hi, v.dhi};
    if (f1 < v.lo) return {v.lo, v.dlo};
    return {f1, 0.0};
  }
  BandExcess excess(double f, double q) const { return excess(f, at(q)); }
  static BandExcess excess(double f, const BandValue& v) {
    if (f > v.hi) return {f - v.hi, -v.dhi};
    if (f < v.lo) return {f - v.lo, -v.dlo};
    return {};
  }

 private:
  enum class Kind { PowerLaw, Linear, Table } kind_ = Kind::Linear;
  double fm_ = 0, emt_ = 1, n_load_ = 1, n_unload_ = 1;  // PowerLaw
  double slope_ = 0, half_ = 0;                          // Linear
  Curve load_, unload_;                                  // Table
};

// Piecewise-linear interpolation with linear extrapolation from the end segments.
double interpolate(const Curve& c, double q, double* slope);

}  // namespace drape
