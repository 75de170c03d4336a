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
  static constexpr double kCompressionOnset = 0.5;
  Band() = default;
  // Stretch: q = strain. Loading curve Fm*(q/EMT)^n with n = 2/LT - 1, so its
  // area to EMT is WT; unloading Fm*(q/EMT)^m with area RT*WT (or measured
  // curves); past EMT both follow the loading tangent. In compression, which
  // KES does not measure, the band is a line of slope `compression`*(Fm/EMT),
  // reached over the first kCompressionOnset*EMT of shortening (a steeper onset
  // made Newton's tangent jump: Peirce's strip crept on instead of settling).
  static Band tensile(const TensileKES& k, double compression = 0);
  // Bending and shear: f = slope*q +- half_width, or measured curves.
  static Band linear(double slope, double half_width, const Curve& load = {},
                     const Curve& unload = {});

  // Linear bands (bending and shear without measured curves: the elements'
  // common case) inline, the same arithmetic as out of line; the others in
  // band.cpp.
  BandValue at(double q) const {
    if (kind_ == Kind::Linear && !tensile_) return {slope_ * q - half_, slope_ * q + half_, slope_, slope_};
    return curve_at(q);
  }

  // Inside the band the force moves with the strain at `reversal` times the
  // loading curve's slope: 0 keeps it where it was (the band taken
  // literally: the element then bends or stretches freely across the band);
  // > 1 gives the steep reversal of a measured KES loop, which crosses the
  // band over a small strain and so keeps a stiffness everywhere.
  void set_reversal(double r) { reversal_ = r; }
  double reversal() const { return reversal_; }

  // The step's anchor: the force f1 and strain q1 at the start of the step
  // folded into one number, so that f1 + reversal*(hi(q) - hi(q1)) = anchor
  // + reversal*hi(q). With reversal 0 the anchor is f1 itself.
  double anchor(double f1, double q1) const { return reversal_ > 0 ? f1 - reversal_ * at(q1).hi : f1; }

  // The hysteresis (stop-operator) force for strain q given the step's
  // anchor: the force moved inside the band as above, clamped to the band
  // edge it was pushed past. Memory means: this, not the step-start force.
  struct Stop {
    double f;     // target force
    double df_dq; // its slope (reversal * the loading slope inside the band)
  };
  Stop stop(double anchor, double q) const { return stop(anchor, at(q)); }
  Stop stop(double anchor, const BandValue& v) const {
    const double f = anchor + reversal_ * v.hi;
    if (f > v.hi) return {v.hi, v.dhi};
    if (f < v.lo) return {v.lo, v.dlo};
    // On an edge by rounding (a band of zero width always): the edge's slope.
    if (reversal_ > 0 && (f == v.hi || f == v.lo)) return {f, f == v.hi ? v.dhi : v.dlo};
    return {f, reversal_ * v.dhi};
  }
  // The tensile power law's numbers (Kind::PowerLaw, which only tensile()
  // makes), for four edges' bands in the lanes of a vector
  // (elements/band_K.hpp: tensile_band4, the same arithmetic as curve_at).
  struct PowerLaw {
    double fm, n_load, n_unload, emt, kc;
  };
  bool power_law() const { return kind_ == Kind::PowerLaw; }
  // A linear band's slope and half width (linear() without curves: at()'s
  // inline case), for the lanes' form likewise (linear_band4).
  bool plain_linear() const { return kind_ == Kind::Linear && !tensile_; }
  double slope() const { return slope_; }
  double half_width() const { return half_; }
  PowerLaw power_law_terms() const { return {fm_, n_load_, n_unload_, emt_, kc_}; }

  BandExcess excess(double f, double q) const { return excess(f, at(q)); }
  static BandExcess excess(double f, const BandValue& v) {
    if (f > v.hi) return {f - v.hi, -v.dhi};
    if (f < v.lo) return {f - v.lo, -v.dlo};
    return {};
  }

 private:
  BandValue curve_at(double q) const;
  enum class Kind { PowerLaw, Linear, Table } kind_ = Kind::Linear;
  double fm_ = 0, n_load_ = 1, n_unload_ = 1;  // PowerLaw
  bool tensile_ = false;
  double emt_ = 1, kc_ = 0;  // tensile: EMT, and the compression branch's slope
  double slope_ = 0, half_ = 0;                          // Linear
  Curve load_, unload_;                                  // Table
  double reversal_ = 0;
};

// Piecewise-linear interpolation with linear extrapolation from the end segments.
double interpolate(const Curve& c, double q, double* slope);

}  // namespace drape
