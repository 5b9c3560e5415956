#pragma once
/// @file solvers.hpp
/// The PIA family on the Loop limit operator: solve B V = V0 (paper eq. 8) for
/// the control vertices V, with B the Loop limit matrix (paper eq. 7).
///
/// Vertex arrays are row-major (n, 3) doubles, or (n, k) for any per-vertex
/// data (k columns, E_k's norm over all k). Every method starts from
/// V^(0) = V0, or from a given warm start, and uses the paper's stopping rule
/// (section 5): E_k = max_i ||v_i^0 - (B V^(k))_i||, stop when E_k / E_0 < tol
/// or k = max_iter, E_0 always that of V^(0) = V0 (so a warm start meets the
/// same guarantee as a cold one).
/// Also: E_k <= 64 eps max_i ||v_i^0|| (rounding level) counts as converged;
/// E_k > 1e6 E_0 or not finite stops as diverged (the iterate is still finite).

#include <cmath>
#include <cstddef>
#include <cstdint>
#include <functional>
#include <mutex>
#include <optional>
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

/// Every method, in the order documented and listed in messages: the one list
/// of method names (Python's sorpia.solve.METHODS is read from it).
constexpr Method all_methods[] = {Method::Pia, Method::Wpia, Method::Gs, Method::Sor,
                                  Method::Cg,  Method::Hss,  Method::Whss};

/// "pia", "wpia", "gs", "sor", "cg", "hss", "whss". @throw ParameterError on another name
Method parse_method(const std::string& name);
const char* method_name(Method method);

/// How "sor" chooses omega.
enum class OmegaRule {
  Given,  ///< SolveOptions::omega as given, in (0, 2)
  Young,  ///< paper Remark 1: 2 / (1 + sqrt(1 - rho^2)), rho = rho(I - D^-1 B)
  Auto,   ///< sorpia's rule, see sor_auto_omega
};

/// Spectral quantities of one B, estimated on demand and kept so that several
/// solves on one mesh pay for them once. NaN = not estimated yet.
/// Thread-safe: the estimate functions take `mutex`, so solves on one cache
/// from several threads compute each estimate once.
struct SpectralCache {
  double lambda_min = NAN;      ///< smallest eigenvalue of B (B's largest is 1: rows sum to 1)
  double jacobi_rho = NAN;      ///< spectral radius of I - D^-1 B
  double hermitian_min = NAN;   ///< smallest eigenvalue of H = (B + B^T)/2
  double hermitian_max = NAN;   ///< largest eigenvalue of H
  double seconds = 0.0;         ///< time spent estimating, all calls together
  std::mutex mutex;             ///< held while an estimate is looked up or computed

  SpectralCache() = default;
  /// The estimates of `other` (a fresh mutex).
  SpectralCache(const SpectralCache& other) { *this = other; }
  SpectralCache& operator=(const SpectralCache& other) {
    lambda_min = other.lambda_min;
    jacobi_rho = other.jacobi_rho;
    hermitian_min = other.hermitian_min;
    hermitian_max = other.hermitian_max;
    seconds = other.seconds;
    return *this;
  }
};

/// Smallest eigenvalue of B, by Lanczos in the Gamma^-1 inner product, where
/// B is self-adjoint on a closed mesh. With a boundary B is not, but ordered
/// [vertices without neighbours, boundary, interior] it is block lower
/// triangular with self-adjoint diagonal blocks (boundary rows read no interior
/// vertex, and rows without neighbours read none), so its eigenvalues are
/// those of B without the entries whose mirror is absent; Lanczos runs on that.
/// Stops when the smallest Ritz value changes by at most 1e-5 (relative to
/// 1 - lambda_min) on two products in a row, after 40 products at least and
/// 300 at most. Ritz values lie inside the spectrum, so the estimate is at or
/// above the true value. Rows with several weights (LimitOperator::values),
/// which no known inner product makes self-adjoint, and uniform rows where a
/// one-way entry closes a cycle of B's pattern (an infinitely sharp crease
/// that ends in a dart), where no such ordering exists, get the power method
/// on I - B instead (at most 300 products): 1 - max |1 - lambda|, at or below
/// the smallest real part of B's eigenvalues, which may then be complex.
double estimate_lambda_min(const LimitOperator& op, SpectralCache& cache);

/// Spectral radius of the Jacobi matrix I - D^-1 B, by the power method in the
/// D Gamma^-1 inner product (where D^-1 B is self-adjoint): the norm ratio
/// ||A x|| / ||x||, which a +rho/-rho pair does not stall (unlike a Rayleigh
/// quotient), until it changes by less than 1e-7, at most 500 products; a
/// lower bound of the true value.
double estimate_jacobi_rho(const LimitOperator& op, SpectralCache& cache);

/// Extreme eigenvalues of H = (B + B^T)/2, by one Lanczos run on H (symmetric),
/// stopped as estimate_lambda_min's run is, on both ends at once (at most 300
/// scalar products of H). Both lie inside H's true range.
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

/// The "auto" omega of "sor": 1, because bench/omega_study.py finds the best
/// fixed omega close to 1 on every mesh it runs, gaining a few sweeps at most,
/// while any fixed omega above 1 needs more sweeps than Gauss-Seidel on some
/// mesh (the study's page in the docs has the figures). omega = 1 has no
/// estimate to pay for and is never slower than "gs".
constexpr double sor_auto_omega = 1.0;

