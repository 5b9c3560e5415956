#pragma once
/// @file approximation.hpp
/// Approximation's pipeline, as sorpia::Interpolator is interpolation's:
/// options in, a result out, every step in the core (docs/approximation.md).
/// A cage's control vertices V (fixed faces and rules) are moved so that its
/// limit surface lies closest to data points P in the least-squares sense:
///
///   1. footpoints: each point's closest point of the surface as (face, u, v)
///      (closest_points: the nearest of a grid of limit points, then
///      Gauss-Newton), record 0;
///   1b. coarse iterations first (coarse_iterations > 0, iterations above
///      window + 1, and a sample of at most half the points): steps 1-3 on a fixed sample of the points
///      (PointChunks::set_sample: coarse_points per control vertex a face
///      uses), without the stop rule, until coarse_iterations of them ran
///      or one lowered the sample's lowest criterion by at most coarse_tol
///      of it (its record then not made of the sample); then the
///      footpoints of all points searched afresh (step 1) for the iterate
///      they reached, the last coarse iteration's record; steps 2-4 go on
///      from there on all points;
///   2. per iteration: the rows A of the surface at the footpoints
///      (LimitSurface::position_blocks, a face's points at a time, each
///      block multiplied out by NormalBlocks as it is made), the normal equations
///      (A^T W A + c K + mu I) V = A^T W P + mu V_prev (W the points' weights,
///      blended towards the normals by `tangential`: blend_weights; K the
///      thin-plate energy of the cage at depth 0, c = fairness times the
///      mean diagonal of A^T W A, mu = proximal times it), solved by PCG
///      (NormalEquations) or by LSPIA (Deng and Lin 2014);
///   3. the footpoints re-projected from where they were (refine_footpoints),
///      a record (RMS and largest distance data to surface at the
///      footpoints; surface to data, from a uniform tessellation's vertices,
///      only with report_each, else for the returned iterate at the end);
///   4. the stop rule: the lowest RMS so far fell by at most `tol` of itself
///      per iteration over the last `window` iterations, and a fresh search
///      of every footpoint (closest_points again) finds none closer that
///      lowers the RMS by more than `tol` (it goes on from the closer ones
///      when it does), or the RMS is at rounding level (`exact` of the
///      diagonal), or `iterations` ran out.
///
/// The control vertices of the lowest RMS are returned, with their
/// footpoints searched for afresh (closest_points, any closer one kept) and
/// their record measured again from them: re-projection keeps a point in a
/// local minimum of its distance, a fresh search finds the closer surface. Data beyond 2^+-200
/// in magnitude is fitted scaled by a power of two (sorpia/detail/scaling.hpp,
/// exact); records and results are in the caller's units.

#include <cstddef>
#include <cstdint>
#include <functional>
#include <string>
#include <vector>

#include "sorpia/footpoints.hpp"
#include "sorpia/robust.hpp"
#include "sorpia/point_chunks.hpp"
#include "sorpia/surface.hpp"

