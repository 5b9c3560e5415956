#pragma once
/// @file solvers.hpp
/// The PIA family on the Loop limit operator: solve B V = V0 (paper eq. 8) for
/// the control vertices V, with B the Loop limit matrix (paper eq. 7).
///
/// Vertex arrays are row-major (n, 3) doubles. Every method starts from
/// V^(0) = V0 and uses the paper's stopping rule (section 5):
/// E_k = max_i ||v_i^0 - (B V^(k))_i||, stop when E_k / E_0 < tol or k = max_iter.
/// Also: E_k <= 64 eps max_i ||v_i^0|| (rounding level) counts as converged;
/// E_k > 1e6 E_0 or not finite stops as diverged (the iterate is still finite).

#include <cmath>
#include <cstddef>
#include <cstdint>
#include <functional>
#include <string>
#include <vector>

#include "sorpia/limit_operator.hpp"
#include "sorpia/topology.hpp"

namespace sorpia {

/// The methods of sorpia::solve.
enum class Method {
  Pia,   ///< V += d,          d = V0 - B V (paper eq. 9)
  Wpia,  ///< V += sigma d     (weighted PIA)
  Gs,    ///< Gauss-Seidel sweep (Sor with omega = 1)
  Sor,   ///< SOR-PIA sweep, paper eq. 18
  Cg,    ///< conjugate gradients on Upsilon V = Gamma^-1 V0; BiCGSTAB when B is not symmetrisable
  Hss,   ///< Hermitian/skew-Hermitian splitting (Bai, Golub, Ng 2003) of B
  Whss,  ///< HSS relaxed: V <- V + weight (HSS(V) - V)
};

/// "pia", "wpia", "gs", "sor", "cg", "hss", "whss". @throw ParameterError on another name
Method parse_method(const std::string& name);
const char* method_name(Method method);

/// How "sor" chooses omega.
enum class OmegaRule {
  Given,  ///< SolveOptions::omega as given, in (0, 2)
  Young,  ///< paper Remark 1: 2 / (1 + sqrt(1 - rho^2)), rho = rho(I - D^-1 B)
  Auto,   ///< sorpia's measured rule, see auto_omega
};

/// Spectral quantities of one B, estimated on demand and kept so that several
/// solves on one mesh pay for them once. NaN = not estimated yet.
struct SpectralCache {
  double lambda_min = NAN;      ///< smallest eigenvalue of B (B's largest is 1: rows sum to 1)
  double jacobi_rho = NAN;      ///< spectral radius of I - D^-1 B
  double hermitian_min = NAN;   ///< smallest eigenvalue of H = (B + B^T)/2
  double hermitian_max = NAN;   ///< largest eigenvalue of H
  double seconds = 0.0;         ///< time spent estimating, all calls together
};

/// Smallest eigenvalue of B, by the power method on I - B in the Gamma^-1 inner
/// product (where B is self-adjoint): lambda_min = 1 - ||(I-B)x|| / ||x|| after
/// the ratio settles (relative change < 1e-6, at most 300 products). The
/// estimate is at or above the true value (a Rayleigh-type lower bound of 1 - lambda_min).
double estimate_lambda_min(const LimitOperator& op, SpectralCache& cache);

/// Spectral radius of the Jacobi matrix I - D^-1 B, by the power method in the
/// D Gamma^-1 inner product (where D^-1 B is self-adjoint): the norm ratio
/// ||A x|| / ||x||, which a +rho/-rho pair does not stall (unlike a Rayleigh
/// quotient), until it changes by less than 1e-7, at most 500 products; a
/// lower bound of the true value.
double estimate_jacobi_rho(const LimitOperator& op, SpectralCache& cache);

/// Extreme eigenvalues of H = (B + B^T)/2, by the power method on H and on
/// lambda_max I - H (at most 300 scalar products each).
/// Returns {lambda_min(H), lambda_max(H)}.
std::pair<double, double> estimate_hermitian_extremes(const LimitOperator& op, SpectralCache& cache);

/// rho at or above this: Young's formula has no real value (rho >= 1) or none of
/// use (omega within 0.03 of 2); the rule then uses this rho (a warning is the
/// caller's job: SolveResult::omega_clamped).
constexpr double young_rho_clamp = 0.9999;

/// Paper Remark 1: omega = 2 / (1 + sqrt(1 - rho^2)), rho clamped to
/// young_rho_clamp (which gives omega = 1.9720).
/// @param clamped  set to whether rho was clamped (may be null)
double young_omega(double rho, bool* clamped);

/// The "auto" omega of "sor", from bench/omega_study.py: on real and
/// generated meshes the best omega lies close to 1 and saves only a few sweeps
/// over it, and no fixed omega above 1 beats Gauss-Seidel on every mesh. So
/// "auto" is omega = 1: no estimate to pay for, never slower than "gs".
constexpr double sor_auto_omega = 1.0;

/// The largest SolveOptions::threads accepted.
constexpr int max_threads = 1024;

/// Options of sorpia::solve. NaN for sigma / alpha / weight means "estimate".
struct SolveOptions {
  Method method = Method::Sor;
  OmegaRule omega_rule = OmegaRule::Auto;
  double omega = 1.0;     ///< "sor" with OmegaRule::Given, in (0, 2)
  double sigma = NAN;     ///< "wpia" step; default 2 / (lambda_min(B) + 1)
  double alpha = NAN;     ///< "hss"/"whss" shift; default sqrt(lambda_min(H) lambda_max(H))
  /// "whss" relaxation weight; default 2 / (2 - mu_min - mu_max), where
  /// mu = (alpha - l)/(alpha + l) at l = lambda_max(H), lambda_min(H): the
  /// ends of the HSS spectrum when S = 0 (equals 1 at the default alpha)
  double weight = NAN;
  double tol = 1e-10;     ///< stop when E_k / E_0 < tol
  int max_iter = 1000;
  /// "sor"/"gs": threads sweeping at once (1..max_threads; other methods: 1).
  /// The vertices are split into one contiguous index range per thread; each
  /// range is swept in vertex order in parallel, then the vertices with a
  /// neighbour in another range in vertex order: Gauss-Seidel in a slightly
  /// different order, so the iterates differ from threads = 1 by the ordering
  /// (tests: same solution to 1e-8, iterations within 15%), and do not depend
  /// on timing. More threads than cores only slows down. Built without
  /// OpenMP (CMake SORPIA_OPENMP=OFF), the ranges run one after the other on
  /// the calling thread: the same ordering, so the same solution to the
  /// tolerance (bit for bit unless the ranges would have been swept in slabs).
  int threads = 1;
  /// Reference path for tests and benchmarks only, not for use: "sor"/"gs"
  /// compute E_k by a separate residual pass after each sweep instead of
  /// inside it. Both give the same E_k bit for bit (what the tests check);
  /// the fused sweep (default) reads the mesh once per iteration instead of
  /// twice.
  bool two_pass = false;
  /// Called after E_k is known for k = 0, 1, ...; returning true stops the run.
  /// Empty: no call at all.
  std::function<bool(int, double)> callback;
};

enum class StopReason { Converged, MaxIter, Diverged, Callback };
const char* stop_reason_name(StopReason reason);

struct SolveResult {
  std::vector<double> control_vertices;  ///< (n, 3)
  std::vector<double> errors;            ///< errors[k] = E_k / E_0, k = 0..iterations
  double initial_error = 0.0;            ///< E_0, absolute
  int iterations = 0;
  StopReason stop_reason = StopReason::MaxIter;
  bool converged() const { return stop_reason == StopReason::Converged; }
  Method method = Method::Sor;
  std::string variant;                   ///< what ran: e.g. "cg" or "bicgstab" for Method::Cg
  double omega = NAN;                    ///< "sor"/"gs": the omega used
  /// "sor"/"gs": swept in a locality order of its own (breadth-first) because
  /// the input order was too poor (most vertices' neighbours far away in
  /// index); control_vertices are in the caller's order all the same.
  bool reordered = false;
  double rho = NAN;                      ///< "sor" with "young": the estimated rho(I - D^-1 B)
  bool omega_clamped = false;            ///< "young": rho >= young_rho_clamp, omega clamped
  double sigma = NAN;                    ///< "pia"/"wpia": the step used
  double lambda_min = NAN;               ///< estimated smallest eigenvalue of B, where used
  double alpha = NAN;                    ///< "hss"/"whss": the shift used
  double weight = NAN;                   ///< "whss": the relaxation weight used
  long long products = 0;                ///< operator applications (B, B^T, H or S) in the solve
  double estimate_seconds = 0.0;         ///< spectral estimates for the parameters (0 when cached)
  double solve_seconds = 0.0;            ///< the iteration itself
};

/// Solve B V = V0.
/// @param op     the limit operator
/// @param v0     row-major (n, 3) mesh vertices, finite
/// @param opt    method and parameters (validated here: ParameterError)
/// @param cache  spectral estimates to reuse and fill in (may be null)
SolveResult solve(const LimitOperator& op, const double* v0, const SolveOptions& opt,
                  SpectralCache* cache = nullptr);

}  // namespace sorpia
