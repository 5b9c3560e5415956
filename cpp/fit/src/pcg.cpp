#include "sorpia/pcg.hpp"

#include <algorithm>
#include <functional>
#include <stdexcept>

#include "sorpia/detail/parallel.hpp"
#include "sorpia/interrupt.hpp"

namespace sorpia {

namespace {

// Rows of X per task of a vector update below which it runs on one thread.
constexpr std::size_t kRowsPerTask = 50000;

}  // namespace

PcgResult pcg(std::size_t n, int columns, bool coupled, const PcgApply& apply, const BlockDiagonal& precondition,
              const PcgStop& stop, std::vector<double>& x, std::vector<double>& r, long long max_iter, int threads) {
  const auto kc = static_cast<std::size_t>(columns);
  if (columns < 1 || x.size() != n * kc || r.size() != n * kc)
    throw std::invalid_argument("pcg: x and r must have n * columns entries");
  const bool blocks = precondition.scalars.empty();
  if (blocks ? precondition.blocks.size() != n * kc * kc : precondition.scalars.size() != n)
    throw std::invalid_argument("pcg: the preconditioner has the wrong size");
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
  // z_i = P_i r_i for the rows [first, last).
  const auto precondition_rows = [&](std::size_t first, std::size_t last, std::vector<double>& z) {
    for (std::size_t i = first; i < last; ++i) {
      const double* ri = &r[i * kc];
      double* zi = &z[i * kc];
      if (!blocks) {
        for (std::size_t c = 0; c < kc; ++c) zi[c] = precondition.scalars[i] * ri[c];
        continue;
      }
      const double* b = &precondition.blocks[i * kc * kc];
      for (std::size_t c = 0; c < kc; ++c) {
        double s = 0.0;
        for (std::size_t d = 0; d < kc; ++d) s += b[c * kc + d] * ri[d];
        zi[c] = s;
      }
    }
  };
  // Per chunk: (r^T z, r^T r) per system.
  std::vector<double> part(chunks * 2 * systems);
  const auto sum_parts = [&](std::vector<double>& rz, std::vector<double>& rr) {
    std::fill(rz.begin(), rz.end(), 0.0);
    std::fill(rr.begin(), rr.end(), 0.0);
    for (std::size_t t = 0; t < chunks; ++t)
      for (std::size_t s = 0; s < systems; ++s) {
        rz[s] += part[(2 * t) * systems + s];
        rr[s] += part[(2 * t + 1) * systems + s];
      }
  };
  const auto range = [&](std::size_t ch) { return std::pair<std::size_t, std::size_t>{n * ch / chunks, n * (ch + 1) / chunks}; };

  PcgProgress progress;
  progress.rz.assign(systems, 0.0);
  progress.rr.assign(systems, 0.0);
  progress.decrease.assign(systems, 0.0);
  progress.active.assign(systems, 0);
  std::vector<double> z(n * kc), p, q(n * kc);
  // z = P r on chunk t's rows, and its part of r^T z and r^T r.
  const auto precondition_part = [&](std::size_t t) {
    const auto [first, last] = range(t);
    precondition_rows(first, last, z);
    double* rz = &part[2 * t * systems];
    double* rr = rz + systems;
    std::fill(rz, rr + systems, 0.0);
    for (std::size_t i = first; i < last; ++i)
      for (std::size_t c = 0; c < kc; ++c) {
        const std::size_t s = coupled ? 0 : c;
        rz[s] += r[i * kc + c] * z[i * kc + c];
        rr[s] += r[i * kc + c] * r[i * kc + c];
      }
  };
  for_chunks(precondition_part);
  sum_parts(progress.rz, progress.rr);
  for (std::size_t s = 0; s < systems; ++s) progress.active[s] = progress.rz[s] > 0.0;
  p = z;

  std::vector<double> alpha(systems), beta(systems), pq(systems), rz_new(systems), rr_new(systems);
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
    std::fill(pq.begin(), pq.end(), 0.0);
    for (std::size_t i = 0; i < n * kc; ++i) pq[coupled ? 0 : i % kc] += p[i] * q[i];
    for (std::size_t s = 0; s < systems; ++s) {
      alpha[s] = 0.0;
      progress.decrease[s] = 0.0;
      if (!progress.active[s]) continue;
      if (!(pq[s] > 0.0)) {  // no descent left along p (the semidefinite case, or rounding)
        progress.active[s] = 0;
        continue;
      }
      alpha[s] = progress.rz[s] / pq[s];
      progress.decrease[s] = alpha[s] * progress.rz[s];
    }
    // x += alpha p, r -= alpha q, z = P r, r^T z and r^T r: chunk by chunk, each over its own rows.
    for_chunks([&](std::size_t t) {
      const auto [first, last] = range(t);
      for (std::size_t i = first; i < last; ++i)
        for (std::size_t c = 0; c < kc; ++c) {
          const double a = alpha[coupled ? 0 : c];
          x[i * kc + c] += a * p[i * kc + c];
          r[i * kc + c] -= a * q[i * kc + c];
        }
      precondition_part(t);
    });
    sum_parts(rz_new, rr_new);
    for (std::size_t s = 0; s < systems; ++s) {
      beta[s] = 0.0;
      progress.rr[s] = rr_new[s];
      if (!progress.active[s]) continue;
      if (!(rz_new[s] > 0.0)) {
        progress.active[s] = 0;
        progress.rz[s] = 0.0;
        continue;
      }
      beta[s] = rz_new[s] / progress.rz[s];
      progress.rz[s] = rz_new[s];
    }
    for (std::size_t i = 0; i < n; ++i)
      for (std::size_t c = 0; c < kc; ++c) {
        const std::size_t s = coupled ? 0 : c;
        if (progress.active[s]) p[i * kc + c] = z[i * kc + c] + beta[s] * p[i * kc + c];
      }
    out.iterations = k + 1;
  }
  return out;
}

}  // namespace sorpia
