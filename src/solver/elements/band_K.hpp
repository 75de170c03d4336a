#pragma once
// A band's stop and excess (Band::stop, Band::excess) for four elements side
// by side, lane k element k's: the scalar functions' operations lane by lane,
// their branches as selects, so their numbers bit for bit (tests:
// BandLanes.*). Which branch an element takes depends on its strain and
// force: as branches they were mispredicted often enough that the elements'
// chains of divisions could not overlap; as selects four run at once.
#include <cmath>

#include "solver/band.hpp"
#include "solver/elements/lanes.hpp"

#if DRAPE_LANES
namespace drape {

struct BandFour {
  D4 lo, hi, dlo, dhi;
};
struct StopFour {
  D4 f, df_dq;
};
struct ExcessFour {
  D4 r, dr_dq;
};

// Four scalar band values as lanes.
inline BandFour band_four(const BandValue v[4]) {
  return {D4{v[0].lo, v[1].lo, v[2].lo, v[3].lo}, D4{v[0].hi, v[1].hi, v[2].hi, v[3].hi},
          D4{v[0].dlo, v[1].dlo, v[2].dlo, v[3].dlo}, D4{v[0].dhi, v[1].dhi, v[2].dhi, v[3].dhi}};
}

// Lane masks (all bits set where true) of the scalar comparisons: ordered,
// so a NaN compares false as it does there.
inline D4 greater4(D4 a, D4 b) { return (D4)_mm256_cmp_pd((__m256d)a, (__m256d)b, _CMP_GT_OQ); }
inline D4 less4(D4 a, D4 b) { return (D4)_mm256_cmp_pd((__m256d)a, (__m256d)b, _CMP_LT_OQ); }
inline D4 equal4(D4 a, D4 b) { return (D4)_mm256_cmp_pd((__m256d)a, (__m256d)b, _CMP_EQ_OQ); }
inline D4 and4(D4 a, D4 b) { return (D4)_mm256_and_pd((__m256d)a, (__m256d)b); }
inline D4 or4(D4 a, D4 b) { return (D4)_mm256_or_pd((__m256d)a, (__m256d)b); }
// a where mask is set, else b.
inline D4 select4(D4 mask, D4 a, D4 b) { return (D4)_mm256_blendv_pd((__m256d)b, (__m256d)a, (__m256d)mask); }

// Four tensile power-law bands' values (Band::at of a Kind::PowerLaw band:
// curve_at's compression, past-EMT and power-law branches as selects, the
// power law's two std::pow lane by lane), lane k at strain q[k] with band
// p[k]'s numbers: the scalar values bit for bit. The strain's sign at an
// edge near its rest length picks the branch: as branches, mispredicted.
inline D4 less_equal4(D4 a, D4 b) { return (D4)_mm256_cmp_pd((__m256d)a, (__m256d)b, _CMP_LE_OQ); }
inline D4 greater_equal4(D4 a, D4 b) { return (D4)_mm256_cmp_pd((__m256d)a, (__m256d)b, _CMP_GE_OQ); }
inline BandFour tensile_band4(D4 q, const Band::PowerLaw* p[4]) {
  const D4 fm{p[0]->fm, p[1]->fm, p[2]->fm, p[3]->fm};
  const D4 nl{p[0]->n_load, p[1]->n_load, p[2]->n_load, p[3]->n_load};
  const D4 nu{p[0]->n_unload, p[1]->n_unload, p[2]->n_unload, p[3]->n_unload};
  const D4 emt{p[0]->emt, p[1]->emt, p[2]->emt, p[3]->emt};
  const D4 kc{p[0]->kc, p[1]->kc, p[2]->kc, p[3]->kc};
  // The power law below EMT (where 0 < q < EMT; no pow in the other lanes).
  const D4 squeezed = less_equal4(q, splat4(0.0)), past = greater_equal4(q, emt);
  const int other = _mm256_movemask_pd((__m256d)or4(squeezed, past));
  const D4 t = q / emt;
  D4 pl = splat4(0.0), pu = splat4(0.0);
  for (int l = 0; l < 4; ++l)
    if (!(other >> l & 1)) {
      pl[l] = std::pow(t[l], nl[l]);
      pu[l] = std::pow(t[l], nu[l]);
    }
  const D4 hi = fm * pl, lo = fm * pu;
  BandFour v{lo, hi, nu * lo / q, nl * hi / q};
  // Past EMT: the loading tangent.
  const D4 sp = nl * fm / emt, fp = fm + sp * (q - emt);
  v.lo = select4(past, fp, v.lo);
  v.hi = select4(past, fp, v.hi);
  v.dlo = select4(past, sp, v.dlo);
  v.dhi = select4(past, sp, v.dhi);
  // In compression: the quadratic onset over [-eps, 0], then the line.
  const D4 eps = splat4(Band::kCompressionOnset) * emt;
  const D4 line = less4(q, -eps);
  const D4 fc = select4(line, kc * (q + splat4(0.5) * eps), splat4(-0.5) * kc * q * q / eps);
  const D4 sc = select4(line, kc, -kc * q / eps);
  v.lo = select4(squeezed, fc, v.lo);
  v.hi = select4(squeezed, fc, v.hi);
  v.dlo = select4(squeezed, sc, v.dlo);
  v.dhi = select4(squeezed, sc, v.dhi);
  return v;
}

// Four linear bands' values (Band::at's inline case), lane k's slope and
// half width at strain q[k]: the same operations.
inline BandFour linear_band4(D4 q, D4 slope, D4 half) { return {slope * q - half, slope * q + half, slope, slope}; }

// Band::stop(anchor, v) with each lane's reversal: its cases applied from
// the last to the first, so that the first that holds is the one left.
inline StopFour band_stop4(D4 anchor, D4 reversal, const BandFour& v) {
  const D4 f = anchor + reversal * v.hi;
  const D4 on_hi = equal4(f, v.hi);
  const D4 on_edge = and4(greater4(reversal, splat4(0.0)), or4(on_hi, equal4(f, v.lo)));
  StopFour s{f, reversal * v.dhi};
  s.df_dq = select4(on_edge, select4(on_hi, v.dhi, v.dlo), s.df_dq);
  const D4 below = less4(f, v.lo), above = greater4(f, v.hi);
  s.f = select4(below, v.lo, s.f);
  s.df_dq = select4(below, v.dlo, s.df_dq);
  s.f = select4(above, v.hi, s.f);
  s.df_dq = select4(above, v.dhi, s.df_dq);
  return s;
}

// Band::excess(f, v), likewise.
inline ExcessFour band_excess4(D4 f, const BandFour& v) {
  const D4 zero = splat4(0.0);
  const D4 below = less4(f, v.lo), above = greater4(f, v.hi);
  ExcessFour e{select4(below, f - v.lo, zero), select4(below, -v.dlo, zero)};
  e.r = select4(above, f - v.hi, e.r);
  e.dr_dq = select4(above, -v.dhi, e.dr_dq);
  return e;
}

}  // namespace drape
#endif
