#include "bounce/core/scratch.h"

#include <algorithm>
#include <cstdint>

namespace bounce {

namespace {
constexpr size_t kFirstBlock = 4096;
}

std::byte* ScratchBuffer::bytes(size_t size, size_t align) {
    size_t at = (used_ + align - 1) / align * align;
    if (!block_ || at + size > capacity_) {
        if (block_) outgrown_bytes_ += capacity_, outgrown_.push_back(std::move(block_));
        capacity_ = std::max({kFirstBlock, 2 * capacity_, size + align});
        block_ = std::make_unique_for_overwrite<std::byte[]>(capacity_);
        at = 0;
        // new[] of bytes is aligned for any fundamental type (alignof(std::max_align_t)).
    }
    used_ = at + size;
    return block_.get() + at;
}

void ScratchBuffer::reset() {
    used_ = 0;
    if (outgrown_.empty()) return;
    const size_t total = outgrown_bytes_ + capacity_;
    outgrown_.clear(), outgrown_bytes_ = 0;
    block_ = std::make_unique_for_overwrite<std::byte[]>(total);
    capacity_ = total;
}

size_t ScratchBuffer::capacity() const { return outgrown_bytes_ + capacity_; }

}  // namespace bounce
