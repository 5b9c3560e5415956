#include "sorpia/detail/scratch.hpp"

#include <algorithm>
#include <limits>
#include <new>

namespace sorpia {
namespace detail {

namespace {
constexpr std::size_t kAlign = 64;
}  // namespace

void Scratch::Free::operator()(unsigned char* p) const { ::operator delete[](p, std::align_val_t{kAlign}); }

Scratch::Block Scratch::make_block(std::size_t size) {
  Block b;
  b.memory.reset(static_cast<unsigned char*>(::operator new[](size, std::align_val_t{kAlign})));
  b.size = size;
  return b;
}

Scratch::~Scratch() = default;

void Scratch::release() {
  blocks_.clear();
  current_ = in_use_ = most_ = 0;
}

std::size_t Scratch::held() const {
  std::size_t s = 0;
  for (const Block& b : blocks_) s += b.size;
  return s;
}

void* Scratch::take_bytes(std::size_t n, std::size_t size) {
  if (n > (std::numeric_limits<std::size_t>::max() - kAlign) / size) throw std::bad_alloc();
  const std::size_t bytes = std::max(kAlign, (n * size + kAlign - 1) / kAlign * kAlign);
  // The current block, else the first unused one after it with room, else a new one.
  std::size_t j = current_;
  while (j < blocks_.size() && blocks_[j].size - blocks_[j].used < bytes) ++j;
  // After a release, the first block is as large as the one given back (the same work taken up again fits in it).
  if (j == blocks_.size()) blocks_.push_back(make_block(blocks_.empty() ? std::max(bytes, reserve_) : bytes));
  current_ = j;
  Block& b = blocks_[j];
  void* p = b.memory.get() + b.used;
  b.used += bytes;
  in_use_ += bytes;
  most_ = std::max(most_, in_use_);
  return p;
}

void Scratch::close(std::size_t block, std::size_t used) {
  for (std::size_t j = block + 1; j < blocks_.size(); ++j) {
    in_use_ -= blocks_[j].used;
    blocks_[j].used = 0;
  }
  if (block < blocks_.size()) {
    in_use_ -= blocks_[block].used - used;
    blocks_[block].used = used;
  }
  current_ = block;
  if (--depth_ > 0 || blocks_.size() <= 1) return;
  // The outermost frame ended with its arrays in more than one block: one block for the most they held at once
  // (what the same work needs again), with a quarter more for work a little larger (reserved: untouched pages cost
  // no memory).
  const std::size_t size = (most_ + most_ / 4 + kAlign - 1) / kAlign * kAlign;
  reserve_ = size;
  blocks_.clear();
  current_ = 0;
  try {
    blocks_.push_back(make_block(size));
  } catch (const std::bad_alloc&) {  // none: the next arrays take blocks of their own
  }
  most_ = 0;
}

Scratch::Frame::Frame(Scratch* scratch) {
  if (scratch == nullptr) {
    own_ = std::make_unique<Scratch>();
    scratch = own_.get();
  }
  scratch_ = scratch;
  block_ = scratch->current_;
  used_ = scratch->current_ < scratch->blocks_.size() ? scratch->blocks_[scratch->current_].used : 0;
  ++scratch->depth_;
}

Scratch::Frame::~Frame() {
  if (!own_) scratch_->close(block_, used_);
}

}  // namespace detail
}  // namespace sorpia
