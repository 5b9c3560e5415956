// detail::Scratch: arrays taken in a frame are given back when it ends, so that the next frame's arrays are cut
// from the same memory; nested frames give back only their own; the blocks of a first pass are merged into one.
#include <gtest/gtest.h>

#include <cstdint>
#include <numeric>

#include "sorpia/detail/scratch.hpp"

namespace {

using sorpia::detail::Scratch;

TEST(Scratch, FramesGiveBackTheirArrays) {
  Scratch scratch;
  double* first = nullptr;
  for (int pass = 0; pass < 3; ++pass) {
    const Scratch::Frame frame(&scratch);
    double* a = scratch.take<double>(1000);
    std::int32_t* b = scratch.take<std::int32_t>(3000);
    // the arrays are disjoint and aligned to 64 bytes
    EXPECT_EQ(reinterpret_cast<std::uintptr_t>(a) % 64, 0u);
    EXPECT_EQ(reinterpret_cast<std::uintptr_t>(b) % 64, 0u);
    const auto pa = reinterpret_cast<std::uintptr_t>(a), pb = reinterpret_cast<std::uintptr_t>(b);
    EXPECT_TRUE(pb >= pa + 1000 * sizeof(double) || pa >= pb + 3000 * sizeof(std::int32_t));
    std::iota(a, a + 1000, 0.0);
    std::iota(b, b + 3000, 0);
    EXPECT_EQ(a[999], 999.0);
    // from the second pass on the arrays lie in one block: the same memory each pass
    if (pass == 1) first = a;
    if (pass == 2) EXPECT_EQ(a, first);
  }
  const std::size_t held = scratch.held();
  EXPECT_GE(held, 1000 * sizeof(double) + 3000 * sizeof(std::int32_t));
  {
    const Scratch::Frame frame(&scratch);
    double* a = scratch.take<double>(1000);
    {
      const Scratch::Frame inner(&scratch);
      double* c = scratch.take<double>(500);
      EXPECT_GE(c, a + 1000);
    }
    // the inner frame's array was given back: the next one starts where it started
    double* d = scratch.take<double>(500);
    EXPECT_GE(d, a + 1000);
    double* again = nullptr;
    {
      const Scratch::Frame inner(&scratch);
      again = scratch.take<double>(10);
    }
    EXPECT_GT(again, d);
  }
  EXPECT_EQ(scratch.held(), held);  // the same work again takes nothing new
  scratch.release();
  EXPECT_EQ(scratch.held(), 0u);
}

TEST(Scratch, SecondPassReusesOneBlock) {
  Scratch scratch;
  const auto pass = [&] {
    const Scratch::Frame frame(&scratch);
    double* a = scratch.take<double>(1 << 16);
    double* b = scratch.take<double>(1 << 18);
    a[0] = b[0] = 1.0;
    return std::pair<double*, double*>(a, b);
  };
  pass();  // two blocks, merged into one when the frame ends
  const auto [a2, b2] = pass();
  const auto [a3, b3] = pass();
  EXPECT_EQ(a2, a3);
  EXPECT_EQ(b2, b3);
  EXPECT_EQ(b2, a2 + (1 << 16));  // one block: b follows a
  const std::size_t need = (std::size_t{1} << 16) * 8 + (std::size_t{1} << 18) * 8;
  EXPECT_GE(scratch.held(), need);
  EXPECT_LE(scratch.held(), need + need / 4 + 64);
}

TEST(Scratch, NullFrameHasItsOwn) {
  Scratch::Frame frame(nullptr);
  double* a = frame.take<double>(100);
  a[99] = 1.0;
  EXPECT_EQ(a[99], 1.0);
}

}  // namespace