namespace sorpia {

/// How each iteration solves its normal equations.
enum class ApproximationUpdate {
  CG,     ///< the fitting layer's PCG (NormalEquations::solve)
  LSPIA,  ///< x += D^-1 (rhs - M x), D the row sums of |M| (tangential 1 only)
};

/// The options of approximate (checked there, before any work).
struct ApproximationOptions {
  int iterations = 10;            ///< updates at most (the coarse ones included), >= 1
  /// Updates on the sample first (step 1b), >= 0: at most this many, and at
  /// most iterations - window - 1 (window + 1 updates at least on all
  /// points: the first takes back what the sample's fit made of the sample's
  /// own points, the stop rule's window follows); fewer where coarse_tol
  /// ends them; 0: none.
  int coarse_iterations = 6;
  /// The sample's size in points per control vertex a face uses, finite,
  /// > 0; no coarse iterations when it would hold more than half the points.
  double coarse_points = 16.0;
  /// The coarse updates end after one that lowered the sample's lowest
  /// criterion (the stop rule's: RMS, or the robust loss) by at most this
  /// fraction of it (rms_levelled over one iteration), finite, >= 0; 0: only
  /// after one that did not lower it. A fit that falls this little is near
  /// the floor the data's noise sets, where the sample's fit follows the
  /// sample's noise (step 1b).
  double coarse_tol = 1e-2;
  double tol = 3e-3;              ///< the stop rule's fall per iteration (step 4), finite, >= 0
  double fairness = 3e-4;         ///< c over the mean diagonal of A^T W A, finite, >= 0; 0: no K
  double tangential = 0.1;        ///< in [0, 1]: 1 point distance, 0 tangent distance, between a blend
  ApproximationUpdate update = ApproximationUpdate::CG;
  double solver_tol = 1e-3;       ///< each update's residual over its start's, finite, >= 0
  long long solver_max_iter = 2000;  ///< iterations per update at most, >= 1
  /// The footpoint search: grid 1..64 (samples per side of a face), max_steps
  /// >= 1 (Gauss-Newton steps per projection).
  FootpointOptions footpoints{4, 10};
  int report_level = 2;           ///< the tessellation level of the surface-to-data distances, 0..15
  /// The surface-to-data distances in every record (true), or only in the
  /// returned iterate's, measured at the end (false: NaN in the others).
  bool report_each = false;
  int fairness_depth = 0;         ///< K's quadrature depth (a regulariser: its cost, not its exactness, counts)
  double proximal = 1e-6;         ///< mu over the mean diagonal of A^T W A, > 0
  int window = 3;                 ///< the stop rule's iterations, >= 1
  double exact = 1e-13;           ///< an RMS below this fraction of the diagonal stops ("exact")
  double closer = 1e-10;          ///< a fresh footpoint replaces one farther by more than this fraction of the diagonal
  /// The robust weights (sorpia/robust.hpp): before each update every
  /// point's weight times robust_factors of its footpoint distance at the
  /// scale of that iteration's distances; with a loss other than None the
  /// criterion sqrt(RobustSums::loss / k) replaces the RMS distance in the
  /// stop rule and the choice of the iterate returned (the records keep
  /// the RMS distance of all the points).
  RobustOptions robust = robust_options(RobustLoss::Tukey);
  /// Points per chunk of an in-memory array (point_chunks.hpp), >= 1: the
  /// unit of the footpoints and of the normal sums, added in order.
  std::size_t chunk_points = std::size_t{1} << 20;
};

/// One iteration's figures (iteration 0: the cage as given).
struct ApproximationRecord {
  int iteration = 0;
  /// The points its figures are of: all, or the coarse iterations' sample's
  /// (step 1b; their last update's figures are of all points).
  std::size_t points = 0;
  /// Data to surface: the (weighted) RMS and the largest footpoint distance;
  /// surface to data: from the tessellation's vertices to the nearest point
  /// (NaN where not measured: ApproximationOptions::report_each).
  /// In the caller's units, and over the data's bounding-box diagonal.
  double rms = 0.0, max = 0.0, surface_rms = 0.0, surface_max = 0.0;
  double rms_relative = 0.0, max_relative = 0.0, surface_rms_relative = 0.0, surface_max_relative = 0.0;
  /// With a robust loss (0 without), at these distances and robust_scale:
  /// the criterion sqrt(RobustSums::loss / k), the RMS distance of the
  /// points within the cut c s (the data the fit keeps; 0 when none is), in
  /// the caller's units and over the diagonal, and the points beyond it.
  double robust_loss = 0.0, robust_loss_relative = 0.0, inlier_rms = 0.0, inlier_rms_relative = 0.0;
  long long robust_cut = 0;
  /// With a robust loss: the scale s of these distances, which weighs the
  /// points in the next update (ApproximationOptions::robust); 0 without.
  double robust_scale = 0.0;
  /// How far the update before it moved the control vertices (those a face
  /// uses), over the diagonal: the largest move and the RMS move (0 at
  /// iteration 0).
  double move_max_relative = 0.0, move_rms_relative = 0.0;
  long long solver_iterations = 0;  ///< of the update before it (0 at iteration 0)
  double seconds = 0.0;             ///< since approximate was called
};

/// Seconds per phase (wall clock, or the process's CPU time on all threads).
struct ApproximationTimings {
  double footpoints = 0.0, rows = 0.0, normal = 0.0, solve = 0.0, report = 0.0, total = 0.0;
};

/// What approximate returns, in the caller's units.
struct ApproximationResult {
  std::vector<double> control_vertices;  ///< (n, 3) row-major: V of the lowest RMS
  /// The footpoints on that V's surface after the final fresh search:
  /// face_ids, uv and distances (the other fields empty).
  Footpoints footpoints;
  int iterations = 0;      ///< updates made (the coarse ones included)
  int coarse_iterations = 0;  ///< of them on the sample (step 1b)
  /// "converged", "exact" or "max_iter" (`iterations` ran out; step 4).
  std::string stop_reason;
  int best_iteration = 0;  ///< the iteration whose V is returned
  double diagonal = 0.0;   ///< of the data's bounding box: the unit of the relative figures
  /// The robust scale s at the returned iterate's footpoints (0 without a
  /// robust loss), and how many points (of weight > 0) lie farther than c s
  /// from it (with Tukey: the points that do not pull at all): its record's
  /// robust_scale and robust_cut, measured before the final search.
  double robust_scale = 0.0;
  long long robust_outliers = 0;
  std::vector<ApproximationRecord> history;
  ApproximationTimings seconds, cpu_seconds;
};

/// The stop rule's first test (step 4): on the lowest RMS after each
/// iteration so far (non-increasing; bests[0] the cage's as given), true when
/// over the last `window` iterations it fell by at most tol of itself per
/// iteration on average (with tol 0: not at all). One small step between
/// large ones does not stop a run; fewer than window + 1 entries never do.
bool rms_levelled(const std::vector<double>& bests, double tol, int window);

/// Called with each record as soon as it is known (an exception from it
/// ends the run and propagates).
using ApproximationProgress = std::function<void(const ApproximationRecord&)>;

/// Fits the cage of `surface` to the points (steps above), from the
/// surface's current control vertices.
/// @param surface   the cage's limit surface; on return it holds the
///                  returned control vertices
/// @param points    row-major (k, 3), finite
/// @param k         >= 1
/// @param weights   k finite weights >= 0, not all 0, in the fit and in the
///                  RMS (weighted: sum w d^2 / k, so scale them to mean 1),
///                  or nullptr for equal ones
/// @param progress  empty, or called with each record
/// The surface-to-data distances leave out the control vertices no face
/// uses (they are no point of the surface).
/// @throws ParameterError for an option out of range, a weight not finite
///         or negative, or all 0; MeshError for no point, a point not
///         finite, points all at one place (one point, or all duplicates) or
///         all on one line (no surface is determined by them), and as the
///         surface's evaluation
ApproximationResult approximate(LimitSurface& surface, const double* points, std::size_t k, const double* weights,
                                const ApproximationOptions& options, const ApproximationProgress& progress = {});

/// The same fit (the one driver) over points held by a backend (PointChunks:
/// in memory, streamed from a file, or elsewhere) whose chunks run on
/// `surface` or on copies of it kept at the control vertices the driver
/// sets. The backend's footpoint states move with the driver's calls; its
/// sums are added in its chunks' order. With FileChunks the result's
/// footpoints are empty, and the surface-to-data report uses its sample.
ApproximationResult approximate(LimitSurface& surface, PointChunks& chunks, const ApproximationOptions& options,
                                const ApproximationProgress& progress = {});

}  // namespace sorpia
