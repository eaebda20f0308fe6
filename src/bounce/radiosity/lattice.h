// The values of one side of a radiosity map, stored sparsely: triangles' lattices are grouped in
// pages of kPage triangles, and a page is allocated (zeroed) by the first bake that writes into
// it. Gathers bake only the sides they hit, so a set's far or hidden triangles, and most of an
// instanced forest's (docs/instancing.md), cost no values at all.
#pragma once

#include <atomic>
#include <cstddef>
#include <cstdint>
#include <memory>
#include <vector>

#include "bounce/core/math.h"

namespace bounce {

class LatticeSide {
public:
    static constexpr uint32_t kPage = 64;  ///< triangles per page

    LatticeSide() = default;
    ~LatticeSide();
    LatticeSide(const LatticeSide& other);
    LatticeSide& operator=(const LatticeSide& other);
    LatticeSide(LatticeSide&& other) noexcept;
    LatticeSide& operator=(LatticeSide&& other) noexcept;

    /// Triangle t's lattice starts at point offset[t]; `total` points in all, `width` colours per
    /// point (1, or the number of lights for per-light parts). Nothing is allocated.
    void lay_out(const std::vector<uint32_t>& offset, uint32_t total, uint32_t width);
    /// Triangle `tri`'s values (its first point is `first`, its offset), or null while its page
    /// holds nothing (every value 0).
    const Color* run(uint32_t tri, uint32_t first) const;
    /// The same, allocating its page first if needed; safe from many threads.
    Color* writable_run(uint32_t tri, uint32_t first);
    /// The value at point `k` (any triangle's; 0 where nothing was written): for checks, not lookups.
    Color value(uint32_t k) const;
    /// The same layout and every value equal (unallocated pages are zeros).
    bool operator==(const LatticeSide& other) const;
    /// Points laid out, and bytes of values allocated.
    size_t points() const { return total_; }
    size_t allocated_bytes() const;

private:
    void release();
    std::vector<uint32_t> page_start_;  ///< first point of each page, then the total
    std::unique_ptr<std::atomic<Color*>[]> pages_;
    uint32_t width_ = 1, total_ = 0;
    size_t pages() const { return page_start_.empty() ? 0 : page_start_.size() - 1; }
    size_t page_values(size_t p) const { return size_t{page_start_[p + 1] - page_start_[p]} * width_; }
};

}  // namespace bounce
