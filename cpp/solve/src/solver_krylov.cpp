// Krylov and splitting methods: "cg" (CG on the symmetrised system, BiCGSTAB
// where boundaries break the symmetry), "gmres" (any invertible B), "cgls"
// (least squares, any B) and "hss"/"whss" (Bai, Golub and Ng 2003).
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

// x += a p, r -= a q per column, a = num / den (0 where den = 0).
void step_along(const Cols& num, const Cols& den, const std::vector<double>& p, const std::vector<double>& q,
                std::vector<double>& x, std::vector<double>& r) {
  const std::size_t kc = num.size();
  Cols a(kc), na(kc);
  for (std::size_t c = 0; c < kc; ++c) {
    a[c] = safe_div(num[c], den[c]);
    na[c] = -a[c];
  }
  axpy(a, p, x);
  axpy(na, q, r);
}

// The rest of a CG iteration once q = M p (M self-adjoint in the w-weighted
// inner product), per column: x += a p, r -= a q, p = r + b p, with
// a = rr / <p, q>, b = rr_new / rr; rr = <r, r> is updated. A column already
// solved has rr = 0 and stays put.
void cg_step(const std::vector<double>& w, std::vector<double>& x, std::vector<double>& r, std::vector<double>& p,
             const std::vector<double>& q, Cols& rr) {
  const std::size_t kc = rr.size();
  step_along(rr, wdot(p, q, w, kc), p, q, x, r);
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

// Columns' Euclidean norms.
Cols norms(const std::vector<double>& a, std::size_t kc) {
  Cols s = dot(a, a, kc);
  for (double& x : s) x = std::sqrt(x);
  return s;
}

// y = x / s per column (0 where s = 0: a solved column).
void scaled_copy(const std::vector<double>& x, const Cols& s, std::vector<double>& y) {
  const std::size_t kc = s.size();
  for (std::size_t k = 0; k < x.size(); k += kc)
    for (std::size_t c = 0; c < kc; ++c) y[k + c] = safe_div(x[k + c], s[c]);
}

// The longest GMRES basis: every vector is (n, k) doubles; the basis stays
// within gmres_basis_bytes, with at least gmres_restart vectors, and needs no
// more than n + 1 (full GMRES, exact in n steps).
std::size_t gmres_max_basis(std::size_t n, std::size_t kc) {
  const std::size_t by_memory = gmres_basis_bytes / (sizeof(double) * kc * std::max<std::size_t>(n, 1));
  return std::min<std::size_t>(n, std::max<std::size_t>(by_memory, gmres_restart + 1) - 1);
}

}  // namespace

