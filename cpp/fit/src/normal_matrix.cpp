#include "sorpia/normal_matrix.hpp"

#include <algorithm>
#include <atomic>
#include <memory>
#include <mutex>
#include <cmath>
#include <string>
#include <type_traits>
#include <vector>

#include "sorpia/detail/parallel.hpp"
#include "sorpia/errors.hpp"
#include "sorpia/interrupt.hpp"

namespace sorpia {

namespace {

// Stored entries (of N and K together) per task of a product below which it runs on one thread.
constexpr std::size_t kEntriesPerTask = 100000;
// Stored entries of the rows per task of normal_matrix's blocks, at least.
constexpr std::size_t kRowEntriesPerTask = 32768;

// Columns of a block's Gram row summed at once by gram_row, their sums held in registers.
constexpr std::size_t kGramColumns = 4;

// Where row li of a Gram matrix of `width` columns starts among its packed rows on and above the diagonal (in
// entries).
std::size_t packed_row(std::size_t li, std::size_t width) { return li * (2 * width + 1 - li) / 2; }

// out[b * NB + c] = sum over the rows r < count of a block (count, stride) of w_r[c] a_r[li] a_r[li + b],
// b < width, each sum added up over the rows in their order from 0; w_r = weights[NB r ..] (1 when null). The
// weights' count a constant, so that each a_r[li + b] is read once for all NB sums; `scaled` holds w_r[c] a_r[li]
// per row.
template <int NB>
void gram_row(const double* rows, std::size_t stride, std::size_t count, const double* weights, std::size_t li,
              std::size_t width, double* out, std::vector<double>& scaled) {
  scaled.resize(count * NB);
  for (std::size_t r = 0; r < count; ++r) {
    const double a0 = rows[r * stride + li];
    for (int c = 0; c < NB; ++c)
      scaled[r * NB + static_cast<std::size_t>(c)] =
          a0 * (weights == nullptr ? 1.0 : weights[NB * r + static_cast<std::size_t>(c)]);
  }
  // kGramColumns columns at a time (then one at a time), each sum in a register over all the rows.
  const auto columns = [&](std::size_t b, auto n_columns) {
    constexpr std::size_t kCount = decltype(n_columns)::value;
    double acc[kCount][NB] = {};
    for (std::size_t r = 0; r < count; ++r) {
      const double* a = rows + r * stride + li + b;
      const double* w = &scaled[r * NB];
      for (std::size_t j = 0; j < kCount; ++j)
        for (int c = 0; c < NB; ++c) acc[j][c] += w[c] * a[j];
    }
    for (std::size_t j = 0; j < kCount; ++j)
      for (int c = 0; c < NB; ++c) out[(b + j) * NB + static_cast<std::size_t>(c)] = acc[j][c];
  };
  std::size_t b = 0;
  for (; b + kGramColumns <= width; b += kGramColumns) columns(b, std::integral_constant<std::size_t, kGramColumns>{});
  for (; b < width; ++b) columns(b, std::integral_constant<std::size_t, 1>{});
}

// Blocks per run that NormalBlocks adds into the pattern at once, in order.
constexpr std::size_t kBlocksPerRun = 256;

}  // namespace

struct NormalPattern {
  std::size_t n = 0;
  std::vector<std::int64_t> offsets;  // the blocks' columns it was made from
  std::vector<std::int32_t> columns;
  // The whole matrix's pattern (NormalMatrix's indptr and indices): row i's columns, sorted, are those of every
  // block holding column i.
  std::vector<std::int64_t> indptr;
  std::vector<std::int32_t> indices;
  // Where row i's diagonal entry is (its entries on and above the diagonal follow it); indptr[i] for an empty row.
  std::vector<std::int64_t> diagonal;
  // For an entry (j, i) below the diagonal, where its mirror (i, j) is (the entries on and above the diagonal
  // hold the sums; those below copy them); unused above.
  std::vector<std::int64_t> mirror;
  std::size_t n_blocks() const { return offsets.empty() ? 0 : offsets.size() - 1; }
  std::size_t width(std::size_t b) const { return static_cast<std::size_t>(offsets[b + 1] - offsets[b]); }
};

namespace {

// The pattern of blocks' columns, in ranges of rows on the core's threads (each row's columns made on its own).
std::shared_ptr<NormalPattern> make_pattern(std::size_t n, std::vector<std::int64_t> offsets,
                                            std::vector<std::int32_t> columns) {
  auto out = std::make_shared<NormalPattern>();
  NormalPattern& s = *out;
  s.n = n;
  s.offsets = std::move(offsets);
  s.columns = std::move(columns);
  const std::size_t n_blocks = s.n_blocks();
  // The blocks holding each column (A^T's rows over blocks): column j's are col_blocks[col_ptr[j] .. col_ptr[j + 1]).
  std::vector<std::int64_t> col_ptr(n + 1, 0);
  for (const std::int32_t j : s.columns) ++col_ptr[static_cast<std::size_t>(j) + 1];
  for (std::size_t j = 0; j < n; ++j) col_ptr[j + 1] += col_ptr[j];
  std::vector<std::int32_t> col_blocks(s.columns.size());
  {
    std::vector<std::int64_t> next(col_ptr.begin(), col_ptr.end() - 1);
    for (std::size_t b = 0; b < n_blocks; ++b)
      for (std::size_t p = 0; p < s.width(b); ++p)
        col_blocks[static_cast<std::size_t>(next[static_cast<std::size_t>(s.columns[s.offsets[b] + p])]++)] =
            static_cast<std::int32_t>(b);
  }
  poll_interrupt();
  // Row i: the union of its blocks' columns (Gustavson), a range of rows per task, then the ranges put together.
  const int tasks = detail::task_count(s.columns.size(), kRowEntriesPerTask);
  std::vector<std::vector<std::int32_t>> part(static_cast<std::size_t>(tasks));
  std::vector<std::int64_t> length(n + 1, 0);
  detail::for_each_range(tasks > 1, tasks, n, [&](int t, std::size_t i0, std::size_t i1) {
    std::vector<std::int32_t> marker(n, -1), touched;
    std::vector<std::int32_t>& out_t = part[static_cast<std::size_t>(t)];
    for (std::size_t i = i0; i < i1; ++i) {
      touched.clear();
      for (std::int64_t e = col_ptr[i]; e < col_ptr[i + 1]; ++e) {
        const auto b = static_cast<std::size_t>(col_blocks[static_cast<std::size_t>(e)]);
        for (auto c = static_cast<std::size_t>(s.offsets[b]); c < static_cast<std::size_t>(s.offsets[b + 1]); ++c) {
          const auto j = static_cast<std::size_t>(s.columns[c]);
          if (marker[j] != static_cast<std::int32_t>(i)) {
            marker[j] = static_cast<std::int32_t>(i);
            touched.push_back(s.columns[c]);
          }
        }
      }
      std::sort(touched.begin(), touched.end());
      out_t.insert(out_t.end(), touched.begin(), touched.end());
      length[i + 1] = static_cast<std::int64_t>(touched.size());
    }
  });
  s.indptr = std::move(length);
  for (std::size_t i = 0; i < n; ++i) s.indptr[i + 1] += s.indptr[i];
  s.indices.resize(static_cast<std::size_t>(s.indptr[n]));
  s.diagonal.resize(n);
  s.mirror.resize(s.indices.size());
  detail::for_each_range(tasks > 1, tasks, n, [&](int t, std::size_t i0, std::size_t) {
    std::copy(part[static_cast<std::size_t>(t)].begin(), part[static_cast<std::size_t>(t)].end(),
              s.indices.begin() + s.indptr[i0]);
  });
  detail::for_each_index(tasks > 1, tasks, n, [&](std::size_t i) {
    const auto first = s.indices.begin() + s.indptr[i], last = s.indices.begin() + s.indptr[i + 1];
    s.diagonal[i] = std::lower_bound(first, last, static_cast<std::int32_t>(i)) - s.indices.begin();
  });
  detail::for_each_index(tasks > 1, tasks, n, [&](std::size_t j) {
    for (auto e = static_cast<std::size_t>(s.indptr[j]); e < static_cast<std::size_t>(s.diagonal[j]); ++e) {
      const auto i = static_cast<std::size_t>(s.indices[e]);  // < j: (i, j) is in row i, after its diagonal
      const auto first = s.indices.begin() + s.diagonal[i], last = s.indices.begin() + s.indptr[i + 1];
      s.mirror[e] = std::lower_bound(first, last, static_cast<std::int32_t>(j)) - s.indices.begin();
    }
  });
  return out;
}

}  // namespace

struct NormalBlocks::State {
  int weight_count = 0;
  std::size_t nb = 1;  // values per entry
  std::shared_ptr<const NormalPattern> pattern;
  // The sums on and above the diagonal, at the pattern's entries (nb values each; made on the first run's adding)
  // and A^T x ((n, 3)).
  std::vector<double> values, rhs;
  // A block's share until its run is added: its Gram matrix's rows on and above the diagonal (packed, nb values
  // per entry) and then A^T x ((width, 3)), at share_at[b] in its run's slab (share_at[b + 1] - share_at[b]
  // values; runs restart at 0); `filled` once made (a block of no rows or columns has none). A run's slab is
  // taken from `spare` by the first of its blocks to be made and put back once the run is added, so that the
  // shares of the few runs in flight reuse a few slabs rather than each block allocating (and another thread
  // freeing) its own.
  std::vector<std::size_t> share_at;
  std::vector<char> filled;
  std::unique_ptr<std::atomic<double*>[]> slab;  // per run, its slab (null before its first block)
  std::vector<std::unique_ptr<double[]>> slabs;  // every slab made, each of slab_size values
  std::vector<double*> spare;                    // the slabs no run holds
  std::size_t slab_size = 0;
  std::mutex slab_mutex;                         // guards slabs, spare and the making of a run's slab
  std::unique_ptr<std::atomic<std::size_t>[]> run_left;  // per run, its blocks not yet added
  std::mutex mutex;                                       // guards the three below
  std::vector<char> run_complete;
  std::size_t next_run = 0;  // the first run not yet added into the pattern
  bool adding = false;       // a thread is adding runs
  std::size_t n_runs() const { return run_complete.size(); }
  void make_values() {
    if (values.empty()) values.assign(pattern->indices.size() * nb, 0.0);
  }
  // Run r's slab, taken on its first call.
  double* slab_of(std::size_t r) {
    double* at = slab[r].load(std::memory_order_acquire);
    if (at != nullptr) return at;
    const std::lock_guard<std::mutex> lock(slab_mutex);
    at = slab[r].load(std::memory_order_relaxed);
    if (at != nullptr) return at;
    if (spare.empty()) {
      slabs.push_back(std::make_unique<double[]>(slab_size));
      spare.push_back(slabs.back().get());
    }
    at = spare.back();
    spare.pop_back();
    slab[r].store(at, std::memory_order_release);
    return at;
  }
  // Run r's blocks' shares added at their entries, in the blocks' order, and its slab put back.
  void add_run(std::size_t r) {
    const NormalPattern& p = *pattern;
    make_values();
    const std::size_t b1 = std::min(filled.size(), (r + 1) * kBlocksPerRun);
    double* const run_slab = slab[r].load(std::memory_order_acquire);
    for (std::size_t b = r * kBlocksPerRun; b < b1; ++b) {
      if (!filled[b]) continue;
      const std::size_t w = p.width(b);
      const double* const gram = run_slab + share_at[b];
      const double* const share_rhs = gram + packed_row(w, w) * nb;
      const std::int32_t* cols = &p.columns[static_cast<std::size_t>(p.offsets[b])];
      for (std::size_t li = 0; li < w; ++li) {
        const auto i = static_cast<std::size_t>(cols[li]);
        const double* row = &gram[packed_row(li, w) * nb];
        auto e = static_cast<std::size_t>(p.diagonal[i]);
        for (std::size_t c = li; c < w; ++c, row += nb) {
          while (p.indices[e] != cols[c]) ++e;  // cols sorted, a subset of row i's
          double* dst = &values[e * nb];
          for (std::size_t v = 0; v < nb; ++v) dst[v] += row[v];
        }
        if (filled[b] == 2)
          for (std::size_t v = 0; v < 3; ++v) rhs[3 * i + v] += share_rhs[3 * li + v];
      }
    }
    if (run_slab != nullptr) {
      const std::lock_guard<std::mutex> lock(slab_mutex);
      spare.push_back(run_slab);
      slab[r].store(nullptr, std::memory_order_relaxed);
    }
  }
};

NormalBlocks::NormalBlocks(std::size_t n, int weight_count, std::vector<std::int64_t> offsets,
                           std::vector<std::int32_t> columns, std::shared_ptr<const NormalPattern>* kept)
    : state_(std::make_unique<State>()) {
  if (weight_count != 0 && weight_count != 1 && weight_count != 6)
    throw ParameterError("weight_count must be 0, 1 or 6, got " + std::to_string(weight_count));
  State& s = *state_;
  s.weight_count = weight_count;
  s.nb = weight_count == 6 ? 6 : 1;
  if (kept != nullptr && *kept && (*kept)->n == n && (*kept)->offsets == offsets && (*kept)->columns == columns) {
    s.pattern = *kept;
  } else {
    s.pattern = make_pattern(n, std::move(offsets), std::move(columns));
    if (kept != nullptr) *kept = s.pattern;
  }
  s.rhs.assign(3 * n, 0.0);
  const std::size_t n_blocks = s.pattern->n_blocks();
  s.filled.assign(n_blocks, 0);
  s.share_at.resize(n_blocks);
  for (std::size_t b = 0, at = 0; b < n_blocks; ++b) {
    if (b % kBlocksPerRun == 0) at = 0;
    s.share_at[b] = at;
    const std::size_t w = s.pattern->width(b);
    at += packed_row(w, w) * s.nb + 3 * w;
    s.slab_size = std::max(s.slab_size, at);
  }
  const std::size_t n_runs = (n_blocks + kBlocksPerRun - 1) / kBlocksPerRun;
  s.slab.reset(new std::atomic<double*>[n_runs]);
  for (std::size_t r = 0; r < n_runs; ++r) s.slab[r].store(nullptr, std::memory_order_relaxed);
  s.run_complete.assign(n_runs, 0);
  s.run_left.reset(new std::atomic<std::size_t>[n_runs]);
  for (std::size_t r = 0; r < n_runs; ++r) s.run_left[r] = std::min(n_blocks, (r + 1) * kBlocksPerRun) - r * kBlocksPerRun;
}

NormalBlocks::~NormalBlocks() = default;

void NormalBlocks::add(std::size_t b, const double* rows, std::size_t count, const double* weights, const double* x) {
  State& s = *state_;
  const std::size_t width = s.pattern->width(b);
  const std::size_t run = b / kBlocksPerRun;
  if (count > 0 && width > 0) {
    double* const gram = s.slab_of(run) + s.share_at[b];
    thread_local std::vector<double> scaled;
    for (std::size_t li = 0; li < width; ++li) {
      double* row = &gram[packed_row(li, width) * s.nb];
      if (s.nb == 6)
        gram_row<6>(rows, width, count, weights, li, width - li, row, scaled);
      else
        gram_row<1>(rows, width, count, s.weight_count == 0 ? nullptr : weights, li, width - li, row, scaled);
    }
    s.filled[b] = 1;
    if (x != nullptr) {
      double* const out_rhs = gram + packed_row(width, width) * s.nb;
      std::fill_n(out_rhs, 3 * width, 0.0);
      for (std::size_t r = 0; r < count; ++r)
        for (std::size_t li = 0; li < width; ++li) {
          const double a = rows[r * width + li];
          for (std::size_t c = 0; c < 3; ++c) out_rhs[3 * li + c] += a * x[3 * r + c];
        }
      s.filled[b] = 2;
    }
  }
  // The run complete: it and the complete runs after it added in order, unless a thread is adding already (which
  // then finds them complete).
  if (--s.run_left[run] != 0) return;
  std::unique_lock<std::mutex> lock(s.mutex);
  s.run_complete[run] = 1;
  if (s.adding) return;
  s.adding = true;
  while (s.next_run < s.n_runs() && s.run_complete[s.next_run]) {
    const std::size_t r = s.next_run;
    lock.unlock();
    s.add_run(r);
    lock.lock();
    ++s.next_run;
  }
  s.adding = false;
}

NormalMatrix NormalBlocks::finish(double* rhs) {
  State& s = *state_;
  if (s.next_run != s.n_runs()) throw ParameterError("normal blocks: not every block was added");
  const NormalPattern& p = *s.pattern;
  const std::size_t n = p.n, nb = s.nb;
  s.make_values();
  // The entries below the diagonal copied from their mirrors, in ranges of rows on the core's threads.
  const int tasks = detail::task_count(p.indices.size(), kEntriesPerTask);
  detail::for_each_index(tasks > 1, tasks, n, [&](std::size_t j) {
    for (auto e = static_cast<std::size_t>(p.indptr[j]); e < static_cast<std::size_t>(p.diagonal[j]); ++e)
      std::copy_n(&s.values[static_cast<std::size_t>(p.mirror[e]) * nb], nb, &s.values[e * nb]);
  });
  NormalMatrix M;
  M.n = n;
  M.blocks = static_cast<int>(nb);
  M.indptr = p.indptr;
  M.indices = p.indices;
  M.values = std::move(s.values);
  if (rhs != nullptr) std::copy(s.rhs.begin(), s.rhs.end(), rhs);
  return M;
}

NormalMatrix normal_matrix(const CsrMatrix& rows, const double* weights, int weight_count) {
  return normal_matrix(CsrRows{rows.n_rows, rows.n_cols, rows.indptr.data(), rows.indices.data(), rows.data.data()},
                       weights, weight_count);
}

NormalMatrix normal_matrix(const CsrRows& A, const double* weights, int weight_count, const double* x,
                           double* rhs) {
  const std::size_t k = A.n_rows;
  // Runs of consecutive rows with the same columns: their entries are a dense block (rows, width) in place.
  std::vector<std::size_t> run_start;
  for (std::size_t r = 0; r < k; ++r) {
    const bool same = r > 0 && A.indptr[r + 1] - A.indptr[r] == A.indptr[r] - A.indptr[r - 1] &&
                      std::equal(A.indices + A.indptr[r], A.indices + A.indptr[r + 1], A.indices + A.indptr[r - 1]);
    if (!same) run_start.push_back(r);
  }
  run_start.push_back(k);
  const std::size_t n_runs = run_start.size() - 1;
  std::vector<std::int64_t> offsets(n_runs + 1, 0);
  std::vector<std::int32_t> columns;
  for (std::size_t q = 0; q < n_runs; ++q) {
    columns.insert(columns.end(), A.indices + A.indptr[run_start[q]], A.indices + A.indptr[run_start[q] + 1]);
    offsets[q + 1] = static_cast<std::int64_t>(columns.size());
  }
  NormalBlocks blocks(A.n_cols, weight_count, std::move(offsets), std::move(columns));
  const bool with_rhs = x != nullptr && rhs != nullptr;
  const auto nb = static_cast<std::size_t>(weight_count);
  const int tasks = detail::task_count(static_cast<std::size_t>(A.indptr[k]), kRowEntriesPerTask);
  detail::for_each_index(tasks > 1, tasks, n_runs, [&](std::size_t q) {
    const std::size_t r0 = run_start[q], r1 = run_start[q + 1];
    blocks.add(q, A.data + A.indptr[r0], r1 - r0, weights == nullptr ? nullptr : weights + nb * r0,
               with_rhs ? x + 3 * r0 : nullptr);
  });
  return blocks.finish(with_rhs ? rhs : nullptr);
}

void blend_weights(const double* points, const double* normals, const double* row_weights, std::size_t k,
                   double tangential, double* weights, double* weighted_points) {
  for (std::size_t r = 0; r < k; ++r) {
    const double* nr = normals + 3 * r;
    const double* pr = points + 3 * r;
    const double w = row_weights == nullptr ? 1.0 : row_weights[r];
    const bool normal = nr[0] * nr[0] + nr[1] * nr[1] + nr[2] * nr[2] > 0.0;  // false for zero and NaN
    const double c = normal ? (1.0 - tangential) * w : 0.0;                     // the n n^T part
    const double d = normal ? tangential * w : w;                               // the identity part
    const double n0 = normal ? nr[0] : 0.0, n1 = normal ? nr[1] : 0.0, n2 = normal ? nr[2] : 0.0;
    double* out = weights + 6 * r;
    out[0] = c * n0 * n0 + d;
    out[1] = c * n0 * n1;
    out[2] = c * n0 * n2;
    out[3] = c * n1 * n1 + d;
    out[4] = c * n1 * n2;
    out[5] = c * n2 * n2 + d;
    const double np = c * (n0 * pr[0] + n1 * pr[1] + n2 * pr[2]);
    weighted_points[3 * r] = d * pr[0] + np * n0;
    weighted_points[3 * r + 1] = d * pr[1] + np * n1;
    weighted_points[3 * r + 2] = d * pr[2] + np * n2;
  }
}

NormalEquations::NormalEquations(NormalMatrix normal, CsrMatrix fairness_matrix, double fairness, double proximal)
    : n_(std::move(normal)), k_(std::move(fairness_matrix)) {
  if (n_.blocks != 1 && n_.blocks != 6)
    throw ParameterError("the normal matrix must have 1 or 6 values per entry, got " + std::to_string(n_.blocks));
  if (k_.n_rows != 0 && (k_.n_rows != n_.n || k_.n_cols != n_.n))
    throw ParameterError("the fairness matrix is " + std::to_string(k_.n_rows) + " x " + std::to_string(k_.n_cols) +
                         " but the cage has " + std::to_string(n_.n) + " vertices");
  const auto nb = static_cast<std::size_t>(n_.blocks);
  // Each row's diagonal entry (its trace for blocks) found on the core's threads, summed in row order after, as
  // the sum over the entries in order; a row with two (a pattern with repeats) makes that sum run as it is.
  const auto diagonal_term = [&](std::size_t p) {
    const double* v = &n_.values[p * nb];
    return nb == 1 ? v[0] : v[0] + v[3] + v[5];
  };
  std::vector<std::int64_t> diagonal_at(n_.n, -1);  // per row: its diagonal entry, -1 for none, -2 for several
  const int tasks = detail::task_count(n_.indices.size(), kEntriesPerTask);
  detail::for_each_index(tasks > 1, tasks, n_.n, [&](std::size_t i) {
    for (std::int64_t p = n_.indptr[i]; p < n_.indptr[i + 1]; ++p)
      if (static_cast<std::size_t>(n_.indices[static_cast<std::size_t>(p)]) == i)
        diagonal_at[i] = diagonal_at[i] == -1 ? p : -2;
  });
  double sum = 0.0;
  if (std::find(diagonal_at.begin(), diagonal_at.end(), -2) == diagonal_at.end()) {
    for (const std::int64_t p : diagonal_at)
      if (p >= 0) sum += diagonal_term(static_cast<std::size_t>(p));
  } else {
    for (std::size_t i = 0; i < n_.n; ++i)
      for (std::int64_t p = n_.indptr[i]; p < n_.indptr[i + 1]; ++p)
        if (static_cast<std::size_t>(n_.indices[static_cast<std::size_t>(p)]) == i)
          sum += diagonal_term(static_cast<std::size_t>(p));
  }
  const double per = static_cast<double>(n_.n) * (nb == 1 ? 1.0 : 3.0);
  mean_diagonal_ = n_.n > 0 && sum != 0.0 ? sum / per : 1.0;
  mu_ = proximal * mean_diagonal_;
  c_ = fairness * mean_diagonal_;
}

void NormalEquations::apply(const double* x, double* out, int threads) const {
  const std::size_t n = n_.n;
  const std::size_t entries = n_.indices.size() + k_.indices.size();
  const int tasks = static_cast<int>(std::clamp<std::size_t>(entries / kEntriesPerTask, 1,
                                                             static_cast<std::size_t>(std::max(threads, 1))));
  const bool blocks = n_.blocks == 6;
  const bool has_k = k_.n_rows != 0;
  detail::for_each_index(tasks > 1, tasks, n, [&](std::size_t i) {
    double s0 = mu_ * x[3 * i], s1 = mu_ * x[3 * i + 1], s2 = mu_ * x[3 * i + 2];
    for (std::int64_t p = n_.indptr[i]; p < n_.indptr[i + 1]; ++p) {
      const auto up = static_cast<std::size_t>(p);
      const double* xj = x + 3 * static_cast<std::size_t>(n_.indices[up]);
      if (!blocks) {
        const double w = n_.values[up];
        s0 += w * xj[0];
        s1 += w * xj[1];
        s2 += w * xj[2];
        continue;
      }
      const double* b = &n_.values[6 * up];  // xx, xy, xz, yy, yz, zz
      s0 += b[0] * xj[0] + b[1] * xj[1] + b[2] * xj[2];
      s1 += b[1] * xj[0] + b[3] * xj[1] + b[4] * xj[2];
      s2 += b[2] * xj[0] + b[4] * xj[1] + b[5] * xj[2];
    }
    if (has_k) {
      double k0 = 0.0, k1 = 0.0, k2 = 0.0;
      for (std::int32_t p = k_.indptr[i]; p < k_.indptr[i + 1]; ++p) {
        const double w = k_.data[static_cast<std::size_t>(p)];
        const double* xj = x + 3 * static_cast<std::size_t>(k_.indices[static_cast<std::size_t>(p)]);
        k0 += w * xj[0];
        k1 += w * xj[1];
        k2 += w * xj[2];
      }
      s0 += c_ * k0;
      s1 += c_ * k1;
      s2 += c_ * k2;
    }
    out[3 * i] = s0;
    out[3 * i + 1] = s1;
    out[3 * i + 2] = s2;
  });
}

PcgResult NormalEquations::solve(const double* rhs, double* x, double rtol, long long max_iter, int threads) const {
  if (threads < 1) threads = detail::available_processors();
  const std::size_t n = n_.n;
  const bool blocks = n_.blocks == 6;
  // The diagonal (blocks) of the whole matrix, inverted.
  BlockDiagonal precondition;
  (blocks ? precondition.blocks : precondition.scalars).assign(blocks ? 9 * n : n, 0.0);
  // Each row's on its own: on the core's threads.
  const std::size_t entries = n_.indices.size() + k_.indices.size();
  const int tasks = static_cast<int>(std::clamp<std::size_t>(entries / kEntriesPerTask, 1,
                                                             static_cast<std::size_t>(std::max(threads, 1))));
  detail::for_each_index(tasks > 1, tasks, n, [&](std::size_t i) {
    double shift = mu_;
    if (k_.n_rows != 0) {
      const auto* first = k_.indices.data() + k_.indptr[i];
      const auto* last = k_.indices.data() + k_.indptr[i + 1];
      const auto* it = std::lower_bound(first, last, static_cast<std::int32_t>(i));
      if (it != last && static_cast<std::size_t>(*it) == i)
        shift += c_ * k_.data[static_cast<std::size_t>(it - k_.indices.data())];
    }
    double d[6] = {shift, 0.0, 0.0, shift, 0.0, shift};
    for (std::int64_t p = n_.indptr[i]; p < n_.indptr[i + 1]; ++p)
      if (static_cast<std::size_t>(n_.indices[static_cast<std::size_t>(p)]) == i) {
        const double* v = &n_.values[static_cast<std::size_t>(p) * static_cast<std::size_t>(n_.blocks)];
        if (!blocks) {
          d[0] += v[0];
        } else {
          for (int c = 0; c < 6; ++c) d[c] += v[c];
        }
      }
    if (!blocks) {
      precondition.scalars[i] = d[0] > 0.0 ? 1.0 / d[0] : 1.0;
      return;
    }
    // The inverse of the symmetric block [[a, b, c], [b, e, f], [c, f, g]] by its adjugate.
    const double a = d[0], b = d[1], c = d[2], e = d[3], f = d[4], g = d[5];
    const double A00 = e * g - f * f, A01 = c * f - b * g, A02 = b * f - c * e;
    const double A11 = a * g - c * c, A12 = b * c - a * f, A22 = a * e - b * b;
    const double det = a * A00 + b * A01 + c * A02;
    double* inv = &precondition.blocks[9 * i];
    if (det > 0.0 && std::isfinite(det)) {
      const double s = 1.0 / det;
      const double m[9] = {A00, A01, A02, A01, A11, A12, A02, A12, A22};
      for (int q = 0; q < 9; ++q) inv[q] = s * m[q];
    } else {  // not positive definite in rounding: the diagonal alone
      inv[0] = a > 0.0 ? 1.0 / a : 1.0;
      inv[4] = e > 0.0 ? 1.0 / e : 1.0;
      inv[8] = g > 0.0 ? 1.0 / g : 1.0;
    }
  });
  std::vector<double> xv(x, x + 3 * n), r(3 * n);
  apply(xv.data(), r.data(), threads);
  for (std::size_t i = 0; i < 3 * n; ++i) r[i] = rhs[i] - r[i];
  // The stop: each system's residual norm below rtol times its start's, or 1e-15 times its right-hand side's.
  const std::size_t systems = blocks ? 1 : 3;
  std::vector<double> limit(systems, 0.0), rhs2(systems, 0.0);
  for (std::size_t i = 0; i < 3 * n; ++i) {
    limit[blocks ? 0 : i % 3] += r[i] * r[i];
    rhs2[blocks ? 0 : i % 3] += rhs[i] * rhs[i];
  }
  for (std::size_t s = 0; s < systems; ++s)
    limit[s] = std::max(rtol * std::sqrt(limit[s]), 1e-15 * std::sqrt(rhs2[s]));
  const auto stop = [&](const PcgProgress& progress) -> std::string {
    for (std::size_t s = 0; s < systems; ++s)
      if (progress.active[s] && std::sqrt(progress.rr[s]) > limit[s]) return {};
    return "converged";
  };
  const PcgResult out = pcg(
      n, 3, blocks, [&](const std::vector<double>& p, std::vector<double>& q) { apply(p.data(), q.data(), threads); },
      precondition, stop, xv, r, max_iter, threads);
  std::copy(xv.begin(), xv.end(), x);
  return out;
}

}  // namespace sorpia
