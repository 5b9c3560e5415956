#pragma once
/// @file
/// Stopping a long call early (Ctrl-C). The core knows nothing of Python: a
/// caller installs a checker on its thread for the duration of a call
/// (InterruptScope), and the long loops poll once per unit of work (a solver
/// iteration, a product of a spectral estimate, a refinement level, a chunk
/// of a file read). A poll asks the checker at most once per
/// kInterruptPollInterval of work; when the checker says stop, the poll throws
/// Interrupted, so the partial result is discarded as the stack unwinds.
/// Without a checker a poll is a thread-local load. Workers of the core's
/// thread pool have no checker: loops poll on the calling thread, between the
/// pool's fork-join steps, and the pool stays usable.
#include <chrono>
#include <functional>
#include <stdexcept>

namespace sorpia {

/// Thrown by a poll whose checker asked to stop.
class Interrupted : public std::runtime_error {
 public:
  Interrupted() : std::runtime_error("interrupted") {}
};

/// Returns true to stop the call. May throw instead (its exception then
/// propagates from the poll as Interrupted would).
using InterruptChecker = std::function<bool()>;

/// The least time between two questions to the checker: a poll in between is
/// a clock read. Long enough that a checker which must wait for a lock (the
/// Python binding's takes the GIL, which another Python thread may hold for
/// its switch interval) costs the call a few percent at most; short enough
/// that a stop comes well within a second.
constexpr std::chrono::milliseconds kInterruptPollInterval{50};

/// Installs `checker` on the calling thread while the scope lives (an empty
/// one installs none); the checker it replaces comes back at its end.
class InterruptScope {
 public:
  explicit InterruptScope(InterruptChecker checker);
  ~InterruptScope();
  InterruptScope(const InterruptScope&) = delete;
  InterruptScope& operator=(const InterruptScope&) = delete;

 private:
  InterruptChecker checker_;
  std::chrono::steady_clock::time_point last_asked_;
  InterruptScope* previous_;
  friend void poll_interrupt();
  friend void check_interrupt_now();
};

/// Asks the calling thread's checker, if any and if kInterruptPollInterval has
/// passed since it was last asked; throws Interrupted when it says stop.
void poll_interrupt();

/// The same, asking at once: a signal has just interrupted a system call.
void check_interrupt_now();

}  // namespace sorpia
