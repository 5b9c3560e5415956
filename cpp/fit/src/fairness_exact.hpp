#pragma once
// The closed forms of fairness_matrix (fairness.cpp): the energy of a bicubic
// piece as a quadratic form in its derivatives at 2 x 2 points, and the small
// dense solve that builds it. Internal to the fit layer.

#include <cstddef>
#include <vector>

namespace sorpia::fairness_detail {

// Solves a x = b for the columns of b (n x m, row-major) in place, a (n x n)
// destroyed: Gauss-Jordan with partial pivoting, for the small fixed systems
// of ExactForms.
void solve_dense(std::vector<double> a, std::vector<double>& b, std::size_t n, std::size_t m);

// The energy of a bicubic piece as a quadratic form in its data: the
// derivatives (f_s, f_t, f_ss, f_st, f_tt) in the piece's local (s, t) on the
// unit square at the 2 x 2 points kSquareData. These 20 values determine a
// bicubic up to a constant (on each line t = t_j, f_s is the quadratic with
// those values and slopes, likewise f_t on s = s_i; a bicubic vanishing on
// the four lines is (s - s0)(s - s1)(t - t0)(t - t1) g with g bilinear, which
// f_st at the four points makes zero), and positions, whose weights are of
// order 1 where the energy's are of order h^2, are left out for accuracy.
// Q = C^T G C: C the least-squares data-to-coefficients map (exact on
// bicubics), G the energy's Gram matrix of the monomials (Gauss 4 x 4:
// exact). For a piece of side h the thin-plate form scales as h^-2, the
// membrane form stays.
struct ExactForms {
  static constexpr std::size_t kData = 20;
  std::vector<double> thin_plate, membrane;  // kData x kData

  ExactForms();
};

}  // namespace sorpia::fairness_detail
