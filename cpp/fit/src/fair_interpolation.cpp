#include "sorpia/fair_interpolation.hpp"

#include <chrono>
#include <cmath>
#include <cstdio>
#include <numeric>
#include <string>
#include <utility>
#include <vector>

#include "sorpia/detail/parallel.hpp"
#include "sorpia/detail/repr.hpp"
#include "sorpia/detail/scaling.hpp"
#include "sorpia/errors.hpp"
#include "sorpia/fairness.hpp"
#include "sorpia/solvers.hpp"
#include "sorpia/detail/clock.hpp"

namespace sorpia {

namespace {

using detail::Clock;
using detail::seconds_since;

// The options' messages name the parameter, the value as Python's repr() writes it and the range allowed: the
// one check of each (the bindings and Python convert types only).
void check_weight(double w, const char* name) {
  if (!std::isfinite(w))
    throw ParameterError(std::string(name) + " must be a finite real number, got " + detail::repr(w));
  if (w < 0)
    throw ParameterError(std::string(name) + " = " + detail::repr(w) + " is negative: the energy's weights must be >= 0");
}

void check_options(const FairInterpolationOptions& o) {
  if (o.levels < 1 || o.levels > kMaxRefinementLevels)
    throw ParameterError("levels must be an integer in 1.." + std::to_string(kMaxRefinementLevels) + ", got " +
                         std::to_string(o.levels));
  check_weight(o.thin_plate, "thin_plate");
  check_weight(o.membrane, "membrane");
  if (o.thin_plate == 0 && o.membrane == 0)
    throw ParameterError("thin_plate and membrane are both 0: the energy would be zero for every surface; "
                         "give one of them a positive weight");
  if (o.depth < 0 || o.depth > 12) throw ParameterError("depth must be in 0..12, got " + std::to_string(o.depth));
  // tol, window, max_iter and threads: fair_solve's checks, made here before any work, with fair interpolation's
  // range of tol (a relative fall of the energy: below 1).
  if (!(o.solve.tol > 0.0 && o.solve.tol < 1.0))
    throw ParameterError("tol must be a real number in (0, 1), got " + detail::repr(o.solve.tol));
  if (o.solve.window < 1) throw ParameterError("window = " + std::to_string(o.solve.window) + " must be >= 1");
  if (o.solve.max_iter < 1)
    throw ParameterError("max_iter = " + std::to_string(o.solve.max_iter) + " must be an integer >= 1");
  if (o.solve.threads < 1 || o.solve.threads > max_threads)
    throw ParameterError("threads = " + std::to_string(o.solve.threads) + " must be an integer in 1.." +
                         std::to_string(max_threads));
  sorpia::check_options(o.plain);
}

// The targets: at least one, each in [0, n), none twice (the first repeat named with the index it repeats).
void check_targets(const std::int32_t* targets, std::size_t n_targets, std::size_t n) {
  if (n_targets == 0)
    throw ParameterError("targets is empty: give at least one vertex to interpolate (None: every vertex)");
  std::vector<std::int64_t> first(n, -1);
  for (std::size_t i = 0; i < n_targets; ++i) {
    const std::int32_t v = targets[i];
    if (v < 0 || static_cast<std::size_t>(v) >= n)
      throw ParameterError("targets[" + std::to_string(i) + "] = " + std::to_string(v) + " is out of range [0, " +
                           std::to_string(n) + ")");
    if (first[static_cast<std::size_t>(v)] >= 0)
      throw ParameterError("targets[" + std::to_string(i) + "] = " + std::to_string(v) + " repeats targets[" +
                           std::to_string(first[static_cast<std::size_t>(v)]) + "]");
    first[static_cast<std::size_t>(v)] = static_cast<std::int64_t>(i);
  }
}

// y = R x for x (n, 3): each row's products summed in R's column order from 0 (as scipy's csr_matvecs).
std::vector<double> times(const CsrMatrix& r, const double* x) {
  std::vector<double> y(3 * r.n_rows, 0.0);
  for (std::size_t i = 0; i < r.n_rows; ++i)
    for (std::int32_t p = r.indptr[i]; p < r.indptr[i + 1]; ++p) {
      const double a = r.data[static_cast<std::size_t>(p)];
      const double* xj = x + 3 * static_cast<std::size_t>(r.indices[static_cast<std::size_t>(p)]);
      for (int c = 0; c < 3; ++c) y[3 * i + static_cast<std::size_t>(c)] += a * xj[c];
    }
  return y;
}

}  // namespace

Tags energy_tags(const Tags& tags, SemiSharp semi_sharp) {
  if (semi_sharp == SemiSharp::AsTagged || tags.max_semi_sharpness() <= 0) return tags;
  Tags sharp = tags;
  for (double& s : sharp.crease_sharpness)
    if (s > 0) s = kInfiniteSharpness;
  for (double& s : sharp.corner_sharpness)
    if (s > 0) s = kInfiniteSharpness;
  return sharp;
}

FairInterpolationResult fair_interpolate(Interpolator& coarse, const double* v0, const std::int32_t* targets,
                                         std::size_t n_targets, const FairInterpolationOptions& options) {
  check_options(options);
  const Topology& topology = coarse.topology();
  const Rules& rules = coarse.rules();
  const std::size_t n = coarse.n_vertices();
  if (n != topology.n_vertices())
    throw ParameterError("fair interpolation needs a manifold mesh: the Interpolator solves a non-manifold split");
  std::vector<std::int32_t> all;
  if (targets == nullptr) {
    all.resize(n);
    std::iota(all.begin(), all.end(), 0);
    targets = all.data();
    n_targets = n;
  }
  check_targets(targets, n_targets, n);  // before any work
  check_refinement(topology, rules, options.levels);  // a fine mesh too big is refused before any work
  // The reference metric works on V0 / 2^e (detail/scaling.hpp): beyond 2^+-200 the metric's squares leave
  // double's range. Its thin plate does not change when the data and the reference are scaled together; the
  // membrane term grows with the square of the scale, so a membrane on such data is refused. Without the
  // reference, fair_solve scales its targets and start itself.
  int e = 0;
  if (options.reference_metric) {
    const double largest = detail::largest_magnitude(v0, 3 * n);
    e = detail::scale_exponent(largest);
    if (e != 0 && options.membrane > 0) {
      char figure[32];
      std::snprintf(figure, sizeof figure, "%.3g", largest);
      throw ParameterError(std::string("metric='reference' with a membrane term needs coordinates within 2^+-200 "
                                       "in magnitude (the largest is ") + figure +
                           "): the membrane energy scales with the square of the units; scale the data, or use "
                           "the thin plate alone");
    }
  }
  FairInterpolationResult out;

  auto t = Clock::now();
  out.plain = coarse.solve(v0, 3, nullptr, options.plain, true);
  out.plain_seconds = seconds_since(t);

  // The fine mesh and the start R V_plain (Far's PrimvarRefiner); R itself only for the reference metric, from
  // the same refinement.
  t = Clock::now();
  out.fine = refine_uniform(topology, rules, options.levels, out.plain.control_vertices.data(),
                            /*with_refinement=*/options.reference_metric);
  std::vector<double> reference;
  if (options.reference_metric) {
    reference = times(out.fine.refinement, v0);
    detail::scale_pow2(reference.data(), reference.size(), -e);
  }
  out.refine_seconds = seconds_since(t);
  std::vector<double> start = std::move(out.fine.vertices);
  out.fine.vertices.clear();
  const std::size_t n_fine = out.fine.n_vertices;

  Mesh fine_faces = out.fine.mesh;
  if (rules.scheme == Scheme::CatmullClark) fine_faces.face_vertex_counts = fine_faces.counts();
  const Rules fine_rules{rules.scheme, rules.boundary, out.fine.tags};
  Topology fine_topology = [&] {
    try {
      return Topology(std::move(fine_faces), n_fine);
    } catch (const MeshError& exc) {
      // Far refines by topology, a face list names faces by their vertices: two faces back to back (a pillow)
      // refine into faces whose middle triangles share all their vertices under Loop, along edges of four faces.
      throw MeshError("the mesh refined " + std::to_string(options.levels) + " time" +
                      (options.levels > 1 ? "s" : "") + " is not a face list sorpia can take (" + exc.what() +
                      "); under Loop this comes from two triangles with the same vertices in the opposite order (a "
                      "pillow), whose refined faces meet along edges of four faces: fair interpolation cannot "
                      "refine them (interpolate can fit such a mesh)");
    }
  }();

  std::vector<double> positions(3 * n_targets);
  for (std::size_t i = 0; i < n_targets; ++i) {
    const std::int32_t v = targets[i];  // checked above
    for (int c = 0; c < 3; ++c) positions[3 * i + static_cast<std::size_t>(c)] = v0[3 * static_cast<std::size_t>(v) + static_cast<std::size_t>(c)];
  }
  detail::scale_pow2(positions.data(), positions.size(), -e);
  detail::scale_pow2(start.data(), start.size(), -e);
  {
    // `threads` caps K's assembly and Bfr's evaluation in it too.
    const detail::ThreadCap cap(options.solve.threads);
    t = Clock::now();
    FairnessQuadrature quadrature;
    quadrature.depth = options.depth;
    // K stays here: built for fair_solve, never copied; its columns unsorted (fair_solve only multiplies).
    const CsrMatrix k = fairness_matrix(
        fine_topology, Rules{rules.scheme, rules.boundary, energy_tags(fine_rules.tags, options.semi_sharp)},
        options.thin_plate, options.membrane, quadrature, reference.empty() ? nullptr : reference.data(),
        /*sorted_columns=*/false);
    out.energy_seconds = seconds_since(t);
    out.solution = fair_solve(fine_topology, fine_rules, k, targets, n_targets, positions.data(), start.data(),
                              options.solve);
  }
  // Back in the caller's units (the thin plate in the reference metric is scale-free: its energies stay).
  detail::scale_pow2(out.solution.vertices.data(), out.solution.vertices.size(), e);
  out.solution.max_error = std::ldexp(out.solution.max_error, e);
  return out;
}

}  // namespace sorpia
