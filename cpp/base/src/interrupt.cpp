// The calling thread's interrupt checker (sorpia/interrupt.hpp).
#include "sorpia/interrupt.hpp"

#include <utility>

namespace sorpia {
namespace {
thread_local InterruptScope* current_scope = nullptr;
}  // namespace

InterruptScope::InterruptScope(InterruptChecker checker)
    : checker_(std::move(checker)), last_asked_(std::chrono::steady_clock::now()), previous_(current_scope) {
  current_scope = this;
}

InterruptScope::~InterruptScope() { current_scope = previous_; }

void check_interrupt_now() {
  InterruptScope* s = current_scope;
  if (!s || !s->checker_) return;
  s->last_asked_ = std::chrono::steady_clock::now();
  if (s->checker_()) throw Interrupted();
}

void poll_interrupt() {
  InterruptScope* s = current_scope;
  if (!s || !s->checker_) return;
  if (std::chrono::steady_clock::now() - s->last_asked_ < kInterruptPollInterval) return;
  check_interrupt_now();
}

}  // namespace sorpia
