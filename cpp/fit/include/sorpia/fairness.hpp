#pragma once
/// @file fairness.hpp
/// The fairness energy of a limit surface as a sparse symmetric quadratic
/// form in its control vertices (Halstead, Kass & DeRose 1993): the matrix K
/// with E(V) = sum over the columns c of V[:, c]^T K V[:, c], shared by fair
/// interpolation and by approximation's fairness term.

#include "sorpia/limit.hpp"  // CsrMatrix
#include "sorpia/surface.hpp"

namespace sorpia {

/// How the energy is integrated over each face (checked by fairness_matrix).
struct FairnessQuadrature {
  /// Gauss-Legendre points per direction on every piece: n x n on a square,
  /// the collapsed (Duffy) n x n rule on a triangle. Exact for polynomials of
  /// degree 2n - 1 in each variable on squares and of total degree 2n - 2 on
  /// triangles: 4 integrates both terms exactly on regular patches (bicubic
  /// B-splines, Loop's quartic box splines). 1..16.
  int gauss_points = 4;
  /// Dyadic refinements of the face domain towards its irregular corners
  /// (extraordinary, boundary, tagged or hole vertices; a Catmull-Clark
  /// k-gon's centre) and its tagged edges: the piece that touches one is
  /// split in four, `depth` times. 4 matches the rings of polynomial pieces
  /// Bfr builds before its Gregory patch at such a corner (surface.hpp), so
  /// every ring but that last corner piece is integrated exactly. 0..12.
  int depth = 4;
};

/// The fairness matrix K (n_vertices x n_vertices, symmetric, positive
/// semidefinite, columns sorted within a row) of the surface's topology and
/// rules (its control vertices do not enter):
///
///   V^T K V = thin_plate * integral (|S_xx|^2 + 2 |S_xy|^2 + |S_yy|^2)
///           + membrane   * integral (|S_x|^2 + |S_y|^2)
///
/// over the faces' parameter domains (holes left out), S the limit surface of
/// control values V (one column). The measure: Bfr's parameterisation
/// (surface.hpp) for Catmull-Clark, x = u, y = v, so a quad's unit square has
/// area 1 and each of a k-gon's k sub-faces (squares of side 1/2) area 1/4,
/// what the quarter of a quad has: a k-gon counts as k/4 quads, as after one
/// subdivision step. Loop: each triangle mapped onto the equilateral triangle
/// of side 1 (x = u + v/2, y = v sqrt(3)/2, area sqrt(3)/4), so that K does not
/// depend on which corner a triangle lists first.
///
/// Assembled from the derivative rows of LimitSurface::rows (Bfr's stencils)
/// at the quadrature points of FairnessQuadrature: K = sum over points q of
/// w_q (thin_plate (Dxx^T Dxx + 2 Dxy^T Dxy + Dyy^T Dyy) + membrane (Dx^T Dx +
/// Dy^T Dy)), one dense element matrix per face, merged per row; threads from
/// the core's pool. Exact (to rounding) on regular faces; near extraordinary
/// vertices the integral is that of Bfr's surface (rings of polynomial
/// pieces, a Gregory patch in the last corner piece), whose parametric
/// second derivatives grow without bound at an extraordinary vertex whose
/// subdominant eigenvalue exceeds 1/2 (Catmull-Clark valence 5 and more, Loop
/// 7 and more): there the thin-plate integral of the exact limit surface
/// diverges, and K measures Bfr's approximation at its refinement level.
/// Constant V is in K's null space; so are the affine functions of the
/// parameter wherever every face is regular (a flat regular grid).
/// @param surface     the topology and rules (its vertices are not used)
/// @param thin_plate  weight of the thin-plate term, finite, >= 0
/// @param membrane    weight of the membrane term, finite, >= 0; not both 0
/// @param quadrature  the rule on each face
/// @throws ParameterError naming the weight or option out of range
CsrMatrix fairness_matrix(const LimitSurface& surface, double thin_plate, double membrane,
                          const FairnessQuadrature& quadrature = FairnessQuadrature{});

}  // namespace sorpia
