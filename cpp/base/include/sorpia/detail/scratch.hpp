#pragma once
// Scratch memory for the transient arrays of work that is repeated many times on data of about one size (an
// approximation's iterations over its chunks): the arrays are cut from blocks that the Scratch keeps between the
// calls, so that a repeated call writes memory already mapped and touched. Each array allocated afresh instead
// costs the kernel a page fault and a zeroed page per 4 KiB written (glibc maps an array beyond its threshold afresh
// and unmaps it when freed).
//
// Arrays are taken within a Frame, which gives back every array taken in it when it ends (frames nest, innermost
// first, on one thread). The memory held is that of the most arrays open at once (in one block once the outermost
// frame has ended, a quarter larger; pages beyond those written are only reserved, and cost no memory), and it is
// held until release() or the Scratch's end: an owner that lends it to calls on data of bounded size (a chunk)
// bounds it.
#include <cstddef>
#include <memory>
#include <type_traits>
#include <vector>

namespace sorpia {
namespace detail {

class Scratch {
 public:
  Scratch() = default;
  ~Scratch();
  Scratch(const Scratch&) = delete;
  Scratch& operator=(const Scratch&) = delete;

  /// Room for n values of T, not initialised, aligned to 64 bytes, until the innermost open Frame ends. On the
  /// thread that opened the frame (a task writes into an array taken before the tasks start).
  template <class T>
  T* take(std::size_t n) {
    static_assert(std::is_trivially_default_constructible_v<T> && std::is_trivially_destructible_v<T>,
                  "scratch holds arrays that need no construction");
    return static_cast<T*>(take_bytes(n, sizeof(T)));
  }
  /// Gives the memory held back to the system. No frame may be open. The next array taken opens a block as large as
  /// the one given back (pages not written cost no memory).
  void release();
  /// Bytes held (reserved, not necessarily touched).
  std::size_t held() const;

  /// A frame on a Scratch: the arrays taken in it are given back when it ends. On null, a Scratch of its own for
  /// the frame's lifetime (a caller that keeps none across calls: its arrays are then allocated for the call).
  class Frame {
   public:
    explicit Frame(Scratch* scratch);
    ~Frame();
    Frame(const Frame&) = delete;
    Frame& operator=(const Frame&) = delete;
    Scratch& scratch() { return *scratch_; }
    template <class T>
    T* take(std::size_t n) {
      return scratch_->take<T>(n);
    }

   private:
    std::unique_ptr<Scratch> own_;
    Scratch* scratch_;
    std::size_t block_, used_;  // where the scratch stood when the frame opened
  };

 private:
  void* take_bytes(std::size_t n, std::size_t size);
  // Back to where a frame opened; the blocks merged into one when the outermost frame ends.
  void close(std::size_t block, std::size_t used);
  struct Free {
    void operator()(unsigned char* p) const;
  };
  struct Block {
    std::unique_ptr<unsigned char[], Free> memory;
    std::size_t size = 0, used = 0;
  };
  static Block make_block(std::size_t size);
  std::vector<Block> blocks_;  // the blocks after current_ are unused
  std::size_t current_ = 0;    // the block taken from last
  std::size_t in_use_ = 0;     // bytes taken and not given back (alignment included), over all blocks
  std::size_t most_ = 0;       // the most of in_use_ since the blocks were last merged
  std::size_t reserve_ = 0;    // the size of the block the blocks were last merged into
  int depth_ = 0;              // frames open
};

}  // namespace detail
}  // namespace sorpia
