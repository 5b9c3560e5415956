// The SOR-PIA / Gauss-Seidel engine ("sor" and "gs"): one pass over the mesh
// per iteration that both sweeps (paper eq. 18) and yields the paper's E_k of
// the new iterate, exactly; optionally on several threads.
//
// Fused E_k. E_k = max_i ||v_i^0 - (B V^(k))_i|| needs every neighbour of i at
// its value after sweep k. In sweep order, vertex j's neighbours are all final
// once the sweep has passed max(N(j)); on meshes whose vertex order is
// spatially coherent that is a few rows later. So the residual of vertex j is
// computed in the same loop, `lag` vertices behind the update front, by the
// same formula and summation order as a separate residual pass: the E_k are
// bit for bit those of the two-pass method (tested), while V, V0 and the
// neighbour lists are still in cache. Vertices with a neighbour beyond the lag
// (seams such as a torus's wrap-around) are marked "deferred" once per solve
// and get their residual after the sweep. A mesh in a very poor order (most
// vertices deferred, e.g. a shuffled file) is swept in a breadth-first order
// of its own (locality_order) and handed back in the caller's order. When
// more than 1/8 of the residuals would be deferred all the same, E_k comes
// from a residual pass after each sweep instead (Engine::fused_pays). E_0
// comes from the pass that sets V^(0) = V0 (Engine::start).
//
// Threads. The vertices are split into contiguous index ranges of equal work,
// one per thread, or, when that would leave many vertices with a neighbour in
// another range, renumbered into slabs across the mesh first (slab_order,
// each keeping the caller's order). A vertex with a neighbour in another
// range is an "interface" vertex: the ranges sweep their other vertices in
// parallel, in vertex order (no two of them are adjacent across ranges, so
// the result does not depend on timing), then one thread sweeps the
// interface vertices in vertex order. This is Gauss-Seidel in a slightly
// different vertex order (interface vertices last), so the iteration count
// stays about that of the sequential sweep (a multicolour order would change
// the ordering of every vertex). One fork and one join per sweep: each thread
// also computes the deferred residuals of its own range; the interface
// vertices, and the residuals that need them, run on the calling thread
// after the join, on the core's thread pool (parallel.hpp). Below
// sweep_min_vertices_per_thread the ranges run one after the other on the
// calling thread: the same iterates, bit for bit, except that ranges are then
// never replaced by slabs (nothing to gain); where the pool cannot give
// threads, it runs them in turn too, with the same iterates.
//
// Layout. V is held as (n + 1, 4) doubles, the fourth lane and the last row
// zero, so a neighbour is one 32-byte load; V0 is read in place (n, 3). The
// arithmetic is per lane in the same order as the scalar formula
// (sweep_kernels_impl.hpp), in a baseline and an AVX2 build picked at run time
// that give the same bits.
//
// Rows. Uniform rows (one weight per row, every Loop row) take kernels that
// gather the neighbours by a loop of fixed length (choose_slots); rows with
// per-entry weights (LimitOperator::values) take a plain scalar-weighted
// loop, with the same fused E_k, threads, orders and plan.
//
// Units: the kernels (sweep_kernels*), the vertex orders (vertex_order), the
// plan of ranges and residuals (sweep_plan), and here the engine that runs
// them.
#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <vector>

#include "aligned_buffer.hpp"
#include "sorpia/detail/parallel.hpp"
#include "solver_detail.hpp"
#include "sweep_kernels.hpp"
#include "sweep_plan.hpp"
#include "vertex_order.hpp"

