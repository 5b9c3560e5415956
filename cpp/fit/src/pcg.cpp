#include "sorpia/pcg.hpp"

#include <algorithm>
#include <functional>
#include <stdexcept>
#include <type_traits>

#include "sorpia/detail/parallel.hpp"
#include "sorpia/interrupt.hpp"

namespace sorpia {

namespace {

// Rows of X per chunk of the vector updates (a thread takes whole chunks: fewer rows run on one thread).
constexpr std::size_t kRowsPerTask = 50000;

// pcg with KC columns known at compile time (0: `columns`, known at run time).
template <int KC>
PcgResult pcg_impl(std::size_t n, int columns, bool coupled, const PcgApply& apply, const BlockDiagonal& precondition,
                   const PcgStop& stop, std::vector<double>& x, std::vector<double>& r, long long max_iter,
                   int threads) {
  const std::size_t kc = KC > 0 ? static_cast<std::size_t>(KC) : static_cast<std::size_t>(columns);
  const bool blocks = precondition.scalars.empty();
  const std::size_t systems = coupled ? 1 : kc;
  // The rows in chunks of a count that does not depend on the threads, each chunk's part of the sums kept and
  // the parts summed in chunk order: the same rounding on any number of threads.
  const std::size_t chunks = std::max<std::size_t>(1, n / kRowsPerTask);
  const int tasks = static_cast<int>(std::min<std::size_t>(chunks, static_cast<std::size_t>(std::max(threads, 1))));
  const auto for_chunks = [&](const std::function<void(std::size_t)>& body) {
    detail::for_each_task(tasks > 1, tasks, [&](int t) {
      const auto k = static_cast<std::size_t>(t), count = static_cast<std::size_t>(tasks);
      for (std::size_t ch = chunks * k / count; ch < chunks * (k + 1) / count; ++ch) body(ch);
    });
  };
  const auto range = [&](std::size_t ch) {
    return std::pair<std::size_t, std::size_t>{n * ch / chunks, n * (ch + 1) / chunks};
  };
  std::vector<double> z(n * kc), p, q(n * kc);
  // Per chunk and column: r^T z and r^T r (rows 2 ch and 2 ch + 1 of kc entries).
  std::vector<double> part(chunks * 2 * kc);
  // For chunk ch's rows: x += alpha p and r -= alpha q (with `step`), z = P r, and the chunk's sums; one pass.
  std::vector<double> col_alpha(kc, 0.0), col_beta(kc, 0.0);
  const auto step_kernel = [&](std::size_t ch, auto step_tag, auto blocks_tag) {
    constexpr bool step = decltype(step_tag)::value;
    constexpr bool blocks = decltype(blocks_tag)::value;
    const auto [first, last] = range(ch);
    double* rz = &part[2 * ch * kc];
    double* rr = rz + kc;
    std::fill(rz, rr + kc, 0.0);
    for (std::size_t i = first; i < last; ++i) {
      double* ri = &r[i * kc];
      double* zi = &z[i * kc];
      if constexpr (step) {
        double* xi = &x[i * kc];
        const double* pi = &p[i * kc];
        const double* qi = &q[i * kc];
        for (std::size_t c = 0; c < kc; ++c) {
          xi[c] += col_alpha[c] * pi[c];
          ri[c] -= col_alpha[c] * qi[c];
        }
      }
      if constexpr (!blocks) {
        for (std::size_t c = 0; c < kc; ++c) zi[c] = precondition.scalars[i] * ri[c];
      } else {
        const double* b = &precondition.blocks[i * kc * kc];
        for (std::size_t c = 0; c < kc; ++c) {
          double sum = 0.0;
          for (std::size_t d = 0; d < kc; ++d) sum += b[c * kc + d] * ri[d];
          zi[c] = sum;
        }
      }
      for (std::size_t c = 0; c < kc; ++c) {
        rz[c] += ri[c] * zi[c];
        rr[c] += ri[c] * ri[c];
      }
    }
  };
  const auto step_rows = [&](std::size_t ch, bool step) {
    using Yes = std::true_type;
    using No = std::false_type;
    if (step) {
      if (blocks) step_kernel(ch, Yes{}, Yes{}); else step_kernel(ch, Yes{}, No{});
    } else {
      if (blocks) step_kernel(ch, No{}, Yes{}); else step_kernel(ch, No{}, No{});
    }
  };
  // The chunks' sums, in chunk order, folded into the systems.
  const auto sum_parts = [&](std::vector<double>& rz, std::vector<double>& rr) {
    std::fill(rz.begin(), rz.end(), 0.0);
    std::fill(rr.begin(), rr.end(), 0.0);
    for (std::size_t ch = 0; ch < chunks; ++ch)
      for (std::size_t c = 0; c < kc; ++c) {
        rz[coupled ? 0 : c] += part[2 * ch * kc + c];
        rr[coupled ? 0 : c] += part[(2 * ch + 1) * kc + c];
      }
  };

  PcgProgress progress;
  progress.rz.assign(systems, 0.0);
  progress.rr.assign(systems, 0.0);
  progress.decrease.assign(systems, 0.0);
  progress.active.assign(systems, 0);
  for_chunks([&](std::size_t ch) { step_rows(ch, false); });
  sum_parts(progress.rz, progress.rr);
  for (std::size_t s = 0; s < systems; ++s) progress.active[s] = progress.rz[s] > 0.0;
  p = z;

  std::vector<double> pq(systems), col_pq(kc), rz_new(systems), rr_new(systems);
  std::vector<char> col_update(kc);
  PcgResult out;
  out.stop_reason = "max_iter";
  for (long long k = 0;; ++k) {
    progress.iteration = k;
    std::string reason = stop(progress);
    if (std::none_of(progress.active.begin(), progress.active.end(), [](char a) { return a != 0; }))
      reason = "exact";
    if (!reason.empty()) {
      out.stop_reason = std::move(reason);
      break;
    }
    if (k >= max_iter) break;
    poll_interrupt();
    apply(p, q);
    std::fill(col_pq.begin(), col_pq.end(), 0.0);
    for (std::size_t i = 0; i < n; ++i)
      for (std::size_t c = 0; c < kc; ++c) col_pq[c] += p[i * kc + c] * q[i * kc + c];
    std::fill(pq.begin(), pq.end(), 0.0);
    for (std::size_t c = 0; c < kc; ++c) pq[coupled ? 0 : c] += col_pq[c];
    for (std::size_t s = 0; s < systems; ++s) {
      progress.decrease[s] = 0.0;
      if (!progress.active[s]) continue;
      if (!(pq[s] > 0.0)) {  // no descent left along p (the semidefinite case, or rounding)
        progress.active[s] = 0;
        continue;
      }
      progress.decrease[s] = progress.rz[s] / pq[s] * progress.rz[s];
    }
    for (std::size_t c = 0; c < kc; ++c) {
      const std::size_t s = coupled ? 0 : c;
      col_alpha[c] = progress.active[s] ? progress.rz[s] / pq[s] : 0.0;
    }
    for_chunks([&](std::size_t ch) { step_rows(ch, true); });
    sum_parts(rz_new, rr_new);
    for (std::size_t s = 0; s < systems; ++s) {
      progress.rr[s] = rr_new[s];
      if (!progress.active[s]) continue;
      if (!(rz_new[s] > 0.0)) {
        progress.active[s] = 0;
        progress.rz[s] = 0.0;
        continue;
      }
      const double beta = rz_new[s] / progress.rz[s];
      for (std::size_t c = 0; c < kc; ++c)
        if (coupled || c == s) col_beta[c] = beta;
      progress.rz[s] = rz_new[s];
    }
    for (std::size_t c = 0; c < kc; ++c) col_update[c] = progress.active[coupled ? 0 : c];
    for_chunks([&](std::size_t ch) {
      const auto [first, last] = range(ch);
      for (std::size_t i = first; i < last; ++i)
        for (std::size_t c = 0; c < kc; ++c)
          if (col_update[c]) p[i * kc + c] = z[i * kc + c] + col_beta[c] * p[i * kc + c];
    });
    out.iterations = k + 1;
  }
  return out;
}

}  // namespace

PcgResult pcg(std::size_t n, int columns, bool coupled, const PcgApply& apply, const BlockDiagonal& precondition,
              const PcgStop& stop, std::vector<double>& x, std::vector<double>& r, long long max_iter, int threads) {
  const auto kc = static_cast<std::size_t>(columns);
  if (columns < 1 || x.size() != n * kc || r.size() != n * kc)
    throw std::invalid_argument("pcg: x and r must have n * columns entries");
  if (precondition.scalars.empty() ? precondition.blocks.size() != n * kc * kc : precondition.scalars.size() != n)
    throw std::invalid_argument("pcg: the preconditioner has the wrong size");
  if (columns == 3) return pcg_impl<3>(n, columns, coupled, apply, precondition, stop, x, r, max_iter, threads);
  return pcg_impl<0>(n, columns, coupled, apply, precondition, stop, x, r, max_iter, threads);
}

}  // namespace sorpia
