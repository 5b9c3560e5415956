#pragma once
// Uninitialised, aligned arrays for the sweep engine. Not a public header.
#include <sys/mman.h>

#include <algorithm>
#include <cstddef>
#include <cstdlib>
#include <new>
#include <utility>

namespace sorpia {
namespace detail {

// n values of T, uninitialised (no pass to zero them, no page faulted in
// before its first use), 64-byte aligned, so that a 32-byte row never
// straddles a cache line. With huge_pages, a large buffer is placed on a
// 2 MB boundary and transparent huge pages are asked for: they save most of
// the page faults and TLB misses of the array the sweep gathers from. Only
// for that array: a fresh huge page can take much longer to fault in than the
// 4 kB pages it replaces, which the engine's other, linearly read copies do
// not win back.
// std::vector<d4> would not even guarantee 32 bytes: the baseline target caps
// vector alignment at 16.
template <class T>
class AlignedBuffer {
 public:
  AlignedBuffer() = default;
  AlignedBuffer(std::size_t n, bool huge_pages) {
    const std::size_t bytes = std::max<std::size_t>(sizeof(T) * n, 64);
    const std::size_t align = huge_pages && bytes >= kHuge ? kHuge : 64;
    const std::size_t rounded = (bytes + align - 1) / align * align;
    void* p = std::aligned_alloc(align, rounded);
    if (!p) throw std::bad_alloc();
#ifdef MADV_HUGEPAGE
    if (align == kHuge) madvise(p, rounded, MADV_HUGEPAGE);  // advice only: failure is harmless
#endif
    data_ = static_cast<T*>(p);
  }
  ~AlignedBuffer() { std::free(data_); }
  AlignedBuffer(const AlignedBuffer&) = delete;
  AlignedBuffer& operator=(const AlignedBuffer&) = delete;
  AlignedBuffer& operator=(AlignedBuffer&& o) noexcept {
    std::swap(data_, o.data_);
    return *this;
  }
  T* data() { return data_; }
  const T* data() const { return data_; }
  T& operator[](std::size_t i) { return data_[i]; }
  const T& operator[](std::size_t i) const { return data_[i]; }

 private:
  static constexpr std::size_t kHuge = std::size_t{1} << 21;
  T* data_ = nullptr;
};

}  // namespace detail
}  // namespace sorpia