namespace sorpia {
namespace detail {

std::size_t sweep_min_vertices_per_thread = 8192;

namespace {

class Engine {
 public:
  // v0: the caller's (n, 3) vertices, solved for as V0 / 2^exponent (in place
  // when exponent = 0 and the order is kept).
  Engine(const LimitOperator& op, const double* v0, int exponent, double omega, int threads)
      : op_(rows_of(op)),
        // Below sweep_min_vertices_per_thread, waking the threads costs more
        // than they save. The ranges then run one after the other (the same
        // order, so the same result).
        parallel_(threads > 1 && op.n / static_cast<std::size_t>(threads) >= sweep_min_vertices_per_thread),
        x_(op.n + 1, true),
        exponent_(exponent) {
    x_[op.n] = d4{0.0, 0.0, 0.0, 0.0};  // the zero row
    std::vector<std::int32_t> begin = equal_work_ranges(op_, threads);
    const OrderSurvey survey = survey_order(op_, begin);
    const bool poor = poor_order(survey);
    if (poor) {
      // Sweep in a locality order instead (a Gauss-Seidel order like any
      // other: same solution, iteration counts within a few percent), and
      // hand the control vertices back in the caller's order.
      perm_ = locality_order(op_);
    } else if (parallel_ && crowded_interface(survey)) {
      perm_ = slab_order(op_, v0, threads, begin);
    }
    const std::size_t n = op.n;
    if (!perm_.empty() || exponent_ != 0) v0_ = AlignedBuffer<double>(3 * n, false);
    if (!perm_.empty()) {
      inv_.resize(n);
      for (std::size_t k = 0; k < n; ++k) inv_[perm_[k]] = static_cast<std::int32_t>(k);
      reordered_ = Renumbered(op_, perm_.data(), inv_.data(), threads, parallel_);
      op_ = reordered_.view;
      if (poor) begin = equal_work_ranges(op_, threads);
      double* w = v0_.data();
      const std::int32_t* perm = perm_.data();
      for_each_index(parallel_, threads, n, [&](std::size_t k) {
        for (int a = 0; a < 3; ++a) w[3 * k + a] = v0[3 * static_cast<std::size_t>(perm[k]) + a];
      });
    } else if (exponent_ != 0) {
      std::memcpy(v0_.data(), v0, 3 * n * sizeof(double));
    }
    if (v0_.data()) {
      scale_pow2(v0_.data(), 3 * n, -exponent_);
      v0 = v0_.data();
    }
    plan_ = make_plan(op_, threads, parallel_, begin);
    std::int32_t slots_end = 0;
    if (op_.uniform()) {
      const int choice = n + 1 <= kMaxSlotRows ? choose_slots(op_) : 0;  // index into kSlotChoices
      k_ = &uniform_kernels(choice);
      const std::int32_t nnz = op_.offsets[n];
      slots_end = static_cast<std::int32_t>(n);
      while (slots_end > 0 && op_.offsets[slots_end - 1] + kSlotChoices[choice] > nnz) --slots_end;
    } else {
      k_ = &per_entry_kernels();
    }
    ctx_ = Ctx{op_, static_cast<std::int32_t>(n), slots_end, v0, x_.data(), plan_.flags.data(), omega, plan_.lag};
  }

  // Whether E_k inside the sweep is faster than a residual pass after it.
  // Not when many residuals are deferred: each gathers its neighbours from
  // rows long evicted (an icosphere numbered level by level, whose coarse
  // quarter reaches far ahead). Either way gives the same E_k, bit for bit.
  bool fused_pays() const {
    return plan_.deferred.size() <= op_.n / 8;
  }

  // Whether the vertices are swept in another order than the caller's.
  bool reordered() const { return !perm_.empty(); }

  int threads() const { return static_cast<int>(plan_.begin.size()) - 1; }

  // max_i ||v_i^0|| of the (scaled) V0: the monitor's rounding level.
  double scale() const { return max_row_norm(ctx_.v0, op_.n); }

  // Sets V^(0) = V0 and returns E_0, in one pass: the residuals run lag
  // behind the rows being set, as in a fused sweep (the same bits as
  // residual(), without reading x back from memory).
  // On the calling thread alone, the ranges one after the other: threads
  // faulting in the fresh pages of x at once contend on the one mapping,
  // and were often slower than one thread alone.
  double start() {
    const int t_count = threads();
    double m = 0.0;
    for (int t = 0; t < t_count; ++t) m = std::max(m, k_->init_fused(ctx_, plan_.begin[t], plan_.begin[t + 1]));
    m = std::max(m, k_->residual_list(ctx_, plan_.deferred.data(), plan_.deferred.size()));
    return std::sqrt(m);
  }

  // x = `initial`, (n, 3) in the caller's order, already divided by
  // 2^exponent: a warm start, loaded after start() has found E_0 from V0.
  void load(const double* initial) {
    for_each_index(parallel_, threads(), op_.n, [&](std::size_t k) {
      const double* y = initial + 3 * (perm_.empty() ? k : static_cast<std::size_t>(perm_[k]));
      x_[k] = d4{y[0], y[1], y[2], 0.0};
    });
  }

