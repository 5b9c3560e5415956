// The stationary methods (PIA, W-PIA,
// Gauss-Seidel, SOR-PIA) and the driver shared by every method.
#include "sorpia/solvers.hpp"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <string>
#include <tuple>

#include "solver_detail.hpp"
#include "sorpia/errors.hpp"

namespace sorpia {

Method parse_method(const std::string& name) {
  for (Method m : {Method::Pia, Method::Wpia, Method::Gs, Method::Sor, Method::Cg, Method::Hss, Method::Whss})
    if (name == method_name(m)) return m;
  throw ParameterError("unknown method '" + name + "': use one of 'pia', 'wpia', 'gs', 'sor', 'cg', 'hss', 'whss'");
}

const char* method_name(Method method) {
  switch (method) {
    case Method::Pia: return "pia";
    case Method::Wpia: return "wpia";
    case Method::Gs: return "gs";
    case Method::Sor: return "sor";
    case Method::Cg: return "cg";
    case Method::Hss: return "hss";
    case Method::Whss: return "whss";
  }
  return "?";
}

const char* stop_reason_name(StopReason reason) {
  switch (reason) {
    case StopReason::Converged: return "converged";
    case StopReason::MaxIter: return "max_iter";
    case StopReason::Diverged: return "diverged";
    case StopReason::Callback: return "callback";
  }
  return "?";
}

double young_omega(double rho, bool* clamped) {
  const bool c = !(rho < young_rho_clamp);  // NaN clamps too
  if (clamped) *clamped = c;
  const double r = c ? young_rho_clamp : std::max(rho, 0.0);
  return 2.0 / (1.0 + std::sqrt(1.0 - r * r));
}

namespace detail {

double residual(const LimitOperator& op, const double* v0, const double* v, double* r) {
  double m = 0.0;
  for (std::size_t i = 0; i < op.n; ++i) {
    double bv[3];
    row_product(op, v, i, bv);
    const double r0 = v0[3 * i] - bv[0];
    const double r1 = v0[3 * i + 1] - bv[1];
    const double r2 = v0[3 * i + 2] - bv[2];
    if (r) {
      r[3 * i] = r0;
      r[3 * i + 1] = r1;
      r[3 * i + 2] = r2;
    }
    m = std::max(m, r0 * r0 + r1 * r1 + r2 * r2);
  }
  return std::sqrt(m);
}

void scale_pow2(double* x, std::size_t n, int e) {
  // Multiplying by a normal power of two is exact and rounds a subnormal
  // result as ldexp does, at a fraction of its cost; 2^e outside the normal
  // range needs ldexp itself.
  if (e > -1000 && e < 1000) {
    const double f = std::ldexp(1.0, e);
    for (std::size_t k = 0; k < n; ++k) x[k] *= f;
  } else {
    for (std::size_t k = 0; k < n; ++k) x[k] = std::ldexp(x[k], e);
  }
}

Transposed transpose(const LimitOperator& op) {
  Transposed t;
  t.offsets.assign(op.n + 1, 0);
  for (std::int32_t j : op.neighbors) ++t.offsets[j + 1];
  for (std::size_t j = 0; j < op.n; ++j) t.offsets[j + 1] += t.offsets[j];
  t.rows.resize(op.neighbors.size());
  t.values.resize(op.neighbors.size());
  std::vector<std::int32_t> fill(t.offsets.begin(), t.offsets.end() - 1);
  for (std::size_t i = 0; i < op.n; ++i)
    for (std::int32_t p = op.offsets[i]; p < op.offsets[i + 1]; ++p) {
      const std::int32_t q = fill[op.neighbors[p]]++;
      t.rows[q] = static_cast<std::int32_t>(i);
      t.values[q] = op.entry(i, p);
    }
  return t;
}

namespace {

// Richardson: V += sigma (V0 - B V) (paper eq. 9 with sigma = 1, W-PIA otherwise).
void solve_richardson(const LimitOperator& op, const double* v0, double sigma, Monitor& mon, SolveResult& res) {
  double* v = res.control_vertices.data();
  std::vector<double> r(3 * op.n);
  if (mon.start(residual(op, v0, v, r.data()))) return;
  for (;;) {
    for (std::size_t k = 0; k < 3 * op.n; ++k) v[k] += sigma * r[k];
    ++res.products;
    if (mon.record(residual(op, v0, v, r.data()))) return;
  }
}

void check_open_unit(double x, const char* name, double hi) {
  if (!(x > 0.0 && x < hi))
    throw ParameterError(std::string(name) + " = " + std::to_string(x) + " is outside (0, " + std::to_string(hi) +
                         ")");
}

}  // namespace
}  // namespace detail

SolveResult solve(const LimitOperator& op, const double* v0, const SolveOptions& opt, SpectralCache* cache) {
  using clock = std::chrono::steady_clock;
  if (!(opt.tol > 0.0)) throw ParameterError("tol = " + std::to_string(opt.tol) + " must be positive");
  if (opt.max_iter < 1) throw ParameterError("max_iter = " + std::to_string(opt.max_iter) + " must be at least 1");
  if (opt.threads < 1 || opt.threads > max_threads)
    throw ParameterError("threads = " + std::to_string(opt.threads) + " must be an integer in 1.." +
                         std::to_string(max_threads));
  if (opt.threads > 1 && opt.method != Method::Sor && opt.method != Method::Gs)
    throw ParameterError("threads = " + std::to_string(opt.threads) + " applies to method 'sor' or 'gs' only (method '" +
                         method_name(opt.method) + "')");

  SpectralCache local;
  SpectralCache& sc = cache ? *cache : local;
  SolveResult res;
  res.method = opt.method;
  res.variant = method_name(opt.method);

  // Parameters: the estimates are timed apart from the solve (and cost nothing
  // when the cache already holds them).
  const double spent_before = sc.seconds;
  switch (opt.method) {
    case Method::Pia:
      res.sigma = 1.0;
      break;
    case Method::Wpia:
      if (std::isnan(opt.sigma)) {
        res.lambda_min = estimate_lambda_min(op, sc);
        res.sigma = 2.0 / (res.lambda_min + 1.0);  // lambda_max(B) = 1
      } else {
        detail::check_open_unit(opt.sigma, "sigma", 2.0);
        res.sigma = opt.sigma;
      }
      break;
    case Method::Gs:
      res.omega = 1.0;
      break;
    case Method::Sor:
      if (opt.omega_rule == OmegaRule::Given) {
        detail::check_open_unit(opt.omega, "omega", 2.0);
        res.omega = opt.omega;
      } else if (opt.omega_rule == OmegaRule::Young) {
        res.rho = estimate_jacobi_rho(op, sc);
        res.omega = young_omega(res.rho, &res.omega_clamped);
      } else {
        res.omega = sor_auto_omega;
      }
      break;
    case Method::Cg:
      break;
    case Method::Hss:
    case Method::Whss: {
      const bool relaxed = opt.method == Method::Whss;
      const bool need_h = std::isnan(opt.alpha) || (relaxed && std::isnan(opt.weight));
      double hmin = NAN, hmax = NAN;
      if (need_h) std::tie(hmin, hmax) = estimate_hermitian_extremes(op, sc);
      if (std::isnan(opt.alpha)) {
        // H's extremes are positive on Loop limit matrices; guard the square
        // root anyway.
        res.alpha = std::sqrt(std::max(hmin, 1e-3 * hmax) * hmax);
      } else {
        if (!(opt.alpha > 0.0 && std::isfinite(opt.alpha)))
          throw ParameterError("alpha = " + std::to_string(opt.alpha) + " must be positive and finite");
        res.alpha = opt.alpha;
      }
      if (!relaxed) {
        res.weight = 1.0;
      } else if (std::isnan(opt.weight)) {
        // With S = 0 the HSS iteration matrix is (alpha - H)(alpha + H)^-1,
        // eigenvalues (alpha - l)/(alpha + l) for l in [hmin, hmax]; the
        // relaxation 2 / (2 - mu_min - mu_max) centres them on 0. At
        // alpha = sqrt(hmin hmax) they are already centred (weight 1).
        const double mu_min = (res.alpha - hmax) / (res.alpha + hmax);
        const double mu_max = (res.alpha - hmin) / (res.alpha + hmin);
        res.weight = 2.0 / (2.0 - mu_min - mu_max);
      } else {
        detail::check_open_unit(opt.weight, "weight", 2.0);
        res.weight = opt.weight;
      }
      break;
    }
  }
  res.estimate_seconds = sc.seconds - spent_before;

  const auto t0 = clock::now();
  // Solve for V0 / 2^e, 2^e ~ max |v0|: multiplying by a power of two is exact
  // and B is linear, so the iterates are those of V0 scaled, and norms can
  // neither overflow (|v| > 1e154 squares to inf) nor underflow. Within
  // 2^+-200 no squared norm down to rounding level (2^-53 max |v0|) can do
  // either, and the scaling would change no bit of any iterate (every
  // operation commutes with it): then V0 is used as it is, without a copy.
  double max_abs = 0.0;
  for (std::size_t k = 0; k < 3 * op.n; ++k) max_abs = std::max(max_abs, std::abs(v0[k]));
  int exponent = 0;
  if (max_abs > 0.0 && std::isfinite(max_abs)) std::frexp(max_abs, &exponent);
  if (std::abs(exponent) <= 200) exponent = 0;
  if (opt.method == Method::Gs || opt.method == Method::Sor) {
    detail::solve_sor(op, v0, exponent, opt, res.omega, res);
  } else {
    std::vector<double> scaled;
    if (exponent != 0) {
      scaled.assign(v0, v0 + 3 * op.n);
      detail::scale_pow2(scaled.data(), scaled.size(), -exponent);
      v0 = scaled.data();
    }
    res.control_vertices.assign(v0, v0 + 3 * op.n);  // V^(0) = V0 (paper: M^0 = M)
    detail::Monitor mon(opt, res, detail::max_row_norm(v0, op.n));
    switch (opt.method) {
      case Method::Pia:
      case Method::Wpia:
        detail::solve_richardson(op, v0, res.sigma, mon, res);
        break;
      case Method::Cg:
        detail::solve_cg(op, v0, mon, res);
        break;
      default:  // Hss, Whss
        detail::solve_hss(op, v0, res.alpha, res.weight, mon, res);
        break;
    }
    detail::scale_pow2(res.control_vertices.data(), res.control_vertices.size(), exponent);
  }
  res.initial_error = std::ldexp(res.initial_error, exponent);
  res.solve_seconds = std::chrono::duration<double>(clock::now() - t0).count();
  return res;
}

}  // namespace sorpia
