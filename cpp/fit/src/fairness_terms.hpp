#pragma once
// The integrands of fairness_matrix (fairness.cpp): the energy at a point as
// weighted combinations of the derivative rows, in each scheme's parametric
// measure or in a reference surface's metric. Internal to the fit layer.

#include <cstdint>
#include <vector>

#include "sorpia/subdivision.hpp"
#include "sorpia/surface.hpp"

namespace sorpia::fairness_detail {

// The terms of the energy at a point, each a combination of the derivative
// rows (du, dv, duu, duv, dvv) with the weight it carries in the energy.
struct Term {
  double coef[5];
  double weight;
};

// The terms of the parametric energy (fairness.hpp's measure of each scheme).
std::vector<Term> energy_terms(Scheme scheme, double thin_plate, double membrane);

// The terms of the energy of face f measured in a fixed first fundamental
// form G of the reference surface (fairness_matrix's reference): with G^-1 =
// L L^T (L lower triangular), tr(G^-1 H G^-1 H) = |L^T H L|_F^2 and
// tr(G^-1 J^T J) = |J L|_F^2, each term weighted by sqrt(det G).
std::vector<Term> metric_terms(const double g[3], double thin_plate, double membrane);

// Per face, the terms of fairness_matrix's reference metric: G the first
// fundamental form of the limit surface of `reference` at the face's
// centre; at a face with an extraordinary corner (inside the mesh, valence
// other than the scheme's), where Bfr's parameterisation is far from affine
// within the face and a constant G would charge that, the face's parametric
// shape (the unit square, or the equilateral triangle of Loop) scaled to the
// area sqrt(det G).
std::vector<std::vector<Term>> reference_terms(const LimitSurface& surface, const double* reference,
                                               const std::vector<std::uint8_t>& hole, double thin_plate,
                                               double membrane);

}  // namespace sorpia::fairness_detail
