#include "solver/multigrid/rank_rows.hpp"

#include <algorithm>
#include <utility>

namespace drape {

void RankRows::number(const Reducer& red, const Tiling& tiling, const std::vector<int64_t>& mine, int64_t grid) {
  red.counts(int64_t(mine.size()), rows_);
  int64_t n = 0;
  first_.clear();
  for (int64_t c : rows_) {
    first_.push_back(n);
    n += c;
  }
  std::vector<int64_t> cat(static_cast<size_t>(n));
  gather_all(red, mine.data(), rows_, cat.data(), bytes_);
  // One rank's list order: by tile, then by index.
  std::vector<std::pair<int64_t, int64_t>> key(static_cast<size_t>(n));
  for (int64_t k = 0; k < n; ++k) key[k] = {int64_t(tiling.tile_of(cat[k])) * grid + cat[k], k};
  std::sort(key.begin(), key.end());
  ids_.resize(size_t(n));
  from_.resize(size_t(n));
  column_of_.assign(size_t(grid), -1);
  for (int64_t g = 0; g < n; ++g) {
    from_[g] = key[g].second;
    ids_[g] = cat[key[g].second];
    column_of_[ids_[g]] = int32_t(g);
  }
  mine_.resize(mine.size());
  for (size_t r = 0; r < mine.size(); ++r) mine_[r] = column_of_[mine[r]];
  std::vector<double>(size_t(3 * n)).swap(cat_);
}

int64_t gather_rows(const Reducer& red, const BlockMatrix& mine, const std::vector<int64_t>& rows_per_rank,
                    const std::vector<int64_t>& from, BlockMatrix& all) {
  int64_t n = 0;
  for (int64_t c : rows_per_rank) n += c;
  std::vector<int64_t> bytes, blocks;
  // Row lengths, then columns and values, each concatenated in rank order.
  std::vector<int64_t> len(size_t(mine.rows)), cat_len(static_cast<size_t>(n)), cat_start(size_t(n) + 1, 0);
  for (int64_t r = 0; r < mine.rows; ++r) len[r] = mine.start[r + 1] - mine.start[r];
  gather_all(red, len.data(), rows_per_rank, cat_len.data(), bytes);
  for (int64_t k = 0; k < n; ++k) cat_start[k + 1] = cat_start[k] + cat_len[k];
  red.counts(mine.blocks(), blocks);
  std::vector<int32_t> cat_col(size_t(cat_start[n]));
  gather_all(red, mine.col.data(), blocks, cat_col.data(), bytes);
  for (int64_t& b : blocks) b *= 9;
  std::vector<double> cat(size_t(9 * cat_start[n]));
  gather_all(red, mine.val.data(), blocks, cat.data(), bytes);
  // Rows in global order.
  all.rows = n;
  all.start.resize(size_t(n) + 1);
  all.start[0] = 0;
  for (int64_t g = 0; g < n; ++g) all.start[g + 1] = all.start[g] + cat_len[from[g]];
  all.col.resize(size_t(all.start[n]));
  all.val.resize(size_t(9 * all.start[n]));
#pragma omp parallel for schedule(static)
  for (int64_t g = 0; g < n; ++g) {
    const int64_t s = cat_start[from[g]], e = cat_start[from[g] + 1];
    std::copy(cat_col.begin() + s, cat_col.begin() + e, all.col.begin() + all.start[g]);
    std::copy(cat.begin() + 9 * s, cat.begin() + 9 * e, all.val.begin() + 9 * all.start[g]);
  }
  return 8 * n + cat_start[n] * (4 + 72);
}

void RankRows::gather_matrix(const Reducer& red, const BlockMatrix& mine, BlockMatrix& all) {
  matrix_bytes_ = gather_rows(red, mine, rows_, from_, all);
}

void RankRows::gather(const Reducer& red, const double* mine, double* all) {
  blocks_.resize(rows_.size());
  for (size_t k = 0; k < rows_.size(); ++k) blocks_[k] = 3 * rows_[k];
  gather_all(red, mine, blocks_, cat_.data(), bytes_);
  const int64_t n = size();
#pragma omp parallel for schedule(static)
  for (int64_t g = 0; g < n; ++g)
    for (int k = 0; k < 3; ++k) all[3 * g + k] = cat_[3 * from_[g] + k];
}

void RankRows::take_mine(const double* all, double* mine) const {
  const int64_t n = int64_t(mine_.size());
#pragma omp parallel for schedule(static)
  for (int64_t r = 0; r < n; ++r)
    for (int k = 0; k < 3; ++k) mine[3 * r + k] = all[3 * mine_[r] + k];
}

size_t RankRows::memory() const {
  return (ids_.capacity() + rows_.capacity() + from_.capacity() + first_.capacity() + mine_.capacity()) * 8 +
         column_of_.capacity() * 4 + cat_.capacity() * 8;
}

}  // namespace drape