// GMRES(m) (Saad and Schultz 1986) on D^-1 B V = D^-1 V0 (Jacobi
// preconditioning from the left, D = diag(B)), every column its own Krylov
// space and scalars, all k columns in one pass per Arnoldi step (modified
// Gram-Schmidt, Givens rotations). E_k is that of the current iterate at
// every Arnoldi step: its residual is V_{j+1} Q^T (g_{j+1} e_{j+1}) by the
// Arnoldi relation (updated by one vector operation a step), scaled back by
// D; where it says converged, and at the end
// of every cycle, the iterate is formed and its true residual computed (one
// product) and recorded, and the next cycle starts from it. The restart
// length starts at gmres_restart and doubles (up to gmres_max_basis) after a
// cycle that left the residual above gmres_grow_ratio of its start: on an
// indefinite B a short restart can slow down, full GMRES (length n) cannot,
// on an invertible B. A cycle
// that leaves the residual where it was (ratio above gmres_stall_ratio)
// stops as "stalled": B is singular (or numerically so) and the residual
// has reached the part of the targets outside its range, or, rarely, a
// restarted GMRES stagnates on an invertible B; "auto" then runs "cgls",
// which converges in both cases.
void solve_gmres(const LimitOperator& op, const double* v0, std::size_t kc, Monitor& mon, SolveResult& res) {
  const std::size_t n = op.n, len = kc * n;
  std::vector<double>& x = res.control_vertices;
  std::vector<double> r(len), w(len), z(len), zs(len);
  double e = residual(op, v0, x.data(), r.data(), kc);
  if (mon.start(e)) return;
  const std::size_t m_cap = std::max<std::size_t>(gmres_max_basis(n, kc), 1);
  std::size_t m = std::min<std::size_t>(gmres_restart, m_cap);
  std::vector<std::vector<double>> basis;
  std::vector<double> h, cs, sn, g, y;
  const auto scale_down = [&](std::vector<double>& a) {
    for (std::size_t i = 0; i < n; ++i)
      for (std::size_t c = 0; c < kc; ++c) a[kc * i + c] /= op.diag[i];
  };
  for (;;) {
    z = r;
    scale_down(z);
    zs = z;
    const Cols beta = norms(z, kc);
    while (basis.size() < m + 1) basis.emplace_back(len);
    scaled_copy(z, beta, basis[0]);
    // H column j, row i, column of the data c at h[(j (m + 1) + i) kc + c].
    h.assign((m + 1) * m * kc, 0.0);
    cs.assign(m * kc, 1.0);
    sn.assign(m * kc, 0.0);
    g.assign((m + 1) * kc, 0.0);
    for (std::size_t c = 0; c < kc; ++c) g[c] = beta[c];
    const auto H = [&](std::size_t i, std::size_t j, std::size_t c) -> double& { return h[(j * (m + 1) + i) * kc + c]; };
    std::size_t steps = 0;
    bool stop = false, checked = false;
    for (std::size_t j = 0; j < m; ++j) {
      apply_columns(op, kc, basis[j].data(), w.data());
      scale_down(w);
      ++res.products;
      for (std::size_t i = 0; i <= j; ++i) {
        const Cols hij = dot(w, basis[i], kc);
        Cols neg(kc);
        for (std::size_t c = 0; c < kc; ++c) {
          H(i, j, c) = hij[c];
          neg[c] = -hij[c];
        }
        axpy(neg, basis[i], w);
      }
      const Cols hn = norms(w, kc);
      scaled_copy(w, hn, basis[j + 1]);
      for (std::size_t c = 0; c < kc; ++c) {
        H(j + 1, j, c) = hn[c];
        for (std::size_t i = 0; i < j; ++i) {  // the earlier rotations on column j
          const double a = H(i, j, c), b = H(i + 1, j, c);
          H(i, j, c) = cs[i * kc + c] * a + sn[i * kc + c] * b;
          H(i + 1, j, c) = -sn[i * kc + c] * a + cs[i * kc + c] * b;
        }
        const double a = H(j, j, c), b = H(j + 1, j, c), rr = std::hypot(a, b);
        cs[j * kc + c] = rr > 0.0 ? a / rr : 1.0;
        sn[j * kc + c] = rr > 0.0 ? b / rr : 0.0;
        H(j, j, c) = rr;
        H(j + 1, j, c) = 0.0;
        g[(j + 1) * kc + c] = -sn[j * kc + c] * g[j * kc + c];
        g[j * kc + c] *= cs[j * kc + c];
      }
      steps = j + 1;
      // The scaled residual of the step's iterate, V_{j+1} Q^T (g_{j+1} e_{j+1}),
      // by its recurrence z_j = s_j^2 z_{j-1} + c_j g_{j+1} v_{j+1} (z_{-1} = D^-1 r).
      for (std::size_t k = 0; k < len; k += kc)
        for (std::size_t c = 0; c < kc; ++c) {
          const double sj = sn[j * kc + c];
          zs[k + c] = sj * sj * zs[k + c] + cs[j * kc + c] * g[(j + 1) * kc + c] * basis[j + 1][k + c];
        }
      z = zs;
      for (std::size_t i = 0; i < n; ++i)
        for (std::size_t c = 0; c < kc; ++c) z[kc * i + c] *= op.diag[i];
      e = max_row_norm(z.data(), n, kc);
      if (mon.converges(e) || j + 1 == m) {
        checked = true;
        break;
      }
      if ((stop = mon.record(e))) break;
    }
    // x += V y, H y = g (upper triangular after the rotations).
    y.assign(steps * kc, 0.0);
    for (std::size_t c = 0; c < kc; ++c)
      for (std::size_t i = steps; i-- > 0;) {
        double s = g[i * kc + c];
        for (std::size_t l = i + 1; l < steps; ++l) s -= H(i, l, c) * y[l * kc + c];
        y[i * kc + c] = safe_div(s, H(i, i, c));
      }
    for (std::size_t i = 0; i < steps; ++i) axpy(Cols(y.begin() + i * kc, y.begin() + (i + 1) * kc), basis[i], x);
    if (stop) return;
    if (checked) {
      e = residual(op, v0, x.data(), r.data(), kc);
      ++res.products;
      if (mon.record(e)) return;
    }
    // How far the cycle brought the scaled residual down (the worst column).
    z = r;
    scale_down(z);
    const Cols after = norms(z, kc);
    double ratio = 0.0;
    for (std::size_t c = 0; c < kc; ++c)
      if (beta[c] > 0.0) ratio = std::max(ratio, after[c] / beta[c]);
    if (ratio > gmres_stall_ratio) {
      mon.finish(StopReason::Stalled);
      return;
    }
    if (ratio > gmres_grow_ratio && m < m_cap) m = std::min(2 * m, m_cap);
  }
}

