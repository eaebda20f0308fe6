#include "bounce/render/distributed.h"

#include <cstring>

#include "bounce/core/tiles.h"

namespace bounce {

std::array<int, 4> window_of(const DeepBuffer& deep) { return {deep.x0, deep.x0 + deep.width, deep.y0, deep.y0 + deep.height}; }

std::vector<std::string> in_tiles(Communicator& comm, const std::array<int, 4>& window, int tile, TilesTo to,
                                  const std::function<std::string(const std::array<int, 4>&)>& work) {
    const std::vector<Tile> tiles = make_tiles(window[1] - window[0], window[3] - window[2], tile);
    std::vector<std::string> out(tiles.size());
    std::string mine;
    for (const Tile& t : tiles) {
        if (!comm.owns(static_cast<size_t>(t.index))) continue;
        std::string bytes = work({window[0] + t.x0, window[0] + t.x1, window[2] + t.y0, window[2] + t.y1});
        if (to == TilesTo::Mine) {
            out[static_cast<size_t>(t.index)] = std::move(bytes);
            continue;
        }
        const uint64_t head[2] = {static_cast<uint64_t>(t.index), bytes.size()};
        mine.append(reinterpret_cast<const char*>(head), sizeof(head));
        mine += bytes;
    }
    if (to == TilesTo::Mine) return out;
    for (const std::string& b : to == TilesTo::Everyone ? comm.allgather(mine) : comm.gather_to_first(mine))
        for (size_t at = 0; at < b.size();) {
            uint64_t head[2];
            std::memcpy(head, b.data() + at, sizeof(head));
            at += sizeof(head);
            out.at(head[0]) = b.substr(at, head[1]);
            at += head[1];
        }
    return out;
}

DeepBuffer visibility_in_tiles(Communicator& comm, const Scene& scene, const SceneAccel& accel, const VisibilitySettings& settings,
                               int tile_size, Stats& stats, const std::array<int, 4>& window, bool everyone) {
    std::vector<DeepBuffer> parts;
    for (const std::string& b :
         in_tiles(comm, window, tile_size, everyone ? TilesTo::Everyone : TilesTo::Mine, [&](const std::array<int, 4>& tile) {
             return serialize_window(render_visibility(scene, accel, settings, stats, nullptr, tile));
         }))
        if (!b.empty()) parts.push_back(parse_window(b));
    return assemble_tiles(scene, settings, window, parts);
}

std::vector<Indirect> window_slice(const DeepBuffer& deep, const std::vector<Indirect>& light, const std::array<int, 4>& w) {
    std::vector<Indirect> out;
    for (int y = w[2] - deep.y0; y < w[3] - deep.y0; ++y) {
        const size_t row = static_cast<size_t>(y) * deep.width;
        out.insert(out.end(), light.begin() + deep.offsets[row + static_cast<size_t>(w[0] - deep.x0)],
                   light.begin() + deep.offsets[row + static_cast<size_t>(w[1] - deep.x0)]);
    }
    return out;
}

std::vector<Indirect> indirect_in_tiles(Communicator& comm, const DeepBuffer& deep, int tile,
                                        const std::function<std::vector<Indirect>(const DeepBuffer&)>& light) {
    std::vector<Indirect> out(deep.fragments.size());
    in_tiles(comm, window_of(deep), tile, TilesTo::Mine, [&](const std::array<int, 4>& w) {
        const std::vector<Indirect> l = light(sub_window(deep, w));
        size_t next = 0;
        for (int y = w[2] - deep.y0; y < w[3] - deep.y0; ++y) {
            const size_t row = static_cast<size_t>(y) * deep.width;
            for (uint32_t i = deep.offsets[row + static_cast<size_t>(w[0] - deep.x0)];
                 i < deep.offsets[row + static_cast<size_t>(w[1] - deep.x0)]; ++i)
                out[i] = l[next++];
        }
        return std::string();
    });
    return out;
}

}  // namespace bounce
