#include "bounce/render/distributed.h"

#include <cstring>

namespace bounce {

std::array<int, 4> window_of(const DeepBuffer& deep) {
    return {deep.x0, deep.x0 + deep.width, deep.y0, deep.y0 + deep.height};
}

std::vector<std::string> in_row_bands(Communicator& comm, const std::array<int, 4>& window, int tile, BandsTo to,
                                      const std::function<std::string(const std::array<int, 4>&)>& work) {
    const RowBands bands(window[3] - window[2], tile, comm.size());
    std::vector<std::string> out(static_cast<size_t>(bands.count()));
    std::string mine;
    for (int i = 0; i < bands.count(); ++i) {
        if (!comm.owns(static_cast<size_t>(i))) continue;
        const auto rows = bands.rows(i);
        std::string bytes = work({window[0], window[1], window[2] + rows[0], window[2] + rows[1]});
        if (to == BandsTo::Mine) {
            out[static_cast<size_t>(i)] = std::move(bytes);
            continue;
        }
        const uint64_t head[2] = {static_cast<uint64_t>(i), bytes.size()};
        mine.append(reinterpret_cast<const char*>(head), sizeof(head));
        mine += bytes;
    }
    if (to == BandsTo::Mine) return out;
    for (const std::string& b : to == BandsTo::Everyone ? comm.allgather(mine) : comm.gather_to_first(mine))
        for (size_t at = 0; at < b.size();) {
            uint64_t head[2];
            std::memcpy(head, b.data() + at, sizeof(head));
            at += sizeof(head);
            out.at(head[0]) = b.substr(at, head[1]);
            at += head[1];
        }
    return out;
}

DeepBuffer visibility_in_row_bands(Communicator& comm, const Scene& scene, const SceneAccel& accel, Stats& stats,
                                   const std::array<int, 4>& window, bool everyone) {
    const int tile = scene.render.parallel.tile_size;
    const std::vector<std::string> bytes = in_row_bands(comm, window, tile, everyone ? BandsTo::Everyone : BandsTo::Mine,
                                                        [&](const std::array<int, 4>& band) {
                                                            return serialize_window(render_visibility(scene, accel, stats, nullptr, band));
                                                        });
    const RowBands bands(window[3] - window[2], tile, comm.size());
    std::vector<DeepBuffer> parts;
    for (int i = 0; i < bands.count(); ++i) {
        const auto rows = bands.rows(i);
        const std::string& b = bytes[static_cast<size_t>(i)];
        parts.push_back(b.empty() ? empty_window(scene, {window[0], window[1], window[2] + rows[0], window[2] + rows[1]})
                                  : parse_window(b));
    }
    return stack_rows(parts);
}

std::vector<Indirect> band_slice(const DeepBuffer& deep, const std::vector<Indirect>& light, const std::array<int, 4>& band) {
    const size_t first = deep.offsets[static_cast<size_t>(band[2] - deep.y0) * deep.width];
    const size_t last = deep.offsets[static_cast<size_t>(band[3] - deep.y0) * deep.width];
    return {light.begin() + static_cast<std::ptrdiff_t>(first), light.begin() + static_cast<std::ptrdiff_t>(last)};
}

std::vector<Indirect> indirect_in_row_bands(Communicator& comm, const DeepBuffer& deep, int tile,
                                            const std::function<std::vector<Indirect>(const DeepBuffer&)>& light) {
    std::vector<Indirect> out(deep.fragments.size());
    in_row_bands(comm, window_of(deep), tile, BandsTo::Mine, [&](const std::array<int, 4>& band) {
        const std::vector<Indirect> l = light(sub_window(deep, band));
        std::copy(l.begin(), l.end(), out.begin() + static_cast<std::ptrdiff_t>(deep.offsets[static_cast<size_t>(band[2] - deep.y0) * deep.width]));
        return std::string();
    });
    return out;
}

}  // namespace bounce
