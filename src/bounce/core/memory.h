// How much memory this process may still take, and the check made before a large allocation,
// so that a frame, a dicing, fur or a bake that cannot fit is refused with its estimate (exit 2)
// instead of ending in std::bad_alloc or an Embree error halfway through.
#pragma once

#include <cstddef>
#include <string>
#include <vector>

namespace bounce {

/// Bytes this process may still allocate: the smaller of the machine's physical memory and
/// what its address-space limit (ulimit -v) leaves above what the process maps already.
double available_memory_bytes();

/// "WHAT needs about X GiB; Y GiB are available" when `bytes` is more than `share` of
/// available_memory_bytes(), else empty.
std::string memory_shortfall(double bytes, const std::string& what, double share = 0.8);

/// Throws InputError(file, place) with memory_shortfall's message when there is one.
void check_memory(double bytes, const std::string& file, const std::string& place, const std::string& what, double share = 0.8);

/// Asks the kernel for 2 MiB pages under [p, p + bytes) (madvise MADV_HUGEPAGE over the whole
/// 2 MiB pages inside; nothing under 4 MiB). An array first touched in 4 KiB pages faults once
/// per page, 14.5 us each on this VM: most of a 14 400-placement scene's first load, while
/// Embree's builds already take 2 MiB pages.
void advise_huge_pages(const void* p, size_t bytes);

/// v.reserve(n), its new storage in 2 MiB pages where the kernel gives them (advise_huge_pages).
template <typename T>
void reserve_huge(std::vector<T>& v, size_t n) {
    if (n <= v.capacity()) return;
    v.reserve(n);
    advise_huge_pages(v.data(), v.capacity() * sizeof(T));
}

}  // namespace bounce
