// libFuzzer target: the irradiance cache file reader must turn any bytes into either a cache or
// an InputError, never a crash, a hang or an unbounded allocation.
#include <cstddef>
#include <cstdint>
#include <string>

#include "bounce/cache/cache_file.h"
#include "bounce/core/error.h"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
    std::string bytes(reinterpret_cast<const char*>(data), size);
    try {
        bounce::CacheFile f = bounce::parse_cache_file(bytes, "fuzz.bic");
        // What parses must serialise back to the same bytes.
        if (bounce::serialize_cache_file(f).size() != bytes.size()) __builtin_trap();
    } catch (const bounce::InputError&) {}
    return 0;
}