  // E of the current iterate, by a residual pass.
  double residual() const {
    const int t_count = threads();
    const double m = max_over_tasks(parallel_, t_count, [&](int t) {
      return k_->residual_range(ctx_, plan_.begin[t], plan_.begin[t + 1]);
    });
    return std::sqrt(m);
  }

  // One sweep; fused: returns E of the new iterate, else NaN. The ranges run
  // in parallel; the interface vertices and the deferred residuals (a few
  // percent of the vertices on a well-ordered mesh) run on the calling thread
  // after the join: one fork and one join per sweep, the fewest waits for
  // threads that the system may have descheduled.
  double sweep(bool fused) {
    const int t_count = threads();
    const auto sweep_range = fused ? k_->sweep_fused : k_->sweep_plain;
    const std::int32_t* deferred = plan_.deferred.data();
    double m = max_over_tasks(parallel_, t_count, [&](int t) {
      double mt = sweep_range(ctx_, plan_.begin[t], plan_.begin[t + 1]);
      // The deferred residuals of the range's own vertices, final now.
      if (fused)
        mt = std::max(mt, k_->residual_list(ctx_, deferred + plan_.local[t], plan_.local[t + 1] - plan_.local[t]));
      return mt;
    });
    k_->update_list(ctx_, plan_.interface.data(), plan_.interface.size());
    if (!fused) return NAN;
    const std::size_t rest = plan_.local[t_count];
    m = std::max(m, k_->residual_list(ctx_, deferred + rest, plan_.deferred.size() - rest));
    return std::sqrt(m);
  }

  // (n, 3) control vertices, times 2^exponent().
  void write(double* v) const {
    for_each_index(parallel_, threads(), op_.n, [&](std::size_t i) {
      const d4& y = x_[perm_.empty() ? i : static_cast<std::size_t>(inv_[i])];
      for (int a = 0; a < 3; ++a) v[3 * i + a] = y[a];
    });
    scale_pow2(v, 3 * op_.n, exponent_);
  }

 private:
  Rows op_;                               // the operator swept: the caller's or reordered_
  bool parallel_;                         // threads really run in parallel
  std::vector<std::int32_t> perm_, inv_;  // the sweep's order (empty: the caller's): perm[new] = old
  Renumbered reordered_;                  // the caller's operator in that order
  Plan plan_;
  const Kernels* k_ = nullptr;
  AlignedBuffer<d4> x_;                          // (n + 1) rows
  int exponent_;
  AlignedBuffer<double> v0_;                     // V0 reordered and/or divided by 2^exponent, when either applies
  Ctx ctx_;
};

}  // namespace

void solve_sor(const LimitOperator& op, const double* v0, int exponent, const SolveOptions& opt, double omega,
               SolveResult& res, const double* initial) {
  Engine engine(op, v0, exponent, omega, opt.threads);
  res.reordered = engine.reordered();
  const bool fused = !opt.two_pass && engine.fused_pays();
  const double e0 = engine.start();
  Monitor mon(opt, res, engine.scale());
  double first = e0;
  if (initial && mon.warm_start(e0)) {
    engine.load(initial);
    first = engine.residual();
  }
  if (!mon.start(first)) {
    for (;;) {
      double e = engine.sweep(fused);
      res.products += 2;  // a sweep and a residual, fused or not
      if (!fused) e = engine.residual();
      if (mon.record(e)) break;
    }
  }
  res.control_vertices.resize(3 * op.n);
  engine.write(res.control_vertices.data());
}

void solve_sor_columns(const LimitOperator& op, const double* v0, std::size_t k, double omega, Monitor& mon,
                       SolveResult& res) {
  double* x = res.control_vertices.data();
  if (mon.start(residual(op, v0, x, nullptr, k))) return;
  const Rows rows = rows_of(op);
  with_row_kind(rows, [&](auto kind) {
    for (;;) {
      for (std::size_t i = 0; i < op.n; ++i) relax_row<0, decltype(kind)>(rows, v0, x, k, i, omega);
      res.products += 2;  // a sweep and a residual
      if (mon.record(residual(op, v0, x, nullptr, k))) return;
    }
  });
}

}  // namespace detail
}  // namespace sorpia
