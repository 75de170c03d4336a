#pragma once
// A sparse matrix of 3 x 3 blocks, one block row per particle (compressed
// rows): the assembled stiffness K and the multigrid's coarse operators.
// Rows are independent, so products split over threads with results that do
// not depend on how (each row sums its blocks in column order).
//
// A block is stored column-major (entry(i, j) = 3 j + i): its column j is
// three consecutive doubles, so that row_times adds a block's three rows as
// the lanes of one vector, each lane the scalar sum's terms in its order.
#if defined(__AVX__)
#include <immintrin.h>
#endif

#include <algorithm>
#include <cstdint>
#include <vector>

namespace drape {

struct BlockMatrix {
  int64_t rows = 0;
  std::vector<int64_t> start;  // rows + 1: row r's blocks are [start[r], start[r+1])
  std::vector<int32_t> col;    // block column, ascending within a row
  std::vector<double> val;     // 9 per block, column-major (entry)

  int64_t blocks() const { return start.empty() ? 0 : start.back(); }
  // y = A x (3 doubles a row).
  void multiply(const double* x, double* y) const;
  // r = b - A x.
  void residual(const double* b, const double* x, double* r) const;
  // The block at (r, c); null where there is none.
  const double* block(int64_t r, int32_t c) const;
  double* block(int64_t r, int32_t c) {
    return const_cast<double*>(static_cast<const BlockMatrix*>(this)->block(r, c));
  }
  // Rows from per-row column lists (ascending, distinct); values zero. For
  // matrices built once; rebuilt patterns use build_pattern (no allocation).
  void set_pattern(const std::vector<std::vector<int32_t>>& cols);
};

// The bytes A's arrays hold (their capacities).
inline size_t held_bytes(const BlockMatrix& A) {
  return A.start.capacity() * sizeof(int64_t) + A.col.capacity() * sizeof(int32_t) + A.val.capacity() * sizeof(double);
}

// Where a stored block keeps its entry (i, j).
constexpr int entry(int i, int j) { return 3 * j + i; }

// A stored block as a row-major 3 x 3 (the smoothers' inverse blocks), and back.
inline void to_row_major(const double* __restrict stored, double* __restrict rm) {
  for (int i = 0; i < 3; ++i)
    for (int j = 0; j < 3; ++j) rm[3 * i + j] = stored[entry(i, j)];
}

// v sized n; capacity grows by a quarter more than asked, so that patterns
// that grow a little between rebuilds reuse the buffer.
template <class T>
void resize_keeping(std::vector<T>& v, size_t n) {
  if (n > v.capacity()) v.reserve(n + n / 4);
  v.resize(n);
}

// The listed columns of each row before they are sorted and made distinct:
// kept between pattern rebuilds so that they allocate nothing once sized.
struct PatternScratch {
  std::vector<int64_t> at;    // rows + 1: row r's listed columns are col[at[r], at[r + 1])
  std::vector<int32_t> col;
  std::vector<int64_t> kept;  // per row: how many distinct
};

// A's pattern (values zero): `list(r, push)` calls push(c) for each column c
// of row r, repeats allowed, the same columns each time it is called. Two
// passes (count, then fill) into flat buffers; A's and s's capacity reused.
template <class List>
void build_pattern(BlockMatrix& A, int64_t rows, PatternScratch& s, List&& list) {
  resize_keeping(s.at, size_t(rows) + 1);
  resize_keeping(s.kept, size_t(rows));
  s.at[0] = 0;
#pragma omp parallel for schedule(static)
  for (int64_t r = 0; r < rows; ++r) {
    int64_t n = 0;
    list(r, [&n](int32_t) { ++n; });
    s.at[r + 1] = n;
  }
  for (int64_t r = 0; r < rows; ++r) s.at[r + 1] += s.at[r];
  resize_keeping(s.col, size_t(s.at[rows]));
#pragma omp parallel for schedule(static)
  for (int64_t r = 0; r < rows; ++r) {
    int32_t* b = s.col.data() + s.at[r];
    int32_t* e = b;
    list(r, [&e](int32_t c) { *e++ = c; });
    std::sort(b, e);
    s.kept[r] = std::unique(b, e) - b;
  }
  A.rows = rows;
  resize_keeping(A.start, size_t(rows) + 1);
  A.start[0] = 0;
  for (int64_t r = 0; r < rows; ++r) A.start[r + 1] = A.start[r] + s.kept[r];
  resize_keeping(A.col, size_t(A.start[rows]));
#pragma omp parallel for schedule(static)
  for (int64_t r = 0; r < rows; ++r)
    std::copy(s.col.begin() + s.at[r], s.col.begin() + s.at[r] + s.kept[r], A.col.begin() + A.start[r]);
  resize_keeping(A.val, 9 * A.col.size());
  std::fill(A.val.begin(), A.val.end(), 0.0);
}

// Per thread, a map from a column to its block in the current row (-1 where
// none): sized for `cols` columns, grown only, kept between products.
struct SlotMaps {
  std::vector<std::vector<int64_t>> of;
  void size(int threads, int64_t cols) {
    if (of.size() < size_t(threads)) of.resize(size_t(threads));
    for (auto& s : of)
      if (s.size() < size_t(cols)) s.resize(size_t(cols), -1);  // the entries kept are -1 already
  }
};

// One block row times x: `count` blocks `val` (9 each) in columns `col`,
// summed in their order into out (3 values). BlockMatrix's products and a
// rank's rows with their own column numbers (DividedLevel) share it: the
// same sums, bit for bit. The plain version, the reference of row_times.
inline void row_times_reference(const double* __restrict val, const int32_t* __restrict col, int64_t count,
                                const double* __restrict x, double* __restrict out) {
  double y0 = 0, y1 = 0, y2 = 0;
  const double* __restrict b = val;
  for (int64_t k = 0; k < count; ++k, b += 9) {
    const double* xc = x + 3 * int64_t(col[k]);
    const double x0 = xc[0], x1 = xc[1], x2 = xc[2];
    y0 += b[entry(0, 0)] * x0 + b[entry(0, 1)] * x1 + b[entry(0, 2)] * x2;
    y1 += b[entry(1, 0)] * x0 + b[entry(1, 1)] * x1 + b[entry(1, 2)] * x2;
    y2 += b[entry(2, 0)] * x0 + b[entry(2, 1)] * x1 + b[entry(2, 2)] * x2;
  }
  out[0] = y0;
  out[1] = y1;
  out[2] = y2;
}

#if defined(__AVX__)
// row_times_reference with the block's three rows as lanes 0-2 of one
// vector: lane i sums (b_i0 x0 + b_i1 x1) + b_i2 x2 into y_i, the scalar
// terms in the scalar order (the build keeps contraction off: no fused
// multiply-adds), so the result is the same bit for bit. Lane 3 of the
// first two columns is the next column's first entry, dropped; the third
// column's load is masked (it may end the array).
inline void row_times(const double* __restrict val, const int32_t* __restrict col, int64_t count,
                      const double* __restrict x, double* __restrict out) {
  const __m256i three = _mm256_set_epi64x(0, -1, -1, -1);
  __m256d y = _mm256_setzero_pd();
  const double* __restrict b = val;
  for (int64_t k = 0; k < count; ++k, b += 9) {
    const double* xc = x + 3 * int64_t(col[k]);
    const __m256d t01 = _mm256_add_pd(_mm256_mul_pd(_mm256_loadu_pd(b), _mm256_broadcast_sd(xc)),
                                      _mm256_mul_pd(_mm256_loadu_pd(b + 3), _mm256_broadcast_sd(xc + 1)));
    y = _mm256_add_pd(y, _mm256_add_pd(t01, _mm256_mul_pd(_mm256_maskload_pd(b + 6, three), _mm256_broadcast_sd(xc + 2))));
  }
  const __m128d lo = _mm256_castpd256_pd128(y);
  _mm_storeu_pd(out, lo);
  _mm_store_sd(out + 2, _mm256_extractf128_pd(y, 1));
}
#else
inline void row_times(const double* __restrict val, const int32_t* __restrict col, int64_t count,
                      const double* __restrict x, double* __restrict out) {
  row_times_reference(val, col, count, x, out);
}
#endif

// y += s * B x for one row-major 3 x 3 block (the smoothers' own blocks).
inline void add_block_times(const double* b, const double* x, double s, double* y) {
  for (int i = 0; i < 3; ++i) y[i] += s * (b[3 * i] * x[0] + b[3 * i + 1] * x[1] + b[3 * i + 2] * x[2]);
}

// y += B x for one stored block: add_block_times' sums (s = 1).
inline void add_stored_block_times(const double* b, const double* x, double* y) {
  for (int i = 0; i < 3; ++i)
    y[i] += (b[entry(i, 0)] * x[0] + b[entry(i, 1)] * x[1] + b[entry(i, 2)] * x[2]);
}

// out += a b (stored blocks): the block products' one sum (BlockMatrix
// products and a rank's rows of level 1's operator, DividedLevel).
inline void add_block_product(const double* __restrict a, const double* __restrict b, double* __restrict out) {
  for (int i = 0; i < 3; ++i)
    for (int j = 0; j < 3; ++j)
      out[entry(i, j)] += a[entry(i, 0)] * b[entry(0, j)] + a[entry(i, 1)] * b[entry(1, j)] + a[entry(i, 2)] * b[entry(2, j)];
}

// out += w b: add_block_product where one factor is w I (the bilinear P's
// blocks), the same sums with its exact zeros left out.
inline void add_scaled_block(double w, const double* __restrict b, double* __restrict out) {
  for (int i = 0; i < 9; ++i) out[i] += w * b[i];
}

// The inverse of a symmetric positive definite row-major 3 x 3 block (by cofactors);
// false where it is not invertible.
bool invert_block(const double* a, double* inv);

// invert_block of a stored block: the inverse row-major (the smoothers' own blocks).
inline bool invert_stored_block(const double* a, double* inv) {
  double rm[9];
  to_row_major(a, rm);
  return invert_block(rm, inv);
}

}  // namespace drape
