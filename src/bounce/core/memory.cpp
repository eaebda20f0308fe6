#include "bounce/core/memory.h"

#include <fmt/format.h>
#include <sys/mman.h>
#include <sys/resource.h>
#include <unistd.h>

#include <algorithm>
#include <fstream>

#include "bounce/core/error.h"

namespace bounce {

namespace {

/// Bytes the process maps now (virtual size; /proc/self/statm's first field, in pages).
double mapped_bytes() {
    std::ifstream in("/proc/self/statm");
    double pages = 0;
    if (!(in >> pages)) return 0;
    return pages * static_cast<double>(sysconf(_SC_PAGE_SIZE));
}

}  // namespace

double available_memory_bytes() {
    double have = static_cast<double>(sysconf(_SC_PHYS_PAGES)) * static_cast<double>(sysconf(_SC_PAGE_SIZE));
    for (int resource : {RLIMIT_AS, RLIMIT_DATA}) {
        rlimit rl{};
        if (getrlimit(resource, &rl) == 0 && rl.rlim_cur != RLIM_INFINITY)
            have = std::min(have, std::max(0.0, static_cast<double>(rl.rlim_cur) - mapped_bytes()));
    }
    return have;
}

std::string memory_shortfall(double bytes, const std::string& what, double share) {
    const double have = available_memory_bytes();
    if (!(bytes > share * have)) return "";
    // The budget, not only what is available: a need between the two read as "1.3 GiB; 1.3 GiB".
    return fmt::format("{} needs about {:.2f} GiB; it may use {:.2f} GiB ({:.0f} % of the {:.2f} GiB available)", what,
                       bytes / 1073741824.0, share * have / 1073741824.0, 100 * share, have / 1073741824.0);
}

void check_memory(double bytes, const std::string& file, const std::string& place, const std::string& what, double share) {
    if (std::string why = memory_shortfall(bytes, what, share); !why.empty()) throw InputError(file, place, why);
}

void advise_huge_pages(const void* p, size_t bytes) {
    constexpr uintptr_t kHuge = uintptr_t{2} << 20;
    if (bytes < 2 * kHuge) return;
    const auto begin = (reinterpret_cast<uintptr_t>(p) + kHuge - 1) & ~(kHuge - 1);
    const auto end = (reinterpret_cast<uintptr_t>(p) + bytes) & ~(kHuge - 1);
    if (end > begin) madvise(reinterpret_cast<void*>(begin), end - begin, MADV_HUGEPAGE);  // (a hint: failure changes nothing)
}

}  // namespace bounce
