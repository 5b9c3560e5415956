// The interrupt hook (sorpia/interrupt.hpp): a poll asks the installed checker
// at most once per interval and throws Interrupted when it says stop; the
// long calls (solves on the core's threads, spectral estimates,
// tessellation, reading a file) then end with Interrupted, keep nothing
// half-done (a later call gives what a fresh one gives) and leave the thread
// pool usable. Without a checker, or with one that never stops, results are
// those of a plain call, bit for bit.
#include <gtest/gtest.h>
#include <unistd.h>

#include <chrono>
#include <cmath>
#include <cstdio>
#include <string>
#include <thread>
#include <vector>

#include "limit_case.hpp"
#include "parallel_ranges.hpp"
#include "sorpia/interrupt.hpp"
#include "sorpia/io.hpp"
#include "sorpia/shapes.hpp"
#include "sorpia/solvers.hpp"
#include "sorpia/surface.hpp"

namespace {

using sorpia::Interrupted;
using sorpia::InterruptScope;

// A checker that counts its questions and answers `stop`.
struct Counting {
  int asked = 0;
  bool stop = false;
  sorpia::InterruptChecker checker() {
    return [this] {
      ++asked;
      return stop;
    };
  }
};

// Past the poll interval: the next poll asks the checker.
void wait_past_interval() { std::this_thread::sleep_for(sorpia::kInterruptPollInterval * 3 / 2); }

TEST(Interrupt, AskedAtMostOncePerIntervalAndThrowsWhenTold) {
  sorpia::poll_interrupt();  // no checker: nothing to ask
  Counting c;
  const InterruptScope scope(c.checker());
  for (int k = 0; k < 1000; ++k) sorpia::poll_interrupt();
  EXPECT_EQ(c.asked, 0);  // installed less than an interval ago
  wait_past_interval();
  sorpia::poll_interrupt();
  sorpia::poll_interrupt();
  EXPECT_EQ(c.asked, 1);
  c.stop = true;
  EXPECT_THROW(sorpia::check_interrupt_now(), Interrupted);
  EXPECT_EQ(c.asked, 2);
}

TEST(Interrupt, ScopesNestAndBelongToTheirThread) {
  Counting outer, inner;
  outer.stop = true;
  const InterruptScope a(outer.checker());
  {
    const InterruptScope b(inner.checker());
    sorpia::check_interrupt_now();  // the inner one answers: go on
    EXPECT_EQ(inner.asked, 1);
    std::thread([] { sorpia::check_interrupt_now(); }).join();  // another thread has none
  }
  EXPECT_THROW(sorpia::check_interrupt_now(), Interrupted);
  EXPECT_EQ(outer.asked, 1);
  EXPECT_EQ(inner.asked, 1);
}

sorpia::SolveResult solve(const sorpia_test::LimitCase& c, sorpia::Method m, int threads,
                          sorpia::SpectralCache* cache = nullptr) {
  sorpia::SolveOptions o;
  o.method = m;
  o.tol = 1e-12;
  o.max_iter = 100000;
  o.threads = threads;
  return sorpia::solve(c.op, c.mesh.vertices.data(), o, cache);
}

TEST(Interrupt, EveryMethodStopsAndThePoolStaysUsable) {
  const sorpia_test::SweepRangesOnThreads on_threads;
  const auto c = sorpia_test::limit_case(sorpia::irregular(3000));
  for (sorpia::Method m : sorpia::all_methods) {
    const int threads = (m == sorpia::Method::Sor || m == sorpia::Method::Gs) ? 2 : 1;
    const sorpia::SolveResult plain = solve(c, m, threads);
    Counting never;
    {
      const InterruptScope scope(never.checker());
      wait_past_interval();
      const sorpia::SolveResult asked = solve(c, m, threads);
      EXPECT_EQ(asked.control_vertices, plain.control_vertices) << sorpia::method_name(m);
      EXPECT_EQ(asked.iterations, plain.iterations) << sorpia::method_name(m);
    }
    EXPECT_GE(never.asked, 1) << sorpia::method_name(m);
    Counting stop;
    stop.stop = true;
    sorpia::SpectralCache cache;
    {
      const InterruptScope scope(stop.checker());
      wait_past_interval();
      EXPECT_THROW(solve(c, m, threads, &cache), Interrupted) << sorpia::method_name(m);
    }
    EXPECT_EQ(stop.asked, 1) << sorpia::method_name(m);
    // Nothing half-done stays behind: the same cache and pool give the plain result.
    EXPECT_EQ(solve(c, m, threads, &cache).control_vertices, plain.control_vertices) << sorpia::method_name(m);
  }
}

TEST(Interrupt, SpectralEstimateStopsAndLeavesItsCacheUnset) {
  const auto c = sorpia_test::limit_case(sorpia::irregular(3000));
  sorpia::SpectralCache fresh, cache;
  const double plain = sorpia::estimate_lambda_min(c.op, fresh);
  Counting stop;
  stop.stop = true;
  {
    const InterruptScope scope(stop.checker());
    wait_past_interval();
    EXPECT_THROW(sorpia::estimate_lambda_min(c.op, cache), Interrupted);
  }
  EXPECT_TRUE(std::isnan(cache.lambda_min));
  EXPECT_EQ(sorpia::estimate_lambda_min(c.op, cache), plain);
}

TEST(Interrupt, TessellationAndEvaluationStop) {
  const sorpia::Mesh m = sorpia::icosphere(2);
  const sorpia::Topology topo(m);
  sorpia::LimitSurface s(topo, m.vertices.data(), sorpia::Scheme::Loop, sorpia::Boundary::EdgeAndCorner);
  sorpia::LimitSurface fresh(topo, m.vertices.data(), sorpia::Scheme::Loop, sorpia::Boundary::EdgeAndCorner);
  const std::vector<std::int32_t> face(1, 0);
  const std::vector<double> uv{0.25, 0.25};
  double p[3];
  Counting stop;
  stop.stop = true;
  {
    const InterruptScope scope(stop.checker());
    wait_past_interval();
    EXPECT_THROW(s.tessellate(2), Interrupted);
    wait_past_interval();
    EXPECT_THROW(s.evaluate(face.data(), uv.data(), 1, p, nullptr, nullptr, nullptr), Interrupted);
  }
  EXPECT_EQ(stop.asked, 2);
  const sorpia::Mesh t = s.tessellate(2), f = fresh.tessellate(2);
  EXPECT_EQ(t.vertices, f.vertices);
  EXPECT_EQ(t.face_vertex_indices, f.face_vertex_indices);
}

TEST(Interrupt, ReadingAFileStops) {
  const sorpia::Mesh m = sorpia::icosphere(1);
  const std::string path = ::testing::TempDir() + "sorpia_interrupt_" + std::to_string(::getpid()) + ".off";
  sorpia::write_mesh(path, m.vertices.data(), m.n_vertices(), m.face_vertex_indices.data(), m.n_faces(), false);
  Counting stop;
  stop.stop = true;
  {
    const InterruptScope scope(stop.checker());
    wait_past_interval();
    EXPECT_THROW(sorpia::read_mesh(path), Interrupted);
  }
  EXPECT_EQ(sorpia::read_mesh(path).face_vertex_indices, m.face_vertex_indices);
  std::remove(path.c_str());
}

}  // namespace
