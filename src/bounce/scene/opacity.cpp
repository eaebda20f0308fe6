#include "bounce/scene/opacity.h"

#include <OpenImageIO/hash.h>
#include <fmt/format.h>

#include <algorithm>
#include <bit>
#include <cmath>

#include "bounce/core/image_input.h"
#include "bounce/core/memory.h"
#include "bounce/core/random.h"
#include "bounce/scene/surface_textures.h"
#include "bounce/scene/texel_lookup.h"

namespace bounce {

float OpacityMap::at(const Vec2& uv) const {
    // A uv that is not finite is opaque (texel (0, 0) would cut it at random).
    if (!std::isfinite(uv.x) || !std::isfinite(uv.y)) return 1;
    return periodic_bilinear(width, height, uv,
                             [&](size_t x, size_t y) { return static_cast<float>(texels[y * static_cast<size_t>(width) + x]); }) /
           65535.0f;
}

std::shared_ptr<const OpacityMap> load_opacity_map(const std::string& path, OpacityChannel channel, std::string& error) {
    auto in = open_whole_texture(path, "opacity", error);
    if (!in) return nullptr;
    const OIIO::ImageSpec& spec = in->spec();
    int c = spec.alpha_channel >= 0 && spec.alpha_channel < spec.nchannels ? spec.alpha_channel : spec.nchannels == 2 ? 1 : -1;
    if (c < 0 && channel == OpacityChannel::AlphaOnly) return nullptr;
    if (c < 0) c = 0;
    const double texels = static_cast<double>(spec.width) * spec.height;
    if (error = memory_shortfall(texels * 6, "reading " + path); !error.empty()) return nullptr;
    std::vector<float> values(static_cast<size_t>(texels));
    if (!in->read_image(0, 0, c, c + 1, OIIO::TypeDesc::FLOAT, values.data())) {
        error = "cannot read its pixels: " + in->geterror();
        return nullptr;
    }
    auto map = std::make_shared<OpacityMap>();
    map->width = spec.width, map->height = spec.height;
    map->texels.resize(values.size());
    for (size_t i = 0; i < values.size(); ++i) {
        if (!std::isfinite(values[i])) {
            error = fmt::format("texel ({}, {}) of channel {} is {}, not a number in [0, 1]", i % static_cast<size_t>(spec.width),
                                i / static_cast<size_t>(spec.width), c, values[i]);
            return nullptr;
        }
        map->texels[i] = static_cast<uint16_t>(std::lround(std::clamp(values[i], 0.0f, 1.0f) * 65535.0f));
    }
    map->hash = OIIO::xxhash::XXH64(map->texels.data(), map->texels.size() * sizeof(uint16_t),
                                    static_cast<uint64_t>(map->width) << 32 | static_cast<uint64_t>(map->height));
    return map;
}

uint64_t cutout_identity(const Material& m) {
    if (!m.is_cutout()) return 0;
    uint64_t h = hash_combine(0x2545f4914f6cdd1dULL, static_cast<uint64_t>(m.alpha_mode));
    h = hash_combine(hash_combine(h, std::bit_cast<uint32_t>(m.opacity)), std::bit_cast<uint32_t>(m.alpha_cutoff));
    h = hash_combine(h, m.opacity_map ? m.opacity_map->hash : 0);
    if (!m.opacity_map) return h;  // the transform moves the texture, nothing else
    for (float f :
         {m.uv_transform.offset.x, m.uv_transform.offset.y, m.uv_transform.rotation, m.uv_transform.scale.x, m.uv_transform.scale.y})
        h = hash_combine(h, std::bit_cast<uint32_t>(f));
    return h;
}

const char* alpha_mode_name(AlphaMode mode) {
    switch (mode) {
        case AlphaMode::Mask:
            return "mask";
        case AlphaMode::Blend:
            return "blend";
        case AlphaMode::Opaque:
            break;
    }
    return "opaque";
}

}  // namespace bounce
