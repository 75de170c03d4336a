#pragma once
// A band's stop and excess (Band::stop, Band::excess) for four elements side
// by side, lane k element k's: the scalar functions' operations lane by lane,
// their branches as selects, so their numbers bit for bit (tests:
// BandLanes.*). Which branch an element takes depends on its strain and
// force: as branches they were mispredicted often enough that the elements'
// chains of divisions could not overlap; as selects four run at once.
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
