// The stationary methods (PIA, W-PIA,
// Gauss-Seidel, SOR-PIA) and the driver shared by every method.
#include "sorpia/solvers.hpp"

#include <algorithm>
#include <chrono>
#include <initializer_list>
#include <cmath>
#include <string>
#include <tuple>

#include "solver_detail.hpp"
#include "sorpia/detail/repr.hpp"
#include "sorpia/errors.hpp"

namespace sorpia {

Method parse_method(const std::string& name) {
  std::string names;
  for (Method m : all_methods) {
    if (name == method_name(m)) return m;
    names += std::string(names.empty() ? "'" : ", '") + method_name(m) + "'";
  }
  throw ParameterError("unknown method '" + name + "': use one of " + names);
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
    case Method::Gmres: return "gmres";
    case Method::Cgls: return "cgls";
    case Method::Auto: return "auto";
  }
  return "?";
}

const char* stop_reason_name(StopReason reason) {
  switch (reason) {
    case StopReason::Converged: return "converged";
    case StopReason::MaxIter: return "max_iter";
    case StopReason::Diverged: return "diverged";
    case StopReason::Callback: return "callback";
    case StopReason::Slow: return "slow";
    case StopReason::Stalled: return "stalled";
    case StopReason::Singular: return "singular";
  }
  return "?";
}

double divergence_growth(Method method) {
  switch (method) {
    case Method::Cg:
      return 1e8;
    case Method::Gmres:
    case Method::Cgls:
      return 1e4;
    case Method::Hss:
    case Method::Whss:
      return 100.0;
    default:
      return 10.0;
  }
}

std::optional<Method> recommended_after(Method method) {
  switch (method) {
    case Method::Cgls: return std::nullopt;
    case Method::Gmres: return Method::Cgls;
    default: return Method::Gmres;
  }
}

namespace {

std::string quoted(Method m) { return std::string("'") + method_name(m) + "'"; }

// "name = value applies to method='a' or 'b' only (method='c')" unless the method is one of `users`.
void check_applies(const char* name, const std::string& value, Method method, std::initializer_list<Method> users) {
  for (Method u : users)
    if (u == method) return;
  std::string list;  // 'a', 'b' or 'c'
  std::size_t k = 0;
  for (Method u : users) list += (k++ == 0 ? "" : k == users.size() ? " or " : ", ") + quoted(u);
  throw ParameterError(std::string(name) + " = " + value + " applies to method=" + list + " only (method=" +
                       quoted(method) + ")");
}

// omega, sigma and weight: relaxation factors, in (0, 2).
void check_relaxation(const char* name, double x) {
  if (!(x > 0.0 && x < 2.0)) throw ParameterError(std::string(name) + " = " + detail::repr(x) + " is outside (0, 2)");
}

void check_positive_finite(const char* name, double x) {
  if (!(x > 0.0 && std::isfinite(x)))
    throw ParameterError(std::string(name) + " = " + detail::repr(x) + " must be a positive finite number");
}

}  // namespace

void check_options(const SolveOptions& opt) {
  const Method m = opt.method;
  if (opt.omega_rule != OmegaRule::Auto) {
    const std::string shown = opt.omega_rule == OmegaRule::Young ? "'young'" : detail::repr(opt.omega);
    check_applies("omega", shown, m, {Method::Sor, Method::Auto});
    if (opt.omega_rule == OmegaRule::Given) check_relaxation("omega", opt.omega);
  }
  if (opt.sigma) {
    check_applies("sigma", detail::repr(*opt.sigma), m, {Method::Wpia});
    check_relaxation("sigma", *opt.sigma);
  }
  if (opt.alpha) {
    check_applies("alpha", detail::repr(*opt.alpha), m, {Method::Hss, Method::Whss});
    check_positive_finite("alpha", *opt.alpha);
  }
  if (opt.weight) {
    check_applies("weight", detail::repr(*opt.weight), m, {Method::Whss});
    check_relaxation("weight", *opt.weight);
  }
  check_positive_finite("tol", opt.tol);
  if (opt.max_iter < 1)
    throw ParameterError("max_iter = " + detail::repr(opt.max_iter) + " must be an integer >= 1");
  if (opt.max_iter > max_iterations)
    throw ParameterError("max_iter = " + detail::repr(opt.max_iter) + " is too large (at most 2**31 - 1)");
  if (opt.threads < 1 || opt.threads > max_threads)
    throw ParameterError("threads = " + detail::repr(opt.threads) + " must be an integer in 1.." +
                         std::to_string(max_threads));
  if (opt.threads > 1)
    check_applies("threads", detail::repr(opt.threads), m, {Method::Sor, Method::Gs, Method::Auto});
}

