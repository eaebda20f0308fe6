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

/// Pages of T made on first use, by whichever thread asks first (compare-and-swap); an absent
/// page is all zeros to its users. What LatticeSide and SideStates share.
template <class T>
class LazyPages {
  public:
    LazyPages() = default;
    explicit LazyPages(size_t pages) : pages_(std::make_unique<std::atomic<T*>[]>(pages)), count_(pages) {
        for (size_t p = 0; p < count_; ++p) pages_[p].store(nullptr, std::memory_order_relaxed);
    }
    ~LazyPages() { clear(); }
    LazyPages(LazyPages&& other) noexcept { *this = std::move(other); }
    LazyPages& operator=(LazyPages&& other) noexcept {
        if (this != &other) {
            clear();
            pages_ = std::move(other.pages_), count_ = other.count_;
            other.count_ = 0;
        }
        return *this;
    }
    LazyPages(const LazyPages&) = delete;
    LazyPages& operator=(const LazyPages&) = delete;

    size_t size() const { return count_; }
    /// Page `p`, or null while nobody made it.
    T* get(size_t p) const { return pages_[p].load(std::memory_order_acquire); }
    /// Page `p`, made of `values` value-initialised (zero) elements if nobody made it yet.
    T* make(size_t p, size_t values) {
        T* page = get(p);
        if (page) return page;
        T* fresh = new T[values]();
        if (pages_[p].compare_exchange_strong(page, fresh, std::memory_order_acq_rel)) return fresh;
        delete[] fresh;  // another thread's page won
        return page;
    }

  private:
    void clear() {
        for (size_t p = 0; p < count_; ++p) delete[] pages_[p].load(std::memory_order_relaxed);
        pages_.reset(), count_ = 0;
    }
    std::unique_ptr<std::atomic<T*>[]> pages_;
    size_t count_ = 0;
};

class LatticeSide {
  public:
    static constexpr uint32_t kPage = 32;  ///< triangles per page

    LatticeSide() = default;
    LatticeSide(const LatticeSide& other);
    LatticeSide& operator=(const LatticeSide& other);
    LatticeSide(LatticeSide&& other) noexcept = default;
    LatticeSide& operator=(LatticeSide&& other) noexcept = default;

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
    std::shared_ptr<const std::vector<uint32_t>> offset_;
    LazyPages<Color> pages_;
    uint32_t width_ = 1, total_ = 0;
    size_t pages() const { return pages_.size(); }
    /// The first point of page `p` (p = pages(): the total).
    uint32_t page_start(size_t p) const { return p < pages() ? (*offset_)[p * kPage] : total_; }
    size_t page_values(size_t p) const { return size_t{page_start(p + 1) - page_start(p)} * width_; }
};

/// Bake states of a map's triangle sides (0 new, 1 baking, 2 baked), two per triangle, in pages
/// of 2 kPage allocated by the first side that leaves 0: a placement whose triangles no gather
/// hits holds a pointer per page, not a byte per side.
class SideStates {
  public:
    explicit SideStates(size_t sides = 0) : pages_((sides + kSides - 1) / kSides), sides_(sides) {}

    size_t size() const { return sides_; }
    /// Side `i`'s state (0 while its page is not allocated, and past size(): a map lit at the
    /// hit keeps no states).
    uint8_t load(size_t i, std::memory_order order) const {
        if (i >= sides_) return 0;
        const std::atomic<uint8_t>* page = pages_.get(i / kSides);
        return page ? page[i % kSides].load(order) : 0;
    }
    /// Side `i`'s state itself, allocating its page first if needed; safe from many threads.
    std::atomic<uint8_t>& at(size_t i) { return pages_.make(i / kSides, kSides)[i % kSides]; }
    /// Stores `v` (a 0 into a page not allocated allocates nothing).
    void store(size_t i, uint8_t v, std::memory_order order) {
        if (v != 0 || pages_.get(i / kSides)) at(i).store(v, order);
    }

  private:
    static constexpr size_t kSides = 2 * LatticeSide::kPage;
    LazyPages<std::atomic<uint8_t>> pages_;
    size_t sides_ = 0;
};

}  // namespace bounce
