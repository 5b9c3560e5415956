#include "fairness_terms.hpp"

#include <cmath>
#include <cstdint>
#include <string>
#include <vector>

#include "sorpia/errors.hpp"

namespace sorpia::fairness_detail {

std::vector<Term> energy_terms(Scheme scheme, double thin_plate, double membrane) {
  std::vector<Term> terms;
  if (scheme == Scheme::Loop) {
    // (x, y) = (u + v/2, v sqrt(3)/2): d/dx = d/du, d/dy = (2 d/dv - d/du) / sqrt(3).
    const double r3 = 1.0 / std::sqrt(3.0);
    if (thin_plate > 0.0) {
      terms.push_back({{0, 0, 1, 0, 0}, thin_plate});                              // xx
      terms.push_back({{0, 0, -r3, 2 * r3, 0}, 2.0 * thin_plate});                 // xy
      terms.push_back({{0, 0, 1.0 / 3.0, -4.0 / 3.0, 4.0 / 3.0}, thin_plate});     // yy
    }
    if (membrane > 0.0) {
      terms.push_back({{1, 0, 0, 0, 0}, membrane});        // x
      terms.push_back({{-r3, 2 * r3, 0, 0, 0}, membrane});  // y
    }
    return terms;
  }
  if (thin_plate > 0.0) {
    terms.push_back({{0, 0, 1, 0, 0}, thin_plate});
    terms.push_back({{0, 0, 0, 1, 0}, 2.0 * thin_plate});
    terms.push_back({{0, 0, 0, 0, 1}, thin_plate});
  }
  if (membrane > 0.0) {
    terms.push_back({{1, 0, 0, 0, 0}, membrane});
    terms.push_back({{0, 1, 0, 0, 0}, membrane});
  }
  return terms;
}

// The terms of the energy of face f measured in a fixed first fundamental
// form G of the reference surface (fairness_matrix's reference): with G^-1 =
// L L^T (L lower triangular), tr(G^-1 H G^-1 H) = |L^T H L|_F^2 and
// tr(G^-1 J^T J) = |J L|_F^2, each term weighted by sqrt(det G).
std::vector<Term> metric_terms(const double g[3], double thin_plate, double membrane) {
  const double det = g[0] * g[2] - g[1] * g[1];
  // G^-1 = [[g2, -g1], [-g1, g0]] / det; its Cholesky factor
  const double i00 = g[2] / det, i01 = -g[1] / det, i11 = g[0] / det;
  const double l11 = std::sqrt(i00), l21 = i01 / l11, l22 = std::sqrt(i11 - l21 * l21);
  const double area = std::sqrt(det);
  std::vector<Term> terms;
  if (thin_plate > 0.0) {
    terms.push_back({{0, 0, l11 * l11, 2 * l11 * l21, l21 * l21}, thin_plate * area});  // (L^T H L)_11
    terms.push_back({{0, 0, 0, l22 * l11, l22 * l21}, 2.0 * thin_plate * area});        // (L^T H L)_12
    terms.push_back({{0, 0, 0, 0, l22 * l22}, thin_plate * area});                      // (L^T H L)_22
  }
  if (membrane > 0.0) {
    terms.push_back({{l11, l21, 0, 0, 0}, membrane * area});
    terms.push_back({{0, l22, 0, 0, 0}, membrane * area});
  }
  return terms;
}

// Per face, the terms of fairness_matrix's reference metric: G the first
// fundamental form of the limit surface of `reference` at the face's
// centre; at a face with an extraordinary corner (inside the mesh, valence
// other than the scheme's), where Bfr's parameterisation is far from affine
// within the face and a constant G would charge that, the face's parametric
// shape (the unit square, or the equilateral triangle of Loop) scaled to the
// area sqrt(det G).
std::vector<std::vector<Term>> reference_terms(const LimitSurface& surface, const double* reference,
                                               const std::vector<std::uint8_t>& hole, double thin_plate,
                                               double membrane) {
  const Topology& t = surface.topology();
  const bool loop = surface.scheme() == Scheme::Loop;
  const std::int32_t size = loop ? 3 : 4, regular_valence = loop ? 6 : 4;
  std::vector<std::int32_t> faces;
  std::vector<double> uv;
  for (std::size_t f = 0; f < t.n_faces(); ++f) {
    if (hole[f]) continue;
    if (t.face_size(f) != size)
      throw ParameterError("the reference metric needs a mesh of " + std::string(loop ? "triangles" : "quads") +
                           ": face " + std::to_string(f) + " has " + std::to_string(t.face_size(f)) +
                           " corners (refine the mesh first)");
    faces.push_back(static_cast<std::int32_t>(f));
    uv.insert(uv.end(), {loop ? 1.0 / 3.0 : 0.5, loop ? 1.0 / 3.0 : 0.5});
  }
  const SurfaceRows rows = surface.rows(faces.data(), uv.data(), faces.size(), 1);
  const auto& fi = t.face_indices();
  auto times_reference = [&](const CsrMatrix& m, std::size_t q, double out[3]) {
    for (auto p = static_cast<std::size_t>(m.indptr[q]); p < static_cast<std::size_t>(m.indptr[q + 1]); ++p)
      for (std::size_t c = 0; c < 3; ++c) out[c] += m.data[p] * reference[3 * static_cast<std::size_t>(m.indices[p]) + c];
  };
  std::vector<std::vector<Term>> out(t.n_faces());
  for (std::size_t q = 0; q < faces.size(); ++q) {
    const auto f = static_cast<std::size_t>(faces[q]);
    double su[3] = {0, 0, 0}, sv[3] = {0, 0, 0};
    times_reference(rows.du, q, su);
    times_reference(rows.dv, q, sv);
    double g[3] = {su[0] * su[0] + su[1] * su[1] + su[2] * su[2], su[0] * sv[0] + su[1] * sv[1] + su[2] * sv[2],
                   sv[0] * sv[0] + sv[1] * sv[1] + sv[2] * sv[2]};
    // A guard against a degenerate G (a reference face folded flat): a floor
    // of 1e-9 of its trace on both axes.
    const double trace = g[0] + g[2];
    if (!(trace > 0.0) || !std::isfinite(trace))
      throw ParameterError("the reference surface is degenerate at face " + std::to_string(f) +
                           ": its derivatives there are zero or not finite");
    g[0] += 1e-9 * trace;
    g[2] += 1e-9 * trace;
    bool extraordinary = false;
    for (std::int32_t i = 0; i < size; ++i) {
      const auto v = static_cast<std::size_t>(fi[static_cast<std::size_t>(t.face_offset(f) + i)]);
      if (!t.is_boundary(v) && t.valence(v) != regular_valence) extraordinary = true;
    }
    if (extraordinary) {
      const double area = std::sqrt(g[0] * g[2] - g[1] * g[1]);
      // unit square: I; Loop's equilateral triangle in (u, v): [[1, 1/2], [1/2, 1]] / sqrt(3/4), determinant 1
      const double k = loop ? area / std::sqrt(0.75) : area;
      g[0] = k;
      g[1] = loop ? 0.5 * k : 0.0;
      g[2] = k;
    }
    out[f] = metric_terms(g, thin_plate, membrane);
  }
  return out;
}

}  // namespace sorpia::fairness_detail
