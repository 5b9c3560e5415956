#pragma once
/// @file fair_interpolation.hpp
/// Fair interpolation's pipeline, as sorpia::Interpolator is interpolation's:
/// options in, a result out, every step in the core (Halstead, Kass and
/// DeRose 1993; docs/fair.md).
///
///   1. the plain interpolation of every input vertex on the input mesh
///      (Interpolator::solve), V_plain;
///   2. the input mesh refined `levels` times uniformly by Far
///      (refine_uniform): the fine faces, their tags, and the start R V_plain
///      (the plain surface on the fine mesh, which meets the constraints);
///   3. the fairness matrix K of the fine mesh (fairness_matrix, with its
///      semi-sharp tags taken as infinitely sharp unless asked otherwise,
///      energy_tags), in the parametric metric or in that of the input
///      surface (the reference R V0);
///   4. the least energy with the targets' children on their targets
///      (fair_solve: the constraints eliminated exactly, then PCG).
///
/// Data beyond 2^+-200 in magnitude is solved scaled by a power of two
/// (sorpia/detail/scaling.hpp, exact) and returned in the caller's units.

#include <cstddef>
#include <cstdint>

#include "sorpia/fair.hpp"
#include "sorpia/interpolator.hpp"
#include "sorpia/refine.hpp"
#include "sorpia/solvers.hpp"
#include "sorpia/subdivision.hpp"

namespace sorpia {

/// How the fairness energy takes semi-sharp creases and corners.
enum class SemiSharp {
  Sharp,     ///< every positive sharpness infinite: the bending measured on each side of a crease
  AsTagged,  ///< as tagged: the thin layer where a semi-sharp crease turns counts too
};

/// The tags the fairness energy integrates: `tags` as given (AsTagged, or no
/// semi-sharp tag at all), or with every positive sharpness made
/// kInfiniteSharpness (sharpness 0 stays smooth). Shared by fair
/// interpolation and approximation's fairness term.
Tags energy_tags(const Tags& tags, SemiSharp semi_sharp);

/// The options of fair_interpolate (checked there, before any work).
struct FairInterpolationOptions {
  /// Uniform refinement steps, 1..kMaxRefinementLevels.
  int levels = 1;
  /// The energy's weights (fairness_matrix), finite, >= 0, not both 0.
  double thin_plate = 1.0;
  double membrane = 0.0;
  /// The iteration's stop rule and limits (FairOptions: tol, window,
  /// max_iter, threads). `threads` also caps K's assembly.
  FairOptions solve;
  /// How K takes semi-sharp tags.
  SemiSharp semi_sharp = SemiSharp::Sharp;
  /// K's quadrature depth (FairnessQuadrature::depth), 0..12.
  int depth = 0;
  /// Measure each fine face in the first fundamental form of the input
  /// mesh's own limit surface (fairness_matrix's `reference`: R V0) rather
  /// than in its parameters. The membrane term is not scale-free: with data
  /// beyond 2^+-200 it is refused.
  bool reference_metric = false;
  /// The plain interpolation's solve (Interpolator::solve; check_options).
  SolveOptions plain;
};

/// What fair_interpolate returns, in the caller's units.
struct FairInterpolationResult {
  /// The plain interpolation (step 1), its control vertices in the caller's
  /// vertex order. Its solve kept its targets in the Interpolator.
  SolveResult plain;
  /// The fine mesh: faces (Far's level `levels`), n_vertices, tags and
  /// coarse_face; `vertices` empty (the start went into the solve); R in
  /// `refinement` only when the reference metric needed it, else empty.
  RefinedMesh fine;
  /// The fair solve (vertices (n_fine, 3), energies, energy, start_energy
  /// = the plain surface's energy, iterations, stop_reason, max_error,
  /// seconds and setup_seconds).
  FairSolution solution;
  double plain_seconds = 0.0;   ///< step 1 (the solve; the Interpolator's build is the caller's)
  double refine_seconds = 0.0;  ///< step 2 (with R when the reference metric needs it)
  double energy_seconds = 0.0;  ///< step 3
};

/// Fair interpolation of `v0` on the mesh of `coarse` (steps above).
/// @param coarse     the input mesh and its rules, B built (a manifold mesh:
///                   not a non-manifold split); its last targets become v0
/// @param v0         row-major (n, 3) vertices, n = coarse.n_vertices()
/// @param targets    the interpolated vertices, distinct, in [0, n) (their
///                   children's indices in the fine mesh too); nullptr:
///                   every vertex
/// @param n_targets  their count (ignored for nullptr)
/// @param options    checked before any work
/// @throws ParameterError for an option out of range, a target out of range
///         or repeated, a fine mesh too big (check_refinement), the
///         reference metric with a membrane term on data beyond 2^+-200, or
///         bad values of v0 (Interpolator::solve); MeshError when the refined
///         faces are not a face list sorpia can take (two triangles with the
///         same vertices in opposite orders) or OpenSubdiv refuses the mesh
FairInterpolationResult fair_interpolate(Interpolator& coarse, const double* v0, const std::int32_t* targets,
                                         std::size_t n_targets, const FairInterpolationOptions& options);

}  // namespace sorpia
