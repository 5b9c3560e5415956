// Spectral estimates for the solver parameters (W-PIA's sigma, Young's omega,
// HSS's alpha), all by the power method with a few hundred operator products
// at most, on one scalar field (a third of the work of a vertex product).
#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdint>
#include <vector>

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

struct Timer {
  SpectralCache& cache;
  clock::time_point t0 = clock::now();
  ~Timer() { cache.seconds += std::chrono::duration<double>(clock::now() - t0).count(); }
};

}  // namespace

double estimate_lambda_min(const LimitOperator& op, SpectralCache& cache) {
  if (!std::isnan(cache.lambda_min)) return cache.lambda_min;
  Timer timer{cache};
  std::vector<double> bx(op.n);
  const auto i_minus_b = [&](const double* x, double* y) {
    detail::apply_cols<1>(op, x, bx.data());
    for (std::size_t i = 0; i < op.n; ++i) y[i] = x[i] - bx[i];
  };
  // Eigenvalues of I - B lie in [0, 1 - lambda_min]: its radius is 1 - lambda_min.
  // Gamma^-1 weights make B (so I - B) self-adjoint where it can be.
  cache.lambda_min = 1.0 - power_radius(op.n, i_minus_b, detail::gamma_inverse(op), 300, 1e-6);
  return cache.lambda_min;
}

double estimate_jacobi_rho(const LimitOperator& op, SpectralCache& cache) {
  if (!std::isnan(cache.jacobi_rho)) return cache.jacobi_rho;
  Timer timer{cache};
  std::vector<double> bx(op.n), w = detail::gamma_inverse(op);
  // D^-1 B = D^-1 Gamma Upsilon is self-adjoint for the weights D Gamma^-1.
  for (std::size_t i = 0; i < op.n; ++i) w[i] *= op.diag[i];
  const auto jacobi = [&](const double* x, double* y) {
    detail::apply_cols<1>(op, x, bx.data());
    for (std::size_t i = 0; i < op.n; ++i) y[i] = x[i] - bx[i] / op.diag[i];
  };
  cache.jacobi_rho = power_radius(op.n, jacobi, w, 500, 1e-7);
  return cache.jacobi_rho;
}

std::pair<double, double> estimate_hermitian_extremes(const LimitOperator& op, SpectralCache& cache) {
  if (std::isnan(cache.hermitian_min) || std::isnan(cache.hermitian_max)) {
    Timer timer{cache};
    const detail::Transposed t = detail::transpose(op);
    std::vector<double> bx(op.n), btx(op.n), ones(op.n, 1.0);
    const auto h = [&](const double* x, double* y) { detail::apply_part<1>(op, t, 1.0, x, bx.data(), btx.data(), y); };
    const double hmax = power_radius(op.n, h, ones, 300, 1e-6);
    const auto shifted = [&](const double* x, double* y) {
      h(x, y);
      for (std::size_t i = 0; i < op.n; ++i) y[i] = hmax * x[i] - y[i];
    };
    cache.hermitian_max = hmax;
    cache.hermitian_min = hmax - power_radius(op.n, shifted, ones, 300, 1e-6);
  }
  return {cache.hermitian_min, cache.hermitian_max};
}

}  // namespace sorpia
