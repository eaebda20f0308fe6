#include "bounce/render/distributed.h"

#include <cstring>

namespace bounce {

namespace {

/// Bands per process: enough that a band of sky and a band of fur even out.
constexpr int kBandsPerProcess = 4;

}  // namespace

std::array<int, 4> window_of(const DeepBuffer& deep) {
    return {deep.x0, deep.x0 + deep.width, deep.y0, deep.y0 + deep.height};
}

std::vector<std::string> in_row_bands(Communicator& comm, const std::array<int, 4>& window,
                                      const std::function<std::string(const std::array<int, 4>&)>& work) {
    const int n = std::max(1, std::min(window[3] - window[2], kBandsPerProcess * comm.size()));
    std::string mine;
    for (int i = 0; i < n; ++i) {
        if (!comm.owns(static_cast<size_t>(i))) continue;
        const std::string bytes = work(row_band(window, i, n));
        const uint64_t head[2] = {static_cast<uint64_t>(i), bytes.size()};
        mine.append(reinterpret_cast<const char*>(head), sizeof(head));
        mine += bytes;
    }
    std::vector<std::string> bands(static_cast<size_t>(n));
    for (const std::string& b : comm.allgather(mine))
        for (size_t at = 0; at < b.size();) {
            uint64_t head[2];
            std::memcpy(head, b.data() + at, sizeof(head));
            at += sizeof(head);
            bands.at(head[0]) = b.substr(at, head[1]);
            at += head[1];
        }
    return bands;
}

std::vector<Indirect> band_slice(const DeepBuffer& deep, const std::vector<Indirect>& light, const std::array<int, 4>& band) {
    const size_t first = deep.offsets[static_cast<size_t>(band[2] - deep.y0) * deep.width];
    const size_t last = deep.offsets[static_cast<size_t>(band[3] - deep.y0) * deep.width];
    return {light.begin() + static_cast<std::ptrdiff_t>(first), light.begin() + static_cast<std::ptrdiff_t>(last)};
}

std::vector<Indirect> indirect_in_row_bands(Communicator& comm, const DeepBuffer& deep,
                                            const std::function<std::vector<Indirect>(const DeepBuffer&)>& light) {
    const std::vector<std::string> bands = in_row_bands(comm, window_of(deep), [&](const std::array<int, 4>& band) {
        const std::vector<Indirect> l = light(sub_window(deep, band));
        return std::string(reinterpret_cast<const char*>(l.data()), l.size() * sizeof(Indirect));
    });
    std::vector<Indirect> out(deep.fragments.size());
    size_t at = 0;
    for (const std::string& b : bands) {
        std::memcpy(static_cast<void*>(out.data() + at), b.data(), b.size());
        at += b.size() / sizeof(Indirect);
    }
    return out;
}

}  // namespace bounce
