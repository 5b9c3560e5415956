// Krylov and splitting methods: "cg" (CG on the symmetrised system, BiCGSTAB
// where boundaries break the symmetry) and "hss"/"whss" (Bai, Golub and Ng 2003).
// The k columns of the data (three coordinates for vertices) are k
// independent right-hand sides: every scalar of a Krylov method is kept per
// column, the stopping rule looks at all of them. The column loops take k at
// run time; with k = 3 they are those of the three coordinates.
#include <algorithm>
#include <cmath>
#include <vector>

#include "solver_detail.hpp"
#include "sorpia/solvers.hpp"

namespace sorpia {
namespace detail {
namespace {

// One scalar per column.
using Cols = std::vector<double>;

Cols dot(const std::vector<double>& a, const std::vector<double>& b, std::size_t kc) {
  Cols s(kc, 0.0);
  for (std::size_t k = 0; k < a.size(); k += kc)
    for (std::size_t c = 0; c < kc; ++c) s[c] += a[k + c] * b[k + c];
  return s;
}

// y += a x per column.
void axpy(const Cols& a, const std::vector<double>& x, std::vector<double>& y) {
  const std::size_t kc = a.size();
  for (std::size_t k = 0; k < y.size(); k += kc)
    for (std::size_t c = 0; c < kc; ++c) y[k + c] += a[c] * x[k + c];
}

double safe_div(double a, double b) { return b != 0.0 ? a / b : 0.0; }

// E_k from a scaled residual S r.
double unscaled_error(const std::vector<double>& rs, const std::vector<double>& s, std::size_t kc) {
  double m = 0.0;
  for (std::size_t i = 0; i < s.size(); ++i) {
    const double* r = rs.data() + kc * i;
    double e = 0.0;
    for (std::size_t c = 0; c < kc; ++c) e += r[c] * r[c];
    m = std::max(m, e / (s[i] * s[i]));
  }
  return std::sqrt(m);
}

void scaled_product(const LimitOperator& op, std::size_t kc, const std::vector<double>& s,
                    const std::vector<double>& x, std::vector<double>& y) {
  apply_columns(op, kc, x.data(), y.data());
  for (std::size_t i = 0; i < op.n; ++i)
    for (std::size_t c = 0; c < kc; ++c) y[kc * i + c] *= s[i];
}

// Weighted dot product per column: sum_i w_i a_i b_i.
Cols wdot(const std::vector<double>& a, const std::vector<double>& b, const std::vector<double>& w, std::size_t kc) {
  Cols s(kc, 0.0);
  for (std::size_t i = 0; i < w.size(); ++i)
    for (std::size_t c = 0; c < kc; ++c) s[c] += w[i] * a[kc * i + c] * b[kc * i + c];
  return s;
}

// The rest of a CG iteration once q = M p (M self-adjoint in the w-weighted
// inner product), per column: x += a p, r -= a q, p = r + b p, with
// a = rr / <p, q>, b = rr_new / rr; rr = <r, r> is updated. A column already
// solved has rr = 0 and stays put.
void cg_step(const std::vector<double>& w, std::vector<double>& x, std::vector<double>& r, std::vector<double>& p,
             const std::vector<double>& q, Cols& rr) {
  const std::size_t kc = rr.size();
  const Cols pq = wdot(p, q, w, kc);
  Cols a(kc), na(kc);
  for (std::size_t c = 0; c < kc; ++c) {
    a[c] = safe_div(rr[c], pq[c]);
    na[c] = -a[c];
  }
  axpy(a, p, x);
  axpy(na, q, r);
  const Cols rr_new = wdot(r, r, w, kc);
  Cols b(kc);
  for (std::size_t c = 0; c < kc; ++c) b[c] = safe_div(rr_new[c], rr[c]);
  rr = rr_new;
  for (std::size_t k = 0; k < p.size(); k += kc)
    for (std::size_t c = 0; c < kc; ++c) p[k + c] = r[k + c] + b[c] * p[k + c];
}

// CG on the symmetrised system: B = Gamma Upsilon is self-adjoint and positive
// definite in the inner product <x, y> = x^T Gamma^-1 y, so CG runs on B V = V0
// with that inner product; this is CG on Gamma^-1/2 B Gamma^1/2 (symmetric,
// the spectrum of B), i.e. CG on Upsilon V = Gamma^-1 V0 preconditioned by
// Gamma. E_k comes from the recursively updated residual (one product per
// iteration), except where it says converged: the true residual is computed
// then, recorded, and the iteration restarts from it if it is not converged.
void cg_symmetric(const LimitOperator& op, const double* v0, std::size_t kc, Monitor& mon, SolveResult& res) {
  const std::size_t m = kc * op.n;
  const std::vector<double> w = gamma_inverse(op);
  std::vector<double>& x = res.control_vertices;
  std::vector<double> r(m), p(m), q(m);
  if (mon.start(residual(op, v0, x.data(), r.data(), kc))) return;
  p = r;
  Cols rr = wdot(r, r, w, kc);
  for (;;) {
    apply_columns(op, kc, p.data(), q.data());
    ++res.products;
    cg_step(w, x, r, p, q, rr);
    double e = max_row_norm(r.data(), op.n, kc);
    if (mon.converges(e)) {  // the updated residual says converged: take the true one, restart from it if not
      e = residual(op, v0, x.data(), r.data(), kc);
      ++res.products;
      p = r;
      rr = wdot(r, r, w, kc);
    }
    if (mon.record(e)) return;
  }
}

// BiCGSTAB (van der Vorst 1992) on S B V = S V0, for meshes with boundary,
// where Upsilon is not symmetric. One iteration = two products. E_k as in
// cg_symmetric: the true residual wherever the updated one says converged.
void bicgstab(const LimitOperator& op, const double* v0, std::size_t kc, Monitor& mon, SolveResult& res) {
  const std::size_t m = kc * op.n;
  const std::vector<double> s = gamma_inverse(op);  // S = Gamma^-1: S B = Upsilon
  std::vector<double>& x = res.control_vertices;
  std::vector<double> r(m), rt(m), p(m, 0.0), q(m, 0.0), h(m), t(m);
  const double e0 = residual(op, v0, x.data(), r.data(), kc);
  for (std::size_t i = 0; i < op.n; ++i)
    for (std::size_t c = 0; c < kc; ++c) r[kc * i + c] *= s[i];
  if (mon.start(e0)) return;
  rt = r;
  Cols rho(kc, 1.0), alpha(kc, 1.0), omega(kc, 1.0);
  for (;;) {
    const Cols rho_new = dot(rt, r, kc);
    for (std::size_t c = 0; c < kc; ++c) {
      if (rho_new[c] == 0.0) continue;  // solved column (or breakdown: see below)
      const double beta = safe_div(rho_new[c], rho[c]) * safe_div(alpha[c], omega[c]);
      for (std::size_t k = c; k < m; k += kc) p[k] = r[k] + beta * (p[k] - omega[c] * q[k]);
    }
    scaled_product(op, kc, s, p, q);
    const Cols rtq = dot(rt, q, kc);
    for (std::size_t c = 0; c < kc; ++c) alpha[c] = rho_new[c] != 0.0 ? safe_div(rho_new[c], rtq[c]) : 0.0;
    for (std::size_t k = 0; k < m; k += kc)
      for (std::size_t c = 0; c < kc; ++c) h[k + c] = r[k + c] - alpha[c] * q[k + c];
    scaled_product(op, kc, s, h, t);
    res.products += 2;
    const Cols th = dot(t, h, kc), tt = dot(t, t, kc);
    for (std::size_t c = 0; c < kc; ++c) omega[c] = safe_div(th[c], tt[c]);
    for (std::size_t k = 0; k < m; k += kc)
      for (std::size_t c = 0; c < kc; ++c) {
        x[k + c] += alpha[c] * p[k + c] + omega[c] * h[k + c];
        r[k + c] = h[k + c] - omega[c] * t[k + c];
      }
    rho = rho_new;
    // A column whose shadow residual became orthogonal to r (rho = 0) or whose
    // stabilising step vanished (omega = 0) restarts from its current residual.
    const Cols rr = dot(r, r, kc);
    for (std::size_t c = 0; c < kc; ++c)
      if (rr[c] > 0.0 && (rho[c] == 0.0 || omega[c] == 0.0)) {
        for (std::size_t k = c; k < m; k += kc) {
          rt[k] = r[k];
          p[k] = q[k] = 0.0;
        }
        rho[c] = alpha[c] = omega[c] = 1.0;
      }
    double e = unscaled_error(r, s, kc);
    if (mon.converges(e)) {  // the updated residual says converged: take the true one, restart from it if not
      e = residual(op, v0, x.data(), r.data(), kc);
      ++res.products;
      for (std::size_t i = 0; i < op.n; ++i)
        for (std::size_t c = 0; c < kc; ++c) r[kc * i + c] *= s[i];
      rt = r;
      std::fill(p.begin(), p.end(), 0.0);
      std::fill(q.begin(), q.end(), 0.0);
      rho = alpha = omega = Cols(kc, 1.0);
    }
    if (mon.record(e)) return;
  }
}

// CG on an operator M self-adjoint and positive definite in the w-weighted
// inner product (kc columns), from the start value in x, until the largest row
// of the residual is at most abs_tol (at most 500 iterations). Returns the
// products of B (or B^T) spent, at `cost` per application of M.
template <class ApplyM>
long long inner_cg(std::size_t n, std::size_t kc, ApplyM apply_m, int cost, const std::vector<double>& w,
                   const std::vector<double>& rhs, std::vector<double>& x, double abs_tol, std::vector<double>& r,
                   std::vector<double>& p, std::vector<double>& q) {
  long long products = cost;
  apply_m(x, q);
  for (std::size_t k = 0; k < r.size(); ++k) r[k] = rhs[k] - q[k];
  p = r;
  Cols rr = wdot(r, r, w, kc);
  for (int it = 0; it < 500 && max_row_norm(r.data(), n, kc) > abs_tol; ++it) {
    apply_m(p, q);
    products += cost;
    cg_step(w, x, r, p, q, rr);
  }
  return products;
}

}  // namespace

void solve_cg(const LimitOperator& op, const double* v0, std::size_t k, Monitor& mon, SolveResult& res) {
  if (is_symmetrisable(op)) {
    res.variant = "cg";
    cg_symmetric(op, v0, k, mon, res);
  } else {
    res.variant = "bicgstab";
    bicgstab(op, v0, k, mon, res);
  }
}

// HSS on B V = V0 (Bai, Golub and Ng 2003): H = (B + B^T)/2, S = (B - B^T)/2,
//   (alpha I + H) U       = (alpha I - S) V^(k) + V0
//   (alpha I + S) V^(k+1) = (alpha I - H) U     + V0
// then V^(k+1) <- V^(k) + weight (V^(k+1) - V^(k)) (weight 1 for "hss").
// Both inner systems are solved by CG: the first is SPD; the second through
// (alpha I - S)(alpha I + S) = alpha^2 I - S^2, SPD since S^T = -S.
// Inner CG is warm-started and stops at a residual of 1e-3 E_k (inexact HSS),
// or at rounding level.
void solve_hss(const LimitOperator& op, const double* v0, std::size_t kc, double alpha, double weight, Monitor& mon,
               SolveResult& res) {
  const std::size_t m = kc * op.n;
  const Transposed tr = transpose(op);
  const std::vector<double> ones(op.n, 1.0);
  std::vector<double> bx(m), btx(m), rhs(m), u(m), xn(m), r(m), p(m), q(m), tmp(m), sx(m);
  const auto apply_h = [&](const std::vector<double>& x, std::vector<double>& y) {
    apply_part(op, tr, kc, 1.0, x.data(), bx.data(), btx.data(), y.data());
  };
  const auto apply_s = [&](const std::vector<double>& x, std::vector<double>& y) {
    apply_part(op, tr, kc, -1.0, x.data(), bx.data(), btx.data(), y.data());
  };
  const auto m1 = [&](const std::vector<double>& x, std::vector<double>& y) {
    apply_h(x, y);
    for (std::size_t k = 0; k < m; ++k) y[k] += alpha * x[k];
  };
  const auto m2 = [&](const std::vector<double>& x, std::vector<double>& y) {
    apply_s(x, sx);
    apply_s(sx, y);
    for (std::size_t k = 0; k < m; ++k) y[k] = alpha * alpha * x[k] - y[k];
  };

  std::vector<double>& x = res.control_vertices;
  // Below rounding level an inner CG cannot get: never ask for it.
  const double floor = mon.floor();
  double e = residual(op, v0, x.data(), nullptr, kc);
  if (mon.start(e)) return;
  for (;;) {
    const double inner_tol = std::max(1e-3 * e, floor);
    // (alpha I + H) U = (alpha I - S) X + V0
    apply_s(x, tmp);
    res.products += 2;
    for (std::size_t k = 0; k < m; ++k) rhs[k] = alpha * x[k] - tmp[k] + v0[k];
    u = x;
    res.products += inner_cg(op.n, kc, m1, 2, ones, rhs, u, inner_tol, r, p, q);
    // (alpha I + S) Xn = (alpha I - H) U + V0 =: c, via (alpha^2 I - S^2) Xn = (alpha I - S) c
    apply_h(u, tmp);
    for (std::size_t k = 0; k < m; ++k) tmp[k] = alpha * u[k] - tmp[k] + v0[k];
    apply_s(tmp, rhs);
    res.products += 4;
    for (std::size_t k = 0; k < m; ++k) rhs[k] = alpha * tmp[k] - rhs[k];
    xn = x;
    res.products += inner_cg(op.n, kc, m2, 4, ones, rhs, xn, alpha * inner_tol, r, p, q);
    for (std::size_t k = 0; k < m; ++k) x[k] += weight * (xn[k] - x[k]);
    e = residual(op, v0, x.data(), nullptr, kc);
    ++res.products;
    if (mon.record(e)) return;
  }
}

}  // namespace detail
}  // namespace sorpia
