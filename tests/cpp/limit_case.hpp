#pragma once
// A test mesh with its limit matrix B from OpenSubdiv's Far Limit()
// (edge-and-corner boundary; the reference, independent of the solvers) and B
// as the solvers get it (sorpia::limit_operator), and the measures the solver
// tests compare results by.
#include <algorithm>
#include <cmath>
#include <cstdint>
#include <random>
#include <vector>

#include "sorpia/limit.hpp"
#include "sorpia/reference.hpp"
#include "sorpia/shapes.hpp"
#include "sorpia/solvers.hpp"
#include "sorpia/topology.hpp"

namespace sorpia_test {

struct LimitCase {
  const char* name;
  sorpia::Mesh mesh;
  sorpia::CsrMatrix b;
  sorpia::LimitOperator op;
};

inline LimitCase limit_case(const sorpia::Mesh& m, const char* name = "") {
  const sorpia::Topology topo(m);
  return LimitCase{name, m, sorpia::reference_limit_matrix(topo, sorpia::Boundary::EdgeAndCorner),
                   sorpia::limit_operator(topo, sorpia::Boundary::EdgeAndCorner)};
}

// B with each off-diagonal weight scaled by 1 + spread * u (u uniform in
// [-1, 1]), then the row's off-diagonal weights rescaled to their old sum:
// rows still sum to 1, the diagonal is unchanged, no two weights of a row
// are equal. sorpia::limit_operator(CsrMatrix) makes it an operator with
// per-entry weights (LimitOperator::values).
inline sorpia::CsrMatrix perturbed(sorpia::CsrMatrix b, double spread, unsigned seed) {
  std::mt19937 rng(seed);
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  for (std::size_t i = 0; i < b.n_rows; ++i) {
    double before = 0.0, after = 0.0;
    for (std::int32_t p = b.indptr[i]; p < b.indptr[i + 1]; ++p) {
      if (b.indices[p] == static_cast<std::int32_t>(i)) continue;
      before += b.data[p];
      b.data[p] *= 1.0 + spread * u(rng);
      after += b.data[p];
    }
    for (std::int32_t p = b.indptr[i]; p < b.indptr[i + 1]; ++p)
      if (b.indices[p] != static_cast<std::int32_t>(i)) b.data[p] *= before / after;
  }
  return b;
}

// y = A x for row-major (n, 3) x and y: the textbook CSR product.
inline void multiply(const sorpia::CsrMatrix& a, const double* x, double* y) {
  for (std::size_t i = 0; i < a.n_rows; ++i) {
    double s[3] = {0.0, 0.0, 0.0};
    for (std::int32_t p = a.indptr[i]; p < a.indptr[i + 1]; ++p)
      for (int c = 0; c < 3; ++c) s[c] += a.data[p] * x[3 * a.indices[p] + c];
    for (int c = 0; c < 3; ++c) y[3 * i + c] = s[c];
  }
}

// max_k |a_k - b_k|
inline double max_abs_diff(const std::vector<double>& a, const std::vector<double>& b) {
  double m = 0.0;
  for (std::size_t k = 0; k < a.size(); ++k) m = std::max(m, std::abs(a[k] - b[k]));
  return m;
}

// The paper's E = max_i ||v_i^0 - (B v)_i|| of control vertices v, with B the
// CSR matrix from OpenSubdiv (not the operator the solvers iterate with).
inline double error_from_scratch(const LimitCase& c, const std::vector<double>& v) {
  std::vector<double> bv(v.size());
  multiply(c.b, v.data(), bv.data());
  const std::vector<double>& v0 = c.mesh.vertices;
  double e = 0.0;
  for (std::size_t i = 0; i < c.op.n; ++i)
    e = std::max(e, std::hypot(v0[3 * i] - bv[3 * i], v0[3 * i + 1] - bv[3 * i + 1], v0[3 * i + 2] - bv[3 * i + 2]));
  return e;
}

}  // namespace sorpia_test
