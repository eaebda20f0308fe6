#include "bounce/radiosity/lattice.h"

#include <algorithm>

namespace bounce {

void LatticeSide::lay_out(std::shared_ptr<const std::vector<uint32_t>> offset, uint32_t total, uint32_t width) {
    width_ = width, total_ = total, offset_ = std::move(offset);
    pages_ = LazyPages<Color>(offset_ ? (offset_->size() + kPage - 1) / kPage : 0);
}

LatticeSide::LatticeSide(const LatticeSide& other) { *this = other; }

LatticeSide& LatticeSide::operator=(const LatticeSide& other) {
    if (this == &other) return *this;
    offset_ = other.offset_, width_ = other.width_, total_ = other.total_;
    pages_ = LazyPages<Color>(other.pages());
    for (size_t p = 0; p < pages(); ++p)
        if (const Color* from = other.pages_.get(p)) std::copy(from, from + page_values(p), pages_.make(p, page_values(p)));
    return *this;
}

const Color* LatticeSide::run(uint32_t tri, uint32_t first) const {
    const size_t p = tri / kPage;
    const Color* base = pages_.get(p);
    return base ? base + size_t{first - page_start(p)} * width_ : nullptr;
}

Color* LatticeSide::writable_run(uint32_t tri, uint32_t first) {
    const size_t p = tri / kPage;
    return pages_.make(p, page_values(p)) + size_t{first - page_start(p)} * width_;
}

Color LatticeSide::value(uint32_t k) const {
    // The page whose first point is the last at or before k (pages start at every kPage-th offset).
    size_t lo = 0, hi = pages();
    while (hi - lo > 1) {
        const size_t mid = (lo + hi) / 2;
        (page_start(mid) <= k ? lo : hi) = mid;
    }
    const Color* base = pages_.get(lo);
    return base ? base[size_t{k - page_start(lo)} * width_] : Color(0);
}

bool LatticeSide::operator==(const LatticeSide& other) const {
    if (pages() != other.pages() || total_ != other.total_ || width_ != other.width_) return false;
    for (size_t p = 0; p < pages(); ++p)
        if (page_start(p) != other.page_start(p)) return false;
    for (size_t p = 0; p < pages(); ++p) {
        const Color *a = pages_.get(p), *b = other.pages_.get(p);
        for (size_t i = 0; (a || b) && i < page_values(p); ++i)
            if (!((a ? a[i] : Color(0)) == (b ? b[i] : Color(0)))) return false;
    }
    return true;
}

size_t LatticeSide::allocated_bytes() const {
    size_t n = 0;
    for (size_t p = 0; p < pages(); ++p)
        if (pages_.get(p)) n += page_values(p) * sizeof(Color);
    return n;
}

}  // namespace bounce
