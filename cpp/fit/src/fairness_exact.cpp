#include "fairness_exact.hpp"

#include <cmath>
#include <cstddef>
#include <utility>
#include <vector>

#include "fairness_pieces.hpp"

namespace sorpia::fairness_detail {

// Solves a x = b for the columns of b (n x m, row-major) in place, a (n x n)
// destroyed: Gauss-Jordan with partial pivoting, for the small fixed systems
// of ExactForms.
void solve_dense(std::vector<double> a, std::vector<double>& b, std::size_t n, std::size_t m) {
  for (std::size_t c = 0; c < n; ++c) {
    std::size_t piv = c;
    for (std::size_t r = c + 1; r < n; ++r)
      if (std::abs(a[r * n + c]) > std::abs(a[piv * n + c])) piv = r;
    for (std::size_t k = 0; k < n; ++k) std::swap(a[c * n + k], a[piv * n + k]);
    for (std::size_t k = 0; k < m; ++k) std::swap(b[c * m + k], b[piv * m + k]);
    const double d = a[c * n + c];
    for (std::size_t r = 0; r < n; ++r) {
      if (r == c) continue;
      const double f = a[r * n + c] / d;
      if (f == 0.0) continue;
      for (std::size_t k = 0; k < n; ++k) a[r * n + k] -= f * a[c * n + k];
      for (std::size_t k = 0; k < m; ++k) b[r * m + k] -= f * b[c * m + k];
    }
  }
  for (std::size_t c = 0; c < n; ++c)
    for (std::size_t k = 0; k < m; ++k) b[c * m + k] /= a[c * n + c];
}


ExactForms::ExactForms() {
  std::vector<std::pair<int, int>> mono;  // s^a t^b but the constant
  for (int a = 0; a < 4; ++a)
    for (int b = 0; b < 4; ++b)
      if (a + b > 0) mono.emplace_back(a, b);
  const std::size_t nm = mono.size();
  // d^(i, j) of monomial (a, b) at (s, t), centred on the piece (better conditioned)
  auto deriv = [](std::pair<int, int> m, int i, int j, double s, double t) {
    if (m.first < i || m.second < j) return 0.0;
    double c = 1.0;
    for (int k = 0; k < i; ++k) c *= m.first - k;
    for (int k = 0; k < j; ++k) c *= m.second - k;
    return c * std::pow(s - 0.5, m.first - i) * std::pow(t - 0.5, m.second - j);
  };
  const std::pair<int, int> orders[5] = {{1, 0}, {0, 1}, {2, 0}, {1, 1}, {0, 2}};
  std::vector<std::pair<UV, std::pair<int, int>>> data;
  for (const double t : kSquareData)
    for (const double s : kSquareData)
      for (const auto& o : orders) data.push_back({{s, t}, o});
  // C = (P^T P)^-1 P^T, P (kData x nm) the functionals on the monomials.
  std::vector<double> pm(kData * nm), ptp(nm * nm, 0.0), c(nm * kData);
  for (std::size_t d = 0; d < kData; ++d)
    for (std::size_t k = 0; k < nm; ++k)
      pm[d * nm + k] = deriv(mono[k], data[d].second.first, data[d].second.second, data[d].first.u, data[d].first.v);
  for (std::size_t i = 0; i < nm; ++i)
    for (std::size_t j = 0; j < nm; ++j)
      for (std::size_t d = 0; d < kData; ++d) ptp[i * nm + j] += pm[d * nm + i] * pm[d * nm + j];
  for (std::size_t k = 0; k < nm; ++k)
    for (std::size_t d = 0; d < kData; ++d) c[k * kData + d] = pm[d * nm + k];
  solve_dense(ptp, c, nm, kData);
  const Rule g = gauss_legendre(4);
  std::vector<double> gtp(nm * nm, 0.0), gmb(nm * nm, 0.0);
  for (std::size_t i = 0; i < 4; ++i)
    for (std::size_t j = 0; j < 4; ++j) {
      const double s = g.x[i], t = g.x[j], w = g.w[i] * g.w[j];
      for (std::size_t a = 0; a < nm; ++a)
        for (std::size_t b = 0; b < nm; ++b) {
          auto dd = [&](int p, int q) { return deriv(mono[a], p, q, s, t) * deriv(mono[b], p, q, s, t); };
          gtp[a * nm + b] += w * (dd(2, 0) + 2.0 * dd(1, 1) + dd(0, 2));
          gmb[a * nm + b] += w * (dd(1, 0) + dd(0, 1));
        }
    }
  auto form = [&](const std::vector<double>& gm) {
    std::vector<double> q(kData * kData, 0.0);
    for (std::size_t a = 0; a < kData; ++a)
      for (std::size_t b = 0; b < kData; ++b) {
        double sum = 0.0;
        for (std::size_t i = 0; i < nm; ++i)
          for (std::size_t j = 0; j < nm; ++j) sum += c[i * kData + a] * gm[i * nm + j] * c[j * kData + b];
        q[a * kData + b] = sum;
      }
    return q;
  };
  thin_plate = form(gtp);
  membrane = form(gmb);
}

}  // namespace sorpia::fairness_detail
