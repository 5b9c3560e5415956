// Spectral estimates for the solver parameters (W-PIA's sigma, Young's omega,
// HSS's alpha) on one scalar field (a third of the work of a vertex product):
// Lanczos for the extreme eigenvalues of B and of H, which are self-adjoint
// in a weighted inner product; the power method for the Jacobi radius.
// Both poll for an interrupt once per product: an interrupted estimate leaves
// its cache entry unset.
#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdint>
#include <limits>
#include <vector>

#include "sorpia/detail/half_edges.hpp"
#include "solver_detail.hpp"
#include "sorpia/solvers.hpp"

namespace sorpia {
namespace {

using clock = std::chrono::steady_clock;

// Deterministic start vector with components along every eigenvector (almost
// surely): a SplitMix64 stream mapped to [-1, 1].
std::vector<double> start_vector(std::size_t n) {
  std::vector<double> x(n);
  std::uint64_t s = 0x9E3779B97F4A7C15ull;
  for (auto& e : x) {
    std::uint64_t z = (s += 0x9E3779B97F4A7C15ull);
    z = (z ^ (z >> 30)) * 0xBF58476D1CE4E5B9ull;
    z = (z ^ (z >> 27)) * 0x94D049BB133111EBull;
    z ^= z >> 31;
    e = static_cast<double>(z >> 11) * (2.0 / 9007199254740992.0) - 1.0;
  }
  return x;
}

// The symmetric tridiagonal matrix T_k of the Lanczos recurrence: diagonal a,
// off-diagonal b (b[i] couples rows i and i + 1).
struct Tridiagonal {
  std::vector<double> a, b;

  // Number of eigenvalues below t (Sturm sequence of the LDL^T pivots).
  std::size_t count_below(double t) const {
    std::size_t count = 0;
    double d = 1.0;
    for (std::size_t i = 0; i < a.size(); ++i) {
      const double off = i ? b[i - 1] * b[i - 1] / d : 0.0;
      d = a[i] - t - off;
      if (d == 0.0) d = -std::numeric_limits<double>::min();
      count += d < 0.0;
    }
    return count;
  }