// CGLS (Hestenes and Stiefel 1952; LSQR's iterates, Paige and Saunders 1982):
// CG on B^T B V = B^T V0, from the start in res.control_vertices, every
// column its own scalars; two products per iteration (B and B^T). The
// limit is the least-squares solution nearest the start, whatever the rank
// of B: from V = 0 ("auto" starts it there) the iterates stay in the range
// of B^T, and the limit is the least-squares solution of least norm. E_k is that of the updated
// residual r = V0 - B V (the true one where it says converged). Stops as
// "singular" where r is orthogonal to B's range as far as doubles tell,
// ||B^T r|| <= cgls_singular_angle ||B|| ||r|| in every column (LSQR's test),
// with E_k / E_0 still above tol: the part of V0 outside the range of B,
// which cannot be interpolated. On an invertible B, ||B^T r|| >= ||r|| /
// ||B^-1||, so that test holds only where cond(B) > 1 / cgls_singular_angle.
void solve_cgls(const LimitOperator& op, const double* v0, std::size_t kc, Monitor& mon, SolveResult& res) {
  const std::size_t len = kc * op.n;
  const Transposed tr = transpose(op);
  std::vector<double>& x = res.control_vertices;
  std::vector<double> r(len), s(len), p(len), q(len);
  double e = residual(op, v0, x.data(), r.data(), kc);
  if (mon.start(e)) return;
  apply_transpose_columns(op, tr, kc, r.data(), s.data());
  ++res.products;
  p = s;
  Cols ss = dot(s, s, kc);
  // ||B||_2 <= sqrt(||B||_1 ||B||_inf), from the row and column sums of |B|.
  std::vector<double> column_sums(op.n, 0.0);
  double row_max = 0.0;
  for (std::size_t i = 0; i < op.n; ++i) {
    double row = std::abs(op.diag[i]);
    column_sums[i] += std::abs(op.diag[i]);
    for (std::int32_t q = op.offsets[i]; q < op.offsets[i + 1]; ++q) {
      row += std::abs(op.entry(i, q));
      column_sums[op.neighbors[q]] += std::abs(op.entry(i, q));
    }
    row_max = std::max(row_max, row);
  }
  const double norm_b = std::sqrt(row_max * *std::max_element(column_sums.begin(), column_sums.end()));
  for (;;) {
    apply_columns(op, kc, p.data(), q.data());
    step_along(ss, dot(q, q, kc), p, q, x, r);
    e = max_row_norm(r.data(), op.n, kc);
    if (mon.converges(e)) {
      e = residual(op, v0, x.data(), r.data(), kc);
      ++res.products;
    }
    apply_transpose_columns(op, tr, kc, r.data(), s.data());
    res.products += 2;
    const Cols ss_new = dot(s, s, kc), rr = dot(r, r, kc);
    bool solved = true;
    for (std::size_t c = 0; c < kc; ++c) {
      const double b = safe_div(ss_new[c], ss[c]);
      for (std::size_t k = c; k < len; k += kc) p[k] = s[k] + b * p[k];
      solved = solved && std::sqrt(ss_new[c]) <= cgls_singular_angle * norm_b * std::sqrt(rr[c]);
    }
    ss = ss_new;
    if (mon.record(e)) return;
    if (solved) {
      mon.finish(StopReason::Singular);
      return;
    }
  }
}

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