void parse_omega(const std::string& text, SolveOptions& opt) {
  if (text == "auto" || text == "young") {
    opt.omega_rule = text == "auto" ? OmegaRule::Auto : OmegaRule::Young;
    return;
  }
  char* end = nullptr;
  const double x = std::strtod(text.c_str(), &end);
  if (text.empty() || end != text.c_str() + text.size())
    throw ParameterError("omega = '" + text + "': use a float in (0, 2), 'auto' or 'young'");
  opt.omega_rule = OmegaRule::Given;
  opt.omega = x;
}

double young_omega(double rho, bool* clamped) {
  const bool c = !(rho < young_rho_clamp);  // NaN clamps too
  if (clamped) *clamped = c;
  const double r = c ? young_rho_clamp : std::max(rho, 0.0);
  return 2.0 / (1.0 + std::sqrt(1.0 - r * r));
}

namespace detail {

double residual(const LimitOperator& op, const double* v0, const double* v, double* r, std::size_t k) {
  const Rows rows = rows_of(op);
  return with_columns(k, [&](auto cols) {
    return with_row_kind(rows, [&](auto kind) {
      double m = 0.0;
      for (std::size_t i = 0; i < rows.n; ++i)
        m = std::max(m, residual_row<cols(), decltype(kind)>(rows, v0, v, k, i, r ? r + k * i : nullptr));
      return std::sqrt(m);
    });
  });
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
void solve_richardson(const LimitOperator& op, const double* v0, std::size_t kc, double sigma, Monitor& mon,
                      SolveResult& res) {
  double* v = res.control_vertices.data();
  std::vector<double> r(kc * op.n);
  if (mon.start(residual(op, v0, v, r.data(), kc))) return;
  for (;;) {
    for (std::size_t k = 0; k < kc * op.n; ++k) v[k] += sigma * r[k];
    ++res.products;
    if (mon.record(residual(op, v0, v, r.data(), kc))) return;
  }
}

}  // namespace
}  // namespace detail

