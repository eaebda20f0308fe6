#include "bounce/radiosity/lattice.h"

#include <algorithm>

namespace bounce {

LatticeSide::~LatticeSide() { release(); }

void LatticeSide::release() {
    for (size_t p = 0; p < pages(); ++p) delete[] pages_[p].load(std::memory_order_relaxed);
    pages_.reset();
}

void LatticeSide::lay_out(const std::vector<uint32_t>& offset, uint32_t total, uint32_t width) {
    release();
    width_ = width, total_ = total;
    page_start_.clear();
    for (size_t t = 0; t < offset.size(); t += kPage) page_start_.push_back(offset[t]);
    page_start_.push_back(total);
    pages_ = std::make_unique<std::atomic<Color*>[]>(pages());
    for (size_t p = 0; p < pages(); ++p) pages_[p].store(nullptr, std::memory_order_relaxed);
}

LatticeSide::LatticeSide(const LatticeSide& other) { *this = other; }

LatticeSide& LatticeSide::operator=(const LatticeSide& other) {
    if (this == &other) return *this;
    release();
    page_start_ = other.page_start_, width_ = other.width_, total_ = other.total_;
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
    page_start_ = std::move(other.page_start_), pages_ = std::move(other.pages_);
    width_ = other.width_, total_ = other.total_;
    other.page_start_.clear(), other.total_ = 0;
    return *this;
}

const Color* LatticeSide::run(uint32_t tri, uint32_t first) const {
    const size_t p = tri / kPage;
    const Color* base = pages_[p].load(std::memory_order_acquire);
    return base ? base + size_t{first - page_start_[p]} * width_ : nullptr;
}

Color* LatticeSide::writable_run(uint32_t tri, uint32_t first) {
    const size_t p = tri / kPage;
    Color* base = pages_[p].load(std::memory_order_acquire);
    if (!base) {
        Color* fresh = new Color[page_values(p)]();
        if (pages_[p].compare_exchange_strong(base, fresh, std::memory_order_acq_rel)) base = fresh;
        else delete[] fresh;  // another thread's page won
    }
    return base + size_t{first - page_start_[p]} * width_;
}

Color LatticeSide::value(uint32_t k) const {
    const size_t p = static_cast<size_t>(std::upper_bound(page_start_.begin(), page_start_.end() - 1, k) - page_start_.begin()) - 1;
    const Color* base = pages_[p].load(std::memory_order_acquire);
    return base ? base[size_t{k - page_start_[p]} * width_] : Color(0);
}

bool LatticeSide::operator==(const LatticeSide& other) const {
    if (page_start_ != other.page_start_ || width_ != other.width_) return false;
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

}  // namespace bounce