/// The largest SolveOptions::threads accepted.
constexpr int max_threads = 1024;

/// The largest SolveOptions::max_iter accepted (2**31 - 1).
constexpr long long max_iterations = 2147483647;

/// Options of sorpia::solve. An empty sigma / alpha / weight means "estimate";
/// a parameter given to a method that does not use it is refused, not ignored.
struct SolveOptions {
  Method method = Method::Sor;
  OmegaRule omega_rule = OmegaRule::Auto;  ///< "sor" only; other methods take Auto (no omega)
  double omega = 1.0;     ///< "sor" with OmegaRule::Given, in (0, 2)
  std::optional<double> sigma;   ///< "wpia" step in (0, 2); default 2 / (lambda_min(B) + 1)
  std::optional<double> alpha;   ///< "hss"/"whss" shift > 0; default sqrt(lambda_min(H) lambda_max(H))
  /// "whss" relaxation weight in (0, 2); default 2 / (2 - mu_min - mu_max), where
  /// mu = (alpha - l)/(alpha + l) at l = lambda_max(H), lambda_min(H): the
  /// ends of the HSS spectrum when S = 0 (equals 1 at the default alpha)
  std::optional<double> weight;
  double tol = 1e-10;     ///< stop when E_k / E_0 < tol; positive and finite
  long long max_iter = 1000;  ///< 1 .. max_iterations
  /// "sor"/"gs": threads sweeping at once (1..max_threads; other methods: 1).
  /// The vertices are split into one contiguous index range per thread; each
  /// range is swept in vertex order in parallel, then the vertices with a
  /// neighbour in another range in vertex order: Gauss-Seidel in a slightly
  /// different order, so the iterates differ from threads = 1 by the ordering
  /// (tests: same solution to 1e-8, iterations within 15%), and do not depend
  /// on timing. More threads than cores only slows down. Where no thread can
  /// be started (a process or memory limit) or the core's thread pool is busy
  /// with another solve, the ranges run one after the other on the calling
  /// thread: the same ordering, so the same result.
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

/// Checks every option of `opt` against its range and its method: the one
/// validation of solver options, whichever way they come in (Python, the
/// command line, C++). Values appear in messages as Python's repr writes them.
/// @throw ParameterError naming the option, its value and what is accepted,
///        e.g. "omega = 2.0 is outside (0, 2)"
void check_options(const SolveOptions& opt);

/// Sets opt.omega_rule and opt.omega from the text of an omega option: "auto",
/// "young" or a number (range checked by check_options).
/// @throw ParameterError on other text
void parse_omega(const std::string& text, SolveOptions& opt);

enum class StopReason { Converged, MaxIter, Diverged, Callback };
const char* stop_reason_name(StopReason reason);

struct SolveResult {
  std::vector<double> control_vertices;  ///< (n, columns)
  std::size_t columns = 3;               ///< k: columns of the data (3 for vertices)
  /// errors[k] = E_k / E_0, k = 0..iterations; errors[0] = 1 from a cold
  /// start, E(start) / E_0 from a warm one (E_0 still that of V0)
  std::vector<double> errors;
  double initial_error = 0.0;            ///< E_0 (of the cold start V^(0) = V0), absolute
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
  /// Single-vertex relaxations (eq. 18 at one vertex): iterations * n for
  /// "sor"/"gs", those of the work list for a LocalSolver update, 0 otherwise
  long long relaxations = 0;
  double estimate_seconds = 0.0;         ///< spectral estimates for the parameters (0 when cached)
  double solve_seconds = 0.0;            ///< the iteration itself
  /// Building the topology and the operator: 0 from solve(), which gets them
  /// built; a caller that builds them for this solve records them here.
  double topology_seconds = 0.0;
  double operator_seconds = 0.0;
  /// Wall time of the whole call: estimate + solve from solve(); a caller that
  /// does more for this result (validation, building B) records its own total.
  double seconds = 0.0;
};

/// Solve B V = V0 for (n, 3) vertices from the cold start V^(0) = V0:
/// solve(op, v0, 3, nullptr, opt, cache).
SolveResult solve(const LimitOperator& op, const double* v0, const SolveOptions& opt,
                  SpectralCache* cache = nullptr);

/// Solve B V = V0.
/// @param op       the limit operator
/// @param v0       row-major (n, k) data (vertices: k = 3), finite
/// @param k        columns, >= 1; "sor"/"gs" with threads > 1 take k <= 3 only
///                 (ParameterError otherwise). k = 3 runs the sweep engine as
///                 it is; k < 3 runs it with zero columns added (the same
///                 iterates and E_k); k > 3 sweeps in vertex order on one thread
/// @param initial  row-major (n, k) warm start V^(0), finite, or null for
///                 V^(0) = V0. E_0 is V0's error all the same: errors[0] =
///                 E(initial) / E_0, and a start already below tol returns
///                 after 0 iterations. When V0 solves the system exactly
///                 (E_0 = 0) the result is V0 whatever the start.
/// @param opt      method and parameters (check_options: ParameterError)
/// @param cache    spectral estimates to reuse and fill in (may be null)
SolveResult solve(const LimitOperator& op, const double* v0, std::size_t k, const double* initial,
                  const SolveOptions& opt, SpectralCache* cache = nullptr);

}  // namespace sorpia