namespace {

// The parameters a method runs with: given, or derived from spectral estimates
// (kept in `sc`), into res.
void resolve_parameters(const LimitOperator& op, const SolveOptions& opt, SpectralCache& sc, SolveResult& res) {
  switch (opt.method) {
    case Method::Pia:
      res.sigma = 1.0;
      break;
    case Method::Wpia:
      if (opt.sigma) {
        res.sigma = *opt.sigma;
      } else {
        res.lambda_min = estimate_lambda_min(op, sc);
        // W-PIA's step assumes B's eigenvalues in (0, 1]; sharpness tags can
        // make them complex, and the estimate is then a lower bound of their
        // real parts. At or below 0 no step is known to converge: refused.
        if (!(res.lambda_min > 0.0))
          throw MeshError("method 'wpia': the limit matrix has an eigenvalue with real part <= 0 (estimated "
                          "lambda_min = " + detail::repr(res.lambda_min) +
                          "), where no step sigma is known to converge, and 'pia', 'gs' and 'sor' diverge; use "
                          "'auto' (the default) or 'gmres', which converge on any invertible B");
        res.sigma = 2.0 / (res.lambda_min + 1.0);  // lambda_max(B) = 1
      }
      break;
    case Method::Gs:
      res.omega = 1.0;
      break;
    case Method::Cg:
    case Method::Gmres:
    case Method::Cgls:
    case Method::Auto:  // its runs resolve their own
      break;
    case Method::Sor:
      if (opt.omega_rule == OmegaRule::Given) {
        res.omega = opt.omega;
      } else if (opt.omega_rule == OmegaRule::Young) {
        res.rho = estimate_jacobi_rho(op, sc);
        res.omega = young_omega(res.rho, &res.omega_clamped);
      } else {
        res.omega = sor_auto_omega;
      }
      break;
    case Method::Hss:
    case Method::Whss: {
      const bool relaxed = opt.method == Method::Whss;
      double hmin = NAN, hmax = NAN;
      if (!opt.alpha || (relaxed && !opt.weight)) std::tie(hmin, hmax) = estimate_hermitian_extremes(op, sc);
      // H's extremes are positive on Loop limit matrices; the square root is guarded anyway.
      res.alpha = opt.alpha ? *opt.alpha : std::sqrt(std::max(hmin, 1e-3 * hmax) * hmax);
      if (!relaxed) {
        res.weight = 1.0;
      } else if (opt.weight) {
        res.weight = *opt.weight;
      } else {
        // With S = 0 the HSS iteration matrix is (alpha - H)(alpha + H)^-1,
        // eigenvalues (alpha - l)/(alpha + l) for l in [hmin, hmax]; the
        // relaxation 2 / (2 - mu_min - mu_max) centres them on 0. At
        // alpha = sqrt(hmin hmax) they are already centred (weight 1).
        const double mu_min = (res.alpha - hmax) / (res.alpha + hmax);
        const double mu_max = (res.alpha - hmin) / (res.alpha + hmin);
        res.weight = 2.0 / (2.0 - mu_min - mu_max);
      }
      break;
    }
  }
}

}  // namespace

namespace {

// Whether V0, scaled up by 2^-exponent for the solve, has a residual that is 0
// at V0's own scale: E_0 = max_i ||v_i^0 - (B V0)_i|| underflows (subnormal
// input), so V0 interpolates as far as doubles can tell, and the solve returns
// it as the answer with errors [0.0], as for E_0 = 0 exactly.
bool nothing_to_solve(const LimitOperator& op, const double* v0, std::size_t k, int exponent) {
  std::vector<double> scaled(v0, v0 + k * op.n);
  detail::scale_pow2(scaled.data(), scaled.size(), -exponent);
  return std::ldexp(detail::residual(op, scaled.data(), scaled.data(), nullptr, k), exponent) == 0.0;
}

// The iteration of a method that iterates on res.control_vertices (all but
// the (n, 3) sweep), for V0 / 2^exponent, (n, k), from V0 or `initial`.
void run_iteration(const LimitOperator& op, const double* v0, std::size_t k, const double* initial, int exponent,
                   const SolveOptions& opt, SolveResult& res) {
  const std::size_t m = k * op.n;
  std::vector<double> scaled;
  if (exponent != 0) {
    scaled.assign(v0, v0 + m);
    detail::scale_pow2(scaled.data(), scaled.size(), -exponent);
    v0 = scaled.data();
  }
  detail::Monitor mon(opt, res, detail::max_row_norm(v0, op.n, k));
  if (initial && mon.warm_start(detail::residual(op, v0, v0, nullptr, k))) {
    res.control_vertices.assign(initial, initial + m);
    detail::scale_pow2(res.control_vertices.data(), m, -exponent);
  } else {
    res.control_vertices.assign(v0, v0 + m);  // V^(0) = V0 (paper: M^0 = M)
  }
  switch (opt.method) {
    case Method::Pia:
    case Method::Wpia:
      detail::solve_richardson(op, v0, k, res.sigma, mon, res);
      break;
    case Method::Cg:
      detail::solve_cg(op, v0, k, mon, res);
      break;
    case Method::Gmres:
      detail::solve_gmres(op, v0, k, mon, res);
      break;
    case Method::Cgls:
      detail::solve_cgls(op, v0, k, mon, res);
      break;
    case Method::Gs:
    case Method::Sor:
      detail::solve_sor_columns(op, v0, k, res.omega, mon, res);
      break;
    default:  // Hss, Whss
      detail::solve_hss(op, v0, k, res.alpha, res.weight, mon, res);
      break;
  }
  detail::scale_pow2(res.control_vertices.data(), res.control_vertices.size(), exponent);
}

// (n, k) data with k < 3 as (n, 3), the columns past k zero: every method
// treats the columns alike and a zero column has a zero residual, so the
// first k columns iterate as they would alone and E_k is the same; the
// sweep then runs on its (n, 3) engine, threads included.
std::vector<double> padded(const double* x, std::size_t n, std::size_t k) {
  std::vector<double> out(3 * n, 0.0);
  for (std::size_t i = 0; i < n; ++i)
    for (std::size_t c = 0; c < k; ++c) out[3 * i + c] = x[k * i + c];
  return out;
}

}  // namespace

