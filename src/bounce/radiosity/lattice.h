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
    static constexpr uint32_t kPage = 32;  ///< triangles per page

    LatticeSide() = default;
    ~LatticeSide();
    LatticeSide(const LatticeSide& other);
    LatticeSide& operator=(const LatticeSide& other);
    LatticeSide(LatticeSide&& other) noexcept;
    LatticeSide& operator=(LatticeSide&& other) noexcept;

    /// Triangle t's lattice starts at point (*offset)[t] (shared with the map's layout, not
    /// copied); `total` points in all, `width` colours per point (1, or the number of lights for
    /// per-light parts). Nothing is allocated but a pointer per page.
    void lay_out(std::shared_ptr<const std::vector<uint32_t>> offset, uint32_t total, uint32_t width);
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
    std::shared_ptr<const std::vector<uint32_t>> offset_;
    std::unique_ptr<std::atomic<Color*>[]> pages_;
    uint32_t width_ = 1, total_ = 0;
    size_t pages() const { return offset_ ? (offset_->size() + kPage - 1) / kPage : 0; }
    /// The first point of page `p` (p = pages(): the total).
    uint32_t page_start(size_t p) const { return p < pages() ? (*offset_)[p * kPage] : total_; }
    size_t page_values(size_t p) const { return size_t{page_start(p + 1) - page_start(p)} * width_; }
};

/// Bake states of a map's triangle sides (0 new, 1 baking, 2 baked), two per triangle, in pages
/// of 2 kPage allocated by the first side that leaves 0: a placement whose triangles no gather
/// hits holds a pointer per page, not a byte per side.
class SideStates {
public:
    explicit SideStates(size_t sides = 0);
    ~SideStates();
    SideStates(SideStates&& other) noexcept;
    SideStates& operator=(SideStates&& other) noexcept;
    SideStates(const SideStates&) = delete;
    SideStates& operator=(const SideStates&) = delete;

    size_t size() const { return sides_; }
    /// Side `i`'s state (0 while its page is not allocated).
    uint8_t load(size_t i, std::memory_order order) const;
    /// Side `i`'s state itself, allocating its page first if needed; safe from many threads.
    std::atomic<uint8_t>& at(size_t i);
    /// Stores `v` (a 0 into a page not allocated allocates nothing).
    void store(size_t i, uint8_t v, std::memory_order order);

private:
    static constexpr size_t kSides = 2 * LatticeSide::kPage;
    size_t pages() const { return (sides_ + kSides - 1) / kSides; }
    void release();
    std::unique_ptr<std::atomic<std::atomic<uint8_t>*>[]> pages_;
    size_t sides_ = 0;
};

}  // namespace bounce
