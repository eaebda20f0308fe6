#include "bounce/radiosity/lattice.h"

#include <algorithm>

namespace bounce {

LatticeSide::~LatticeSide() { release(); }

void LatticeSide::release() {
    for (size_t p = 0; p < pages(); ++p) delete[] pages_[p].load(std::memory_order_relaxed);
    pages_.reset();
}

void LatticeSide::lay_out(std::shared_ptr<const std::vector<uint32_t>> offset, uint32_t total, uint32_t width) {
    release();
    width_ = width, total_ = total, offset_ = std::move(offset);
    pages_ = std::make_unique<std::atomic<Color*>[]>(pages());
    for (size_t p = 0; p < pages(); ++p) pages_[p].store(nullptr, std::memory_order_relaxed);
}

LatticeSide::LatticeSide(const LatticeSide& other) { *this = other; }

LatticeSide& LatticeSide::operator=(const LatticeSide& other) {
    if (this == &other) return *this;
    release();
    offset_ = other.offset_, width_ = other.width_, total_ = other.total_;
    pages_ = std::make_unique<std::atomic<Color*>[]>(pages());
    for (size_t p = 0; p < pages(); ++p) {
        const Color* from = other.pages_[p].load(std::memory_order_acquire);
        Color* copy = nullptr;
        if (from) {
            copy = new Color[page_values(p)];
            std::copy(from, from + page_values(p), copy);
        }
        pages_[p].store(copy, std::memory_order_relaxed);
    }
    return *this;
}

LatticeSide::LatticeSide(LatticeSide&& other) noexcept { *this = std::move(other); }

LatticeSide& LatticeSide::operator=(LatticeSide&& other) noexcept {
    if (this == &other) return *this;
    release();
    offset_ = std::move(other.offset_), pages_ = std::move(other.pages_);
    width_ = other.width_, total_ = other.total_;
    other.offset_.reset(), other.total_ = 0;
    return *this;
}

const Color* LatticeSide::run(uint32_t tri, uint32_t first) const {
    const size_t p = tri / kPage;
    const Color* base = pages_[p].load(std::memory_order_acquire);
    return base ? base + size_t{first - page_start(p)} * width_ : nullptr;
}

Color* LatticeSide::writable_run(uint32_t tri, uint32_t first) {
    const size_t p = tri / kPage;
    Color* base = pages_[p].load(std::memory_order_acquire);
    if (!base) {
        Color* fresh = new Color[page_values(p)]();
        if (pages_[p].compare_exchange_strong(base, fresh, std::memory_order_acq_rel)) base = fresh;
        else delete[] fresh;  // another thread's page won
    }
    return base + size_t{first - page_start(p)} * width_;
}

Color LatticeSide::value(uint32_t k) const {
    // The page whose first point is the last at or before k (pages start at every kPage-th offset).
    size_t lo = 0, hi = pages();
    while (hi - lo > 1) {
        const size_t mid = (lo + hi) / 2;
        (page_start(mid) <= k ? lo : hi) = mid;
    }
    const Color* base = pages_[lo].load(std::memory_order_acquire);
    return base ? base[size_t{k - page_start(lo)} * width_] : Color(0);
}

bool LatticeSide::operator==(const LatticeSide& other) const {
    if (pages() != other.pages() || total_ != other.total_ || width_ != other.width_) return false;
    for (size_t p = 0; p < pages(); ++p)
        if (page_start(p) != other.page_start(p)) return false;
    for (size_t p = 0; p < pages(); ++p) {
        const Color *a = pages_[p].load(std::memory_order_acquire), *b = other.pages_[p].load(std::memory_order_acquire);
        for (size_t i = 0; (a || b) && i < page_values(p); ++i)
            if (!((a ? a[i] : Color(0)) == (b ? b[i] : Color(0)))) return false;
    }
    return true;
}

size_t LatticeSide::allocated_bytes() const {
    size_t n = 0;
    for (size_t p = 0; p < pages(); ++p)
        if (pages_[p].load(std::memory_order_relaxed)) n += page_values(p) * sizeof(Color);
    return n;
}

SideStates::SideStates(size_t sides) : pages_(std::make_unique<std::atomic<std::atomic<uint8_t>*>[]>((sides + kSides - 1) / kSides)), sides_(sides) {
    for (size_t p = 0; p < pages(); ++p) pages_[p].store(nullptr, std::memory_order_relaxed);
}

SideStates::~SideStates() { release(); }

void SideStates::release() {
    for (size_t p = 0; pages_ && p < pages(); ++p) delete[] pages_[p].load(std::memory_order_relaxed);
    pages_.reset();
}

SideStates::SideStates(SideStates&& other) noexcept : pages_(std::move(other.pages_)), sides_(other.sides_) { other.sides_ = 0; }

SideStates& SideStates::operator=(SideStates&& other) noexcept {
    if (this == &other) return *this;
    release();
    pages_ = std::move(other.pages_), sides_ = other.sides_;
    other.sides_ = 0;
    return *this;
}

uint8_t SideStates::load(size_t i, std::memory_order order) const {
    const std::atomic<uint8_t>* page = pages_[i / kSides].load(std::memory_order_acquire);
    return page ? page[i % kSides].load(order) : 0;
}

std::atomic<uint8_t>& SideStates::at(size_t i) {
    std::atomic<std::atomic<uint8_t>*>& slot = pages_[i / kSides];
    std::atomic<uint8_t>* page = slot.load(std::memory_order_acquire);
    if (!page) {
        auto* fresh = new std::atomic<uint8_t>[kSides];
        for (size_t k = 0; k < kSides; ++k) fresh[k].store(0, std::memory_order_relaxed);
        if (slot.compare_exchange_strong(page, fresh, std::memory_order_acq_rel)) page = fresh;
        else delete[] fresh;  // another thread's page won
    }
    return page[i % kSides];
}

void SideStates::store(size_t i, uint8_t v, std::memory_order order) {
    if (v == 0 && !pages_[i / kSides].load(std::memory_order_acquire)) return;
    at(i).store(v, order);
}

}  // namespace bounce