SolveResult solve(const LimitOperator& op, const double* v0, const SolveOptions& opt, SpectralCache* cache) {
  return solve(op, v0, 3, nullptr, opt, cache);
}

namespace {

// One method's run, without the divergence replay and the diagnosis
// (finish_run): solve() for an explicit method, and each run of "auto".
SolveResult solve_one(const LimitOperator& op, const double* v0, std::size_t k, const double* initial,
                      const SolveOptions& opt, SpectralCache* cache) {
  using clock = std::chrono::steady_clock;
  const bool sweep = opt.method == Method::Gs || opt.method == Method::Sor;
  if (sweep && k < 3) {
    const std::vector<double> v0p = padded(v0, op.n, k);
    const std::vector<double> initialp = initial ? padded(initial, op.n, k) : std::vector<double>();
    SolveResult res = solve_one(op, v0p.data(), 3, initial ? initialp.data() : nullptr, opt, cache);
    for (std::size_t i = 0; i < op.n; ++i)
      for (std::size_t c = 0; c < k; ++c) res.control_vertices[k * i + c] = res.control_vertices[3 * i + c];
    res.control_vertices.resize(k * op.n);
    res.columns = k;
    return res;
  }
  SpectralCache local;
  SpectralCache& sc = cache ? *cache : local;
  SolveResult res;
  res.method = opt.method;
  res.variant = method_name(opt.method);
  res.columns = k;

  // The estimates are timed apart from the solve, and cost nothing when the
  // cache already holds them (or another thread's solve computed them).
  const double spent_before = detail::estimate_seconds_on_this_thread;
  resolve_parameters(op, opt, sc, res);
  res.estimate_seconds = detail::estimate_seconds_on_this_thread - spent_before;

  const auto t0 = clock::now();
  const int exponent = detail::scale_exponent(v0, k * op.n);
  if (exponent < 0 && nothing_to_solve(op, v0, k, exponent)) {
    res.control_vertices.assign(v0, v0 + k * op.n);
    res.errors.assign(1, 0.0);
    res.stop_reason = StopReason::Converged;
    if (opt.callback) opt.callback(0, 0.0);
  } else if (sweep && k == 3) {
    std::vector<double> scaled_initial;
    if (initial && exponent != 0) {
      scaled_initial.assign(initial, initial + 3 * op.n);
      detail::scale_pow2(scaled_initial.data(), scaled_initial.size(), -exponent);
      initial = scaled_initial.data();
    }
    detail::solve_sor(op, v0, exponent, opt, res.omega, res, initial);
  } else {
    run_iteration(op, v0, k, initial, exponent, opt, res);
  }
  if (sweep) res.relaxations = static_cast<long long>(res.iterations) * static_cast<long long>(op.n);
  res.initial_error = std::ldexp(res.initial_error, exponent);
  res.solve_seconds = std::chrono::duration<double>(clock::now() - t0).count();
  res.seconds = res.estimate_seconds + res.solve_seconds;
  return res;
}


// The attempt `res` records.
Attempt attempt_of(const SolveResult& res) {
  Attempt a;
  a.method = res.method;
  a.variant = res.variant;
  a.iterations = res.iterations;
  a.stop_reason = res.stop_reason;
  a.final_error = res.errors.empty() ? NAN : res.errors.back();
  a.products = res.products;
  a.seconds = res.seconds;
  return a;
}

// What every solve's result gets once its method has stopped: after a
// divergence, the iterate of the lowest E_k, by running the method again
// (every method is deterministic, threads included) to that iteration
// without callback; and where it did not converge, the method to use
// instead and the vertices whose residual is largest.
void finish_run(const LimitOperator& op, const double* v0, std::size_t k, const double* initial,
                const SolveOptions& opt, SpectralCache* cache, SolveResult& res) {
  res.returned_iteration = res.iterations;
  if (res.stop_reason == StopReason::Diverged && !res.errors.empty()) {
    const auto best = std::min_element(res.errors.begin(), res.errors.end()) - res.errors.begin();
    if (best < res.iterations) {
      if (best == 0) {
        const double* start = initial ? initial : v0;
        res.control_vertices.assign(start, start + k * op.n);
      } else {
        SolveOptions again = opt;
        again.callback = nullptr;
        again.max_iter = best;
        SolveResult replay = solve_one(op, v0, k, initial, again, cache);
        res.control_vertices = std::move(replay.control_vertices);
        res.products += replay.products;
        res.solve_seconds += replay.solve_seconds;
        res.seconds += replay.seconds;
      }
      res.returned_iteration = static_cast<int>(best);
    }
  }
  if (res.converged() || res.stop_reason == StopReason::Callback) return;
  res.recommended = recommended_after(res.method == Method::Auto ? Method::Cgls : res.method);
  std::vector<double> r(k * op.n);
  detail::residual(op, v0, res.control_vertices.data(), r.data(), k);
  std::vector<std::pair<double, std::int64_t>> rows(op.n);
  for (std::size_t i = 0; i < op.n; ++i) {
    double e = 0.0;
    for (std::size_t c = 0; c < k; ++c) e += r[k * i + c] * r[k * i + c];
    rows[i] = {std::sqrt(e), static_cast<std::int64_t>(i)};
  }
  const std::size_t listed = std::min(worst_vertices_listed, rows.size());
  std::partial_sort(rows.begin(), rows.begin() + static_cast<std::ptrdiff_t>(listed), rows.end(),
                    [](const auto& a, const auto& b) { return a.first > b.first || (a.first == b.first && a.second < b.second); });
  res.worst_vertices.clear();
  res.worst_residuals.clear();
  for (std::size_t j = 0; j < listed; ++j) {
    res.worst_vertices.push_back(rows[j].second);
    res.worst_residuals.push_back(rows[j].first);
  }
}

// Whether "auto" stops its "sor" run after E_k / E_0 = errors[k]: E_k not
// below E_{k-auto_window} (growth or stagnation: the sweep's iteration
// matrix has a spectral radius at or near 1 or above), or, from
// auto_first_check on, a contraction per sweep q = (E_k /
// E_{k-auto_window})^(1/auto_window) too slow to reach tol by max_iter. On
// the meshes where Gauss-Seidel converges the rate of the first sweeps is at
// or above the asymptotic one, so the estimate errs towards keeping "sor".
bool too_slow(const std::vector<double>& errors, double tol, long long max_iter) {
  const std::size_t k = errors.size() - 1;
  if (k < static_cast<std::size_t>(auto_window)) return false;
  const double now = errors[k], before = errors[k - auto_window];
  if (!(now < before)) return true;
  if (k < static_cast<std::size_t>(auto_first_check) || k % auto_window != 0 || !(now > tol)) return false;
  const double q = std::pow(now / before, 1.0 / auto_window);
  const double needed = std::log(tol / now) / std::log(q);
  return static_cast<double>(k) + needed > static_cast<double>(max_iter);
}

// "auto": "sor" (omega and threads as given), watched by too_slow and the
// divergence rule; where it stops short, "gmres" from the better of its
// iterate and the start; where that stalls (B singular), "cgls" from 0: the
// least-squares solution of least norm. The callback sees one count of
// iterations across the runs.
SolveResult solve_auto(const LimitOperator& op, const double* v0, std::size_t k, const double* initial,
                       const SolveOptions& opt, SpectralCache* cache) {
  using clock = std::chrono::steady_clock;
  const auto t0 = clock::now();
  std::vector<Attempt> attempts;
  long long offset = 0;
  bool user_stop = false, slow = false;
  std::vector<double> watched;
  const auto forward = [&](int it, double e) {
    if (opt.callback && opt.callback(static_cast<int>(std::min<long long>(offset + it, max_iterations)), e))
      user_stop = true;
    return user_stop;
  };
  SolveOptions sor = opt;
  sor.method = Method::Sor;
  sor.callback = [&](int it, double e) {
    watched.push_back(e);
    if (forward(it, e)) return true;
    slow = too_slow(watched, opt.tol, opt.max_iter);
    return slow;
  };
  SolveResult res = solve_one(op, v0, k, initial, sor, cache);
  if (slow) res.stop_reason = StopReason::Slow;
  // The "sor" run's parameters stay in the result whichever run made it.
  const double omega = res.omega, rho = res.rho;
  const bool omega_clamped = res.omega_clamped, reordered = res.reordered;
  double estimates = res.estimate_seconds;
  long long products = res.products, relaxations = res.relaxations;
  attempts.push_back(attempt_of(res));
  const bool stopped_short = !res.converged() && !user_stop;
  if (stopped_short) {
    // "gmres", from "sor"'s iterate where it got below the start.
    const bool better = res.stop_reason != StopReason::Diverged && res.errors.back() < res.errors.front();
    std::vector<double> start;
    if (better) start = res.control_vertices;
    offset += res.iterations;
    SolveOptions gmres = opt;
    gmres.method = Method::Gmres;
    gmres.omega_rule = OmegaRule::Auto;
    gmres.threads = 1;
    gmres.callback = forward;
    res = solve_one(op, v0, k, better ? start.data() : initial, gmres, cache);
    finish_run(op, v0, k, better ? start.data() : initial, gmres, cache, res);
    estimates += res.estimate_seconds;
    products += res.products;
    attempts.push_back(attempt_of(res));
    if (res.stop_reason == StopReason::Stalled && !user_stop) {
      offset += res.iterations;
      SolveOptions cgls = gmres;
      cgls.method = Method::Cgls;
      const std::vector<double> zero(k * op.n, 0.0);  // from 0: the least-squares solution of least norm
      res = solve_one(op, v0, k, zero.data(), cgls, cache);
      finish_run(op, v0, k, zero.data(), cgls, cache, res);
      estimates += res.estimate_seconds;
      products += res.products;
      attempts.push_back(attempt_of(res));
    }
  }
  res.method = Method::Auto;
  res.omega = omega;
  res.rho = rho;
  res.omega_clamped = omega_clamped;
  res.reordered = reordered;
  if (!stopped_short) finish_run(op, v0, k, initial, sor, cache, res);
  res.attempts = std::move(attempts);
  res.products = products;
  res.relaxations = relaxations;
  res.estimate_seconds = estimates;
  res.seconds = std::chrono::duration<double>(clock::now() - t0).count();
  res.solve_seconds = res.seconds - estimates;
  if (!res.converged() && res.stop_reason != StopReason::Callback) res.recommended.reset();
  return res;
}

}  // namespace

SolveResult solve(const LimitOperator& op, const double* v0, std::size_t k, const double* initial,
                  const SolveOptions& opt, SpectralCache* cache) {
  check_options(opt);
  if (k < 1) throw ParameterError("the data must have at least one column (k = 0)");
  if (opt.threads > 1 && k > 3)
    throw ParameterError("threads = " + detail::repr(opt.threads) + " sweeps (n, 3) data and fewer columns only; " +
                         "this data has " + std::to_string(k) + " columns: use threads=1");
  if (opt.method == Method::Auto) return solve_auto(op, v0, k, initial, opt, cache);
  SolveResult res = solve_one(op, v0, k, initial, opt, cache);
  finish_run(op, v0, k, initial, opt, cache, res);
  res.attempts.assign(1, attempt_of(res));
  return res;
}

}  // namespace sorpia
