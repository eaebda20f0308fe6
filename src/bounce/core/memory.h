// How much memory this process may still take, and the check made before a large allocation,
// so that a frame, a dicing, fur or a bake that cannot fit is refused with its estimate (exit 2)
// instead of ending in std::bad_alloc or an Embree error halfway through.
#pragma once

#include <string>

namespace bounce {

/// Bytes this process may still allocate: the smaller of the machine's physical memory and
/// what its address-space limit (ulimit -v) leaves above what the process maps already.
double available_memory_bytes();

/// "WHAT needs about X GiB; Y GiB are available" when `bytes` is more than `share` of
/// available_memory_bytes(), else empty.
std::string memory_shortfall(double bytes, const std::string& what, double share = 0.8);

/// Throws InputError(file, place) with memory_shortfall's message when there is one.
void check_memory(double bytes, const std::string& file, const std::string& place, const std::string& what,
                  double share = 0.8);

}  // namespace bounce
