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
  /// Reuse element matrices: the energy of a face as a quadratic form over
  /// its control points (listed in an order fixed by the local topology:
  /// from the one-ring where every corner is interior, else Bfr's) depends
  /// only on the face's local topology, so faces that agree in it (the
  /// face's size and, for Bfr's lists, Bfr's IsRegular(), the number of its
  /// control points, and per corner its valence, whether it is on the
  /// boundary and, there, where the face lies in its fan, and where Bfr's
  /// list names a vertex twice, the places of the repeats) share one, computed
  /// once. Faces whose control points touch a
  /// tag, a hole or a face of another size than the scheme's (triangles for
  /// Loop, quads for Catmull-Clark) are integrated on their own. false integrates every face on its own: the same K to
  /// rounding, much slower (what the tests compare against).
  bool reuse = true;
};

/// The fairness matrix K (n_vertices x n_vertices, symmetric, positive
/// semidefinite, columns sorted within a row unless sorted_columns is
/// false) of the surface's topology and
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
/// Assembled from the derivative rows of LimitSurface::rows (Bfr's stencils),
/// one dense element matrix per face (one per local topology with
/// FairnessQuadrature::reuse), summed row by row straight into the CSR;
/// threads from the core's pool. Each face's domain is split `depth` times
/// towards its marks;
/// a Catmull-Clark piece away from them (down to Bfr's isolation level 4) is
/// a bicubic B-spline piece, integrated in closed form from the derivative
/// rows at 2 x 2 points; every other piece (Loop's, those at the marks) by
/// the Gauss rule: K = sum over points q of w_q (thin_plate (Dxx^T Dxx + 2
/// Dxy^T Dxy + Dyy^T Dyy) + membrane (Dx^T Dx + Dy^T Dy)). Exact (to rounding)
/// on regular faces and on the rings of polynomial pieces next to an
/// extraordinary vertex; the corner piece (Bfr's Gregory patch) is
/// approximated by the Gauss rule. The integral is that of Bfr's surface: at
/// an extraordinary vertex whose subdominant eigenvalue lambda exceeds 1/2
/// (Catmull-Clark valence 5 and more, Loop 7 and more) the thin-plate energy
/// of the exact limit surface's rings grows by 4 lambda^2 per ring, so its
/// integral diverges, and K measures Bfr's approximation at its isolation
/// level (4; 10 on meshes with darts).
/// Constant V is in K's null space; so are the affine functions of the
/// parameter wherever every face is regular (a flat regular grid).
/// @param surface     the topology and rules (its vertices are not used)
/// @param thin_plate  weight of the thin-plate term, finite, >= 0
/// @param membrane    weight of the membrane term, finite, >= 0; not both 0
///
/// With `reference` (n_vertices x 3, row-major) each face is measured in a
/// fixed first fundamental form G instead of its parameters: the face's
/// energy is the integral of tr(G^-1 H G^-1 H) sqrt(det G) (membrane:
/// tr(G^-1 J^T J) sqrt(det G)) per coordinate, H the Hessian and J the
/// Jacobian in Bfr's (u, v), G that of the limit surface of `reference` at
/// the face's centre; at a face with an extraordinary corner (inside the mesh,
/// valence other than 4 / 6), where Bfr's parameterisation is far from affine
/// within the face and a constant G would charge that, the face's parametric
/// shape (unit square; Loop's equilateral triangle) scaled to the area
/// sqrt(det G). Still a quadratic form in V; the thin-plate term is invariant
/// under rotations and uniform scalings of the coordinates (of V and
/// `reference` together). Every piece by the Gauss rule, every face on its
/// own (no shared element matrices). Needs a mesh of the scheme's faces only.
/// @param quadrature  the rule on each face
/// @param reference   nullptr: the parametric measure; else the reference control vertices
/// @param sorted_columns  false: each row's columns in the order the faces
///                    first give them (the same entries; for callers that
///                    only multiply with K, such as fair_solve, which then
///                    need not pay for the sorts)
/// @throws ParameterError naming the weight or option out of range; for a
///         reference, a face of another size or a degenerate reference face
CsrMatrix fairness_matrix(const LimitSurface& surface, double thin_plate, double membrane,
                          const FairnessQuadrature& quadrature = FairnessQuadrature{},
                          const double* reference = nullptr, bool sorted_columns = true);

/// K of a mesh's limit surface under `rules` (K does not depend on the control
/// vertices): the surface built here with zero vertices, for callers that hold
/// a topology and no surface (fair interpolation's fine mesh, the binding).
CsrMatrix fairness_matrix(const Topology& topology, const Rules& rules, double thin_plate, double membrane,
                          const FairnessQuadrature& quadrature = FairnessQuadrature{},
                          const double* reference = nullptr, bool sorted_columns = true);

}  // namespace sorpia
