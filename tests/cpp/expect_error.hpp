#pragma once
// Test helper: a call that must throw, with a message naming the problem.
#include <gtest/gtest.h>

#include <string>
#include <vector>

namespace sorpia_test {

// Calls f(), which must throw an E whose message contains every one of `parts`.
template <class E, class F>
void expect_error(F&& f, const std::vector<std::string>& parts) {
  try {
    f();
    ADD_FAILURE() << "no exception; expected one containing '" << parts.front() << "'";
  } catch (const E& e) {
    const std::string what = e.what();
    for (const auto& p : parts) EXPECT_NE(what.find(p), std::string::npos) << "'" << p << "' not in: " << what;
  }
}

}  // namespace sorpia_test