  // {smallest, largest} eigenvalue, by bisection inside the Gershgorin interval.
  std::pair<double, double> extremes() const {
    double lo = a[0], hi = a[0];
    for (std::size_t i = 0; i < a.size(); ++i) {
      const double r = (i ? std::abs(b[i - 1]) : 0.0) + (i < b.size() ? std::abs(b[i]) : 0.0);
      lo = std::min(lo, a[i] - r);
      hi = std::max(hi, a[i] + r);
    }
    const std::size_t k = a.size();
    // The eigenvalue of rank `want` (0-based) lies where count_below passes
    // want; halve [l, h] down to a few ulps (at most 200 halvings).
    constexpr double eps = std::numeric_limits<double>::epsilon();
    auto bisect = [&](std::size_t want) {
      double l = lo, h = hi;
      for (int it = 0; it < 200 && h - l > 4.0 * eps * std::max(std::abs(l), std::abs(h)); ++it) {
        const double m = 0.5 * (l + h);
        (count_below(m) > want ? h : l) = m;
      }
      return 0.5 * (l + h);
    };
    return {bisect(0), bisect(k - 1)};
  }
};

// Lanczos for the extreme eigenvalues of A, self-adjoint in the inner product
// <x, y> = sum_i w_i x_i y_i. After each product the extreme eigenvalues of
// T_k (Ritz values: inside A's spectral interval, moving outwards with k)
// give the pair `tracked(lo, hi)`; the run stops when neither component
// changes by more than rtol times its size on two products in a row (after
// min_products at least), at max_products, or when the Krylov space is
// invariant (the Ritz values are then exact). The floor guards against an
// eigenvector the start vector barely holds: the extreme Ritz value then rests
// near the next eigenvalue for a few products before it moves on (a 7 x 6
// grid does this around product 15). No reorthogonalisation: lost
// orthogonality repeats converged Ritz values but does not move the extreme
// ones. The Lanczos vector q_k is kept unnormalised, q_k = u / scale, so that
// each product costs two passes over the vectors besides A itself.
template <class ApplyA, class Tracked>
std::pair<double, double> lanczos_extremes(std::size_t n, ApplyA apply_a, const std::vector<double>& w,
                                           int max_products, double rtol, Tracked tracked) {
  std::vector<double> u = start_vector(n), u_prev(n, 0.0), au(n);
  double uu = 0.0;
  for (std::size_t i = 0; i < n; ++i) uu += w[i] * u[i] * u[i];
  if (uu == 0.0) return {0.0, 0.0};
  double scale = std::sqrt(uu), scale_prev = 1.0, beta_prev = 0.0;
  Tridiagonal t;
  std::pair<double, double> ends{0.0, 0.0}, prev{NAN, NAN};
  const auto settled = [rtol](double now, double before) { return std::abs(now - before) <= rtol * std::abs(now); };
  constexpr int min_products = 40;
  int calm = 0;
  for (int k = 0; k < max_products; ++k) {
    poll_interrupt();
    apply_a(u.data(), au.data());
    double uau = 0.0;
    for (std::size_t i = 0; i < n; ++i) uau += w[i] * u[i] * au[i];
    const double alpha = uau / (scale * scale);
    // r = A q_k - alpha q_k - beta_{k-1} q_{k-1}, written over u_prev.
    const double ca = 1.0 / scale, cu = -alpha / scale, cp = -beta_prev / scale_prev;
    double rr = 0.0;
    for (std::size_t i = 0; i < n; ++i) {
      const double r = ca * au[i] + cu * u[i] + cp * u_prev[i];
      u_prev[i] = r;
      rr += w[i] * r * r;
    }
    t.a.push_back(alpha);
    ends = t.extremes();
    const std::pair<double, double> now = tracked(ends.first, ends.second);
    calm = settled(now.first, prev.first) && settled(now.second, prev.second) ? calm + 1 : 0;
    prev = now;
    const double beta = std::sqrt(rr);
    const bool invariant = beta <= 1e-14 * std::max(std::abs(ends.first), std::abs(ends.second));
    if ((k + 1 >= min_products && calm >= 2) || invariant) break;
    t.b.push_back(beta);
    // q_{k+1} = r / beta: r's storage becomes u, u's becomes u_prev.
    std::swap(u, u_prev);
    scale_prev = scale;
    scale = beta;
    beta_prev = beta;
  }
  return ends;
}

double wnorm(const std::vector<double>& x, const std::vector<double>& w) {
  double s = 0.0;
  for (std::size_t i = 0; i < x.size(); ++i) s += w[i] * x[i] * x[i];
  return std::sqrt(s);
}

// Power method for the spectral radius of A: the ratio ||A x|| / ||x|| in the
// W-weighted norm (W makes A self-adjoint where it can, so the ratio rises
// monotonically to the radius), until it changes by less than rtol.
template <class ApplyA>
double power_radius(std::size_t n, ApplyA apply_a, const std::vector<double>& w, int max_products, double rtol) {
  std::vector<double> x = start_vector(n), y(n);
  double nx = wnorm(x, w);
  if (nx == 0.0) return 0.0;
  for (auto& e : x) e /= nx;
  double est = 0.0;
  for (int k = 0; k < max_products; ++k) {
    poll_interrupt();
    apply_a(x.data(), y.data());
    const double ny = wnorm(y, w);
    const double prev = est;
    est = ny;
    if (ny == 0.0) break;
    for (std::size_t i = 0; i < n; ++i) x[i] = y[i] / ny;
    if (k > 5 && std::abs(est - prev) <= rtol * est) break;
  }
  return est;
}

// Entries (i, j) of B whose mirror (j, i) is not stored, as (row, column):
// on a mesh with boundary, interior rows reading boundary vertices and
// boundary rows reading one-face corners kept as corners. Ordering the
// vertices as [no neighbours, boundary, interior] makes B block lower
// triangular with exactly these entries below the diagonal blocks, and each
// diagonal block is Gamma Upsilon with Upsilon symmetric. So B's spectrum is
// that of B with these entries dropped, which is self-adjoint in the Gamma^-1
// inner product. Empty when is_symmetrisable(op).
struct OneWay {
  std::int32_t row, entry, column;  // entry: the index into op.neighbors
};
std::vector<OneWay> one_way_entries(const LimitOperator& op) {
  std::vector<OneWay> e;
  for (std::size_t i = 0; i < op.n; ++i)
    for (std::int32_t p = op.offsets[i]; p < op.offsets[i + 1]; ++p) {
      const std::int32_t j = op.neighbors[p];
      const auto* first = op.neighbors.data() + op.offsets[j];
      const auto* last = op.neighbors.data() + op.offsets[j + 1];
      if (std::find(first, last, static_cast<std::int32_t>(i)) == last)
        e.push_back({static_cast<std::int32_t>(i), p, j});
    }
  return e;
}

// Whether B's spectrum is that of B without its one-way entries: when no
// one-way entry lies on a cycle of B's pattern, B is block lower triangular
// (ordered by the classes of its two-way entries, upstream first) with these
// entries below the diagonal blocks. True on Loop meshes without tags (the
// order above); false where an infinitely sharp crease ends in a dart: the
// crease vertices are read one way by their smooth neighbours, which reach
// them back through the dart.
bool one_way_entries_below_blocks(const LimitOperator& op, const std::vector<OneWay>& one_way_list) {
  if (one_way_list.empty()) return true;
  std::vector<std::pair<std::int32_t, std::int32_t>> one_way;  // (row, column)
  for (const OneWay& e : one_way_list) one_way.emplace_back(e.row, e.column);
  detail::DisjointSets two_way(op.n);
  std::vector<std::pair<std::int32_t, std::int32_t>> sorted_one_way(one_way);
  std::sort(sorted_one_way.begin(), sorted_one_way.end());
  for (std::size_t i = 0; i < op.n; ++i)
    for (std::int32_t p = op.offsets[i]; p < op.offsets[i + 1]; ++p) {
      const std::pair<std::int32_t, std::int32_t> e{static_cast<std::int32_t>(i), op.neighbors[p]};
      if (!std::binary_search(sorted_one_way.begin(), sorted_one_way.end(), e)) two_way.unite(e.first, e.second);
    }
  // Kahn's topological sort of the classes along the one-way entries.
  std::vector<std::int32_t> indegree(op.n, 0), out_offsets(op.n + 1, 0), out;
  for (const auto& [i, j] : one_way) {
    const std::int32_t a = two_way.find(i), b = two_way.find(j);
    if (a == b) return false;
    ++out_offsets[a + 1];
    ++indegree[b];
  }
  for (std::size_t k = 0; k < op.n; ++k) out_offsets[k + 1] += out_offsets[k];
  out.resize(one_way.size());
  std::vector<std::int32_t> fill(out_offsets.begin(), out_offsets.end() - 1), ready;
  for (const auto& [i, j] : one_way) out[fill[two_way.find(i)]++] = two_way.find(j);
  for (std::size_t k = 0; k < op.n; ++k)
    if (two_way.find(static_cast<std::int32_t>(k)) == static_cast<std::int32_t>(k) && indegree[k] == 0)
      ready.push_back(static_cast<std::int32_t>(k));
  std::size_t removed = 0;
  while (!ready.empty()) {
    const std::int32_t a = ready.back();
    ready.pop_back();
    for (std::int32_t p = out_offsets[a]; p < out_offsets[a + 1]; ++p) {
      ++removed;
      if (--indegree[out[p]] == 0) ready.push_back(out[p]);
    }
  }
  return removed == one_way.size();
}

// y = B_s x: B x without the one-way entries.
struct SelfAdjointPart {
  const LimitOperator& op;
  std::vector<OneWay> one_way = one_way_entries(op);
  void operator()(const double* x, double* y) const {
    detail::apply_columns(op, 1, x, y);
    for (const OneWay& e : one_way) y[e.row] -= op.entry(e.row, e.entry) * x[e.column];
  }
};

struct Timer {
  SpectralCache& cache;
  clock::time_point t0 = clock::now();
  ~Timer() {
    const double s = std::chrono::duration<double>(clock::now() - t0).count();
    cache.seconds += s;
    detail::estimate_seconds_on_this_thread += s;
  }
};

}  // namespace

namespace detail {
thread_local double estimate_seconds_on_this_thread = 0.0;
}  // namespace detail

double estimate_lambda_min(const LimitOperator& op, SpectralCache& cache) {
  const std::lock_guard<std::mutex> lock(cache.mutex);
  if (!std::isnan(cache.lambda_min)) return cache.lambda_min;
  Timer timer{cache};
  std::vector<double> gamma_inverse = symmetriser(op);
  if (gamma_inverse.empty() || !one_way_entries_below_blocks(op, one_way_entries(op))) {
    // No diagonal inner product makes these rows self-adjoint (sorpia::
    // symmetriser), nor B when a one-way entry closes a cycle, and Lanczos
    // needs one: the power method on I - B, whose norm ratio tends to
    // max |1 - lambda|, so the estimate is at or below the smallest real part
    // of B's eigenvalues (which may be complex then).
    std::vector<double> bx(op.n);
    const auto i_minus_b = [&](const double* x, double* y) {
      detail::apply_columns(op, 1, x, bx.data());
      for (std::size_t i = 0; i < op.n; ++i) y[i] = x[i] - bx[i];
    };
    cache.lambda_min = 1.0 - power_radius(op.n, i_minus_b, std::vector<double>(op.n, 1.0), 300, 1e-6);
    return cache.lambda_min;
  }
  const SelfAdjointPart b{op};
  const auto low_end = [](double lo, double) { return std::make_pair(1.0 - lo, 0.0); };
  cache.lambda_min = lanczos_extremes(op.n, b, gamma_inverse, 300, 1e-5, low_end).first;
  return cache.lambda_min;
}

double estimate_jacobi_rho(const LimitOperator& op, SpectralCache& cache) {
  const std::lock_guard<std::mutex> lock(cache.mutex);
  if (!std::isnan(cache.jacobi_rho)) return cache.jacobi_rho;
  Timer timer{cache};
  std::vector<double> bx(op.n), w = detail::gamma_inverse(op);
  // D^-1 B = D^-1 Gamma Upsilon is self-adjoint for the weights D Gamma^-1.
  for (std::size_t i = 0; i < op.n; ++i) w[i] *= op.diag[i];
  const auto jacobi = [&](const double* x, double* y) {
    detail::apply_columns(op, 1, x, bx.data());
    for (std::size_t i = 0; i < op.n; ++i) y[i] = x[i] - bx[i] / op.diag[i];
  };
  cache.jacobi_rho = power_radius(op.n, jacobi, w, 500, 1e-7);
  return cache.jacobi_rho;
}

std::pair<double, double> estimate_hermitian_extremes(const LimitOperator& op, SpectralCache& cache) {
  const std::lock_guard<std::mutex> lock(cache.mutex);
  if (std::isnan(cache.hermitian_min) || std::isnan(cache.hermitian_max)) {
    Timer timer{cache};
    const detail::Transposed t = detail::transpose(op);
    std::vector<double> bx(op.n), btx(op.n), ones(op.n, 1.0);
    const auto h = [&](const double* x, double* y) { detail::apply_part(op, t, 1, 1.0, x, bx.data(), btx.data(), y); };
    const auto both = [](double lo, double hi) { return std::make_pair(lo, hi); };
    std::tie(cache.hermitian_min, cache.hermitian_max) = lanczos_extremes(op.n, h, ones, 300, 1e-5, both);
  }
  return {cache.hermitian_min, cache.hermitian_max};
}

}  // namespace sorpia
