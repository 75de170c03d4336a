#include "solver/self_contact.hpp"

#include <algorithm>
#include <cmath>
#include <stdexcept>

#include <omp.h>

#include "solver/fit.hpp"

namespace drape {

namespace {
// Partners reserved per particle at the first build; a list that outgrows
// it grows by half (the only allocation after the first build).
constexpr int64_t kReservedPartners = 4;
}  // namespace

// Sized by the list, as the evaluator's arrays (fit.hpp), at most the
// grid's n. What the last build holds is kept: a new capacity for the same
// lists needs no new build.
void SelfContact::fit_to_lists(const ActiveList& particles, int64_t n, bool exact) {
  const size_t np = size_t(particles.size()), most = size_t(n);
  fit_keeping(xb_, 3 * np, 3 * most, exact, 0.0);
  fit_keeping(first_, np + 1, most + 1, exact, int32_t(0));
  const size_t partners = std::max(size_t(listed_), size_t(kReservedPartners) * np);
  fit_keeping(partners_, partners, size_t(kReservedPartners) * most, exact, int32_t(0));
  if (exact) std::vector<double>().swap(gx_);  // the contact ghosts': sized by the halo at a build
  fit_hash(int64_t(np), n, exact);
}

void SelfContact::fit_hash(int64_t hashed, int64_t n, bool exact) {
  int64_t buckets = 1;
  while (buckets < hashed) buckets *= 2;  // a power of two (the hash masks), about one a particle
  fit(bucket_start_, size_t(buckets + 1), size_t(4 * n + 1), exact, int32_t(0));
  fit(bucket_items_, size_t(hashed), size_t(n), exact, int32_t(0));
  fit(bucket_x_, size_t(3 * hashed), size_t(3 * n), exact, 0.0);
}

void SelfContact::memory(MemoryTable& t) const {
  const char* o = "SelfContact";
  t.add(o, "build positions", xb_);
  t.add(o, "contact ghosts' build positions", gx_);
  t.add(o, "partner offsets", first_);
  t.add(o, "partners (hashed indices)", partners_);
  t.add(o, "contact ghosts' own-numbering indices", ghost_lo_);
  t.add(o, "spatial hash", (bucket_start_.capacity() + bucket_items_.capacity()) * sizeof(int32_t));
  t.add(o, "spatial hash's positions", bucket_x_);
  t.add(o, "contact ghosts", ghosts_);
}

bool SelfContact::refresh(const Cloth& c, const ActiveList& particles, uint64_t stamp, const Contact& contact,
                          const double* x, const Reducer& red, const Halo& halo) {
  // The first build's sizes are its lists' (as a new stage's: fit_to_lists
  // with exact); later list changes grow them where short.
  if (builds_ == 0 || stamp != stamp_) fit_to_lists(particles, c.grid.n(), builds_ == 0);
  const bool same_layer = contact.thickness == contact_.thickness && contact.stiffness == contact_.stiffness;
  // One decision for all ranks (the build is collective): the largest move,
  // or infinity where a rank's lists or the layer changed.
  const bool stale = builds_ == 0 || stamp != stamp_ || !same_layer;
  const double worst = red.max(stale ? HUGE_VAL : worst_move(particles, x));
  const double limit = 0.25 * reach_;
  if (worst <= limit * limit) return false;
  contact_ = contact;
  stamp_ = stamp;
  dist_ = 2 * contact.thickness;
  reach_ = 2 * dist_;
  // Mesh neighbours within reach at rest are held apart by the elements:
  // a fold brings them within D only if it is tighter than the layer.
  exclude2_ = reach_ * reach_ * (1 + 1e-9);
  build(c, particles, x, halo);
  ++builds_;
  return true;
}

// The largest squared distance of a listed particle from where the last
// build saw it (max over particles: exact in any order).
double SelfContact::worst_move(const ActiveList& particles, const double* x) const {
  const int64_t n = particles.size();
  const int64_t* items = particles.items.data();
  double worst = 0;
#pragma omp parallel for schedule(static) reduction(max : worst)
  for (int64_t k = 0; k < n; ++k) {
    const int64_t p = items[k];
    double d2 = 0;
    for (int i = 0; i < 3; ++i) {
      const double u = x[3 * p + i] - xb_[3 * k + i];
      d2 += u * u;
    }
    worst = std::max(worst, d2);
  }
  return worst;
}

void SelfContact::cell_of(const double* x, int64_t cell[3]) const {
  for (int i = 0; i < 3; ++i) cell[i] = int64_t(std::floor(x[i] / reach_));
}

// Linear in the cell: the cells of a row along x fall in consecutive
// buckets (a search reads its stencil's three at once), the rows at
// pseudo-random places (odd multipliers near 2^64 over the golden ratio).
int64_t SelfContact::bucket_of(int64_t cx, int64_t cy, int64_t cz) const {
  const uint64_t h = uint64_t(cx) + uint64_t(cy) * 0x9e3779b97f4a7c15ull + uint64_t(cz) * 0xc2b2ae3d27d4eb4full;
  return int64_t(h & uint64_t(buckets_ - 1));
}

// Counting sort of the listed particles, then the contact ghosts, by
// bucket, in that order: serial, one pass, so the hash is the same whatever
// the thread count (and the partners are sorted after anyway).
void SelfContact::hash_particles() {
  // Buckets for these particles (a coarse stage has far fewer than the
  // grid the arrays were sized for): a power of two, at least as many
  // (the partners are sorted after: the same lists whatever the buckets).
  const int64_t hashed = own_ + int64_t(ghosts_.size());
  buckets_ = 1;
  while (buckets_ < hashed) buckets_ *= 2;
  int32_t* start = bucket_start_.data();
  std::fill(start, start + buckets_ + 1, 0);
  int64_t cell[3];
  for (int64_t h = 0; h < hashed; ++h) {
    cell_of(built_at(h), cell);
    ++start[bucket_of(cell[0], cell[1], cell[2]) + 1];
  }
  for (int64_t b = 1; b <= buckets_; ++b) start[b] += start[b - 1];
  for (int64_t h = 0; h < hashed; ++h) {
    cell_of(built_at(h), cell);
    bucket_items_[start[bucket_of(cell[0], cell[1], cell[2])]++] = int32_t(h);
  }
  for (int64_t b = buckets_; b > 0; --b) start[b] = start[b - 1];  // back to each bucket's start
  start[0] = 0;
  // The positions in bucket order: a search reads a bucket's at one place.
#pragma omp parallel for schedule(static)
  for (int64_t s = 0; s < hashed; ++s)
    for (int i = 0; i < 3; ++i) bucket_x_[3 * s + i] = built_at(bucket_items_[s])[i];
}

template <class F>
void SelfContact::candidates(const Cloth& c, const ActiveList& particles, int64_t pos, F&& f) const {
  const Grid& g = c.grid;
  const int64_t p = particles.items[size_t(pos)];
  const double* xp = &xb_[3 * pos];
  int64_t home[3], at[3];
  cell_of(xp, home);
  const int ip = g.i_of(p), jp = g.j_of(p);
  const double reach2 = reach_ * reach_;
  // The particles hashed from s0 to s1 that lie in row (cy, cz), cells x0
  // to x1 along it. The cheapest test first, on positions read in a
  // row: most lie beyond the reach (their cell's far side, or another cell
  // hashed here); most left are mesh neighbours, found from the particle's
  // id (a division) last.
  auto visit = [&](int32_t s0, int32_t s1, int64_t x0, int64_t x1, int64_t cy, int64_t cz) {
    for (int32_t s = s0; s < s1; ++s) {
      const double* xq = &bucket_x_[3 * size_t(s)];
      double d2 = 0;
      for (int i = 0; i < 3; ++i) d2 += (xq[i] - xp[i]) * (xq[i] - xp[i]);
      if (!(d2 < reach2)) continue;
      const int64_t h = bucket_items_[s];
      if (h == pos) continue;
      cell_of(xq, at);
      if (at[1] != cy || at[2] != cz || at[0] < x0 || at[0] > x1) continue;  // another cell hashed here
      const int64_t q = h < own_ ? particles.items[size_t(h)] : ghosts_[size_t(h - own_)];
      const double di = (g.i_of(q) - ip) * g.hi, dj = (g.j_of(q) - jp) * g.hj;
      if (di * di + dj * dj <= exclude2_) continue;  // a mesh neighbour
      f(int32_t(h));
    }
  };
  const int32_t* start = bucket_start_.data();
  for (int64_t b = -1; b <= 1; ++b)
    for (int64_t e = -1; e <= 1; ++e) {
      const int64_t cy = home[1] + b, cz = home[2] + e;
      const int64_t k = bucket_of(home[0], cy, cz);
      if (k >= 1 && k + 1 < buckets_) {
        visit(start[k - 1], start[k + 2], home[0] - 1, home[0] + 1, cy, cz);  // the row's three cells' buckets, side by side
      } else {  // wrapped about the table's ends: a cell at a time (a small table may hold a bucket twice)
        for (int64_t a = -1; a <= 1; ++a) {
          const int64_t w = (k + a) & (buckets_ - 1);
          visit(start[w], start[w + 1], home[0] + a, home[0] + a, cy, cz);
        }
      }
    }
}

void SelfContact::build(const Cloth& c, const ActiveList& particles, const double* x, const Halo& halo) {
  const int64_t n = particles.size();
  const int64_t* items = particles.items.data();
  own_ = n;
  particles_ = &particles;
#pragma omp parallel for schedule(static)
  for (int64_t k = 0; k < n; ++k)
    for (int i = 0; i < 3; ++i) xb_[3 * k + i] = x[3 * items[k] + i];
  // Other ranks' particles within reach, and their positions into gx_.
  halo.plan_contact(particles.items, xb_.data(), reach_, ghosts_, gx_);
  fit_hash(n + int64_t(ghosts_.size()), c.grid.n(), false);
  hash_particles();
  list_pairs(c, particles);
  // The gather's fixed order: ascending global id.
#pragma omp parallel for schedule(static)
  for (int64_t k = 0; k < n; ++k)
    std::sort(partners_.data() + first_[k], partners_.data() + first_[k + 1],
              [this](int32_t a, int32_t b) { return id_of_hashed(a) < id_of_hashed(b); });
  keep_partners(halo);
}

// One search a particle: each thread lists its own run of particles' partners
// into its own share of partners_ (the array cut evenly by thread), then the
// runs are moved down into list order. A thread whose partners outgrow its
// share only counts on; then the particles with partners are searched again
// into their offsets. Either way each particle's partners are those its
// search finds, in its order: the same list on any thread count.
void SelfContact::list_pairs(const Cloth& c, const ActiveList& particles) {
  const int64_t n = particles.size();
  const int64_t room = int64_t(partners_.size());
  bool overflow = false;
  int64_t used = 1;  // the threads that ran the search
  first_[0] = 0;
#pragma omp parallel reduction(|| : overflow)
  {
    const int64_t t = omp_get_thread_num(), threads = omp_get_num_threads();
    if (t == 0) used = threads;
    const int64_t end = room * (t + 1) / threads;
    int64_t at = room * t / threads;
    for (int64_t k = n * t / threads; k < n * (t + 1) / threads; ++k) {
      int32_t m = 0;
      candidates(c, particles, k, [&](int32_t h) {
        if (at + m < end) partners_[size_t(at + m)] = h;
        ++m;
      });
      overflow = overflow || at + m > end;
      at = std::min(at + m, end);
      first_[k + 1] = m;
    }
  }
  int64_t total = 0;
  for (int64_t k = 0; k < n; ++k) {
    total += first_[k + 1];
    if (total > INT32_MAX) throw std::length_error("SelfContact: more pairs than 32-bit offsets reach");
    first_[k + 1] = int32_t(total);
  }
  listed_ = total;
  if (!overflow) {
    // Each thread's run lies at or after its place in list order (the runs
    // before it fit their shares), and ends before the next run's share
    // starts: moved down in thread order, nothing is overwritten unread.
    for (int64_t t = 0; t < used; ++t) {
      const int64_t from = room * t / used, k0 = n * t / used, k1 = n * (t + 1) / used;
      std::copy(partners_.begin() + from, partners_.begin() + from + (first_[k1] - first_[k0]),
                partners_.begin() + first_[k0]);
    }
    return;
  }
  ++searched_twice_;
  if (total > room) partners_.resize(size_t(total + total / 2));
#pragma omp parallel for schedule(static)
  for (int64_t k = 0; k < n; ++k) {
    // Most particles have no partner: no second search for them.
    if (first_[k + 1] == first_[k]) continue;
    int32_t* out = partners_.data() + first_[k];
    int32_t m = 0;
    candidates(c, particles, k, [&](int32_t h) { out[m++] = h; });
  }
}

// Only partners are read (their positions, K's direction, the residuals):
// the other contact ghosts need not be refreshed.
void SelfContact::keep_partners(const Halo& halo) {
  partner_.assign(ghosts_.size(), 0);
  if (!ghosts_.empty())
    for (int64_t k = 0; k < listed_; ++k)
      if (partners_[k] >= own_) partner_[size_t(partners_[k] - own_)] = 1;
  kept_.clear();
  for (size_t k = 0; k < ghosts_.size(); ++k)
    if (partner_[k]) kept_.push_back(ghosts_[k]);
  halo.keep_contact(kept_);
}

bool SelfContact::term(const double* x, int64_t p, int64_t q, PairTerm& t) const {
  const double* xp = x + 3 * p;
  const double* xq = x + 3 * q;
  double u[3], d2 = 0;
  for (int i = 0; i < 3; ++i) {
    u[i] = xp[i] - xq[i];
    d2 += u[i] * u[i];
  }
  if (!(d2 < dist_ * dist_)) return false;
  const double d = std::sqrt(d2);
  if (d > 0) {
    for (int i = 0; i < 3; ++i) t.n[i] = u[i] / d;
  } else {  // on one point: apart along z, the lower id upwards (antisymmetric)
    t.n[0] = t.n[1] = 0;
    t.n[2] = p < q ? 1.0 : -1.0;
  }
  t.d = d;
  t.f = penalty(contact_, dist_ - d, &t.slope);
  return true;
}

void SelfContact::add_force(int64_t pos, int64_t p, const double* x, double* f) const {
  for_partners(pos, [&](int64_t q) {
    PairTerm t;
    if (!term(x, p, q, t)) return;
    for (int i = 0; i < 3; ++i) f[i] += t.f * t.n[i];
  });
}

// dF_p/dx_p = J = -slope n n^T + (f/d)(I - n n^T) and dF_q/dx_p = -J, so the
// gradient's part at p is -J (r_p - r_q).
void SelfContact::add_jtr(int64_t pos, int64_t p, const double* x, const double* r, double* jtr) const {
  for_partners(pos, [&](int64_t q) {
    PairTerm t;
    if (!term(x, p, q, t)) return;
    double dr[3];
    for (int i = 0; i < 3; ++i) dr[i] = r[3 * p + i] - r[3 * q + i];
    const double nr = t.n[0] * dr[0] + t.n[1] * dr[1] + t.n[2] * dr[2];
    const double bend = t.d > 0 ? t.f / t.d : 0.0;
    for (int i = 0; i < 3; ++i) jtr[i] += t.slope * t.n[i] * nr - bend * (dr[i] - t.n[i] * nr);
  });
}

void SelfContact::add_product(int64_t pos, int64_t p, const double* x, const double* v, double* out) const {
  for_partners(pos, [&](int64_t q) {
    PairTerm t;
    if (term(x, p, q, t)) normal_product(t, v + 3 * p, v + 3 * q, out);
  });
}

double SelfContact::closest(const ActiveList& particles, const double* x) const {
  const int64_t n = particles.size();
  const int64_t* items = particles.items.data();
  double least = HUGE_VAL;  // a min over pairs: exact in any order
#pragma omp parallel for schedule(static) reduction(min : least)
  for (int64_t k = 0; k < n; ++k) {
    const int64_t p = items[k];
    for_partners(k, [&](int64_t q) {
      double d2 = 0;
      for (int i = 0; i < 3; ++i) d2 += (x[3 * p + i] - x[3 * q + i]) * (x[3 * p + i] - x[3 * q + i]);
      least = std::min(least, std::sqrt(d2));
    });
  }
  return least;
}

double SelfContact::slope_sum(int64_t pos, int64_t p, const double* x) const {
  double s = 0;
  for_partners(pos, [&](int64_t q) {
    PairTerm t;
    if (term(x, p, q, t)) s += t.slope;
  });
  return s;
}

}  // namespace drape
