#include "bounce/scene/opacity.h"

#include <OpenImageIO/hash.h>
#include <fmt/format.h>

#include <algorithm>
#include <bit>
#include <cmath>

#include "bounce/core/image_input.h"
#include "bounce/core/memory.h"
#include "bounce/core/random.h"

namespace bounce {

float OpacityMap::at(const Vec2& uv) const {
    // As OpenImageIO's periodic lookup of the colour texture: s = u, t = 1 - v, texel centres
    // at (i + 0.5) / width.
    const float x = uv.x * static_cast<float>(width) - 0.5f, y = (1 - uv.y) * static_cast<float>(height) - 0.5f;
    if (!std::isfinite(x) || !std::isfinite(y)) return 1;
    const float fx = std::floor(x), fy = std::floor(y);
    const float ax = x - fx, ay = y - fy;
    const auto wrap = [](float i, int n) {
        const double m = std::fmod(static_cast<double>(i), static_cast<double>(n));
        return static_cast<size_t>(m < 0 ? m + n : m);
    };
    const size_t x0 = wrap(fx, width), x1 = wrap(fx + 1, width), y0 = wrap(fy, height), y1 = wrap(fy + 1, height);
    const auto t = [&](size_t xi, size_t yi) { return static_cast<float>(texels[yi * static_cast<size_t>(width) + xi]); };
    const float top = t(x0, y0) + (t(x1, y0) - t(x0, y0)) * ax;
    const float bottom = t(x0, y1) + (t(x1, y1) - t(x0, y1)) * ax;
    return (top + (bottom - top) * ay) / 65535.0f;
}

std::shared_ptr<const OpacityMap> load_opacity_map(const std::string& path, OpacityChannel channel, std::string& error) {
    auto in = open_image(path, error);
    if (!in) {
        error = "not a readable image: " + error;
        return nullptr;
    }
    const OIIO::ImageSpec& spec = in->spec();
    if (spec.width <= 0 || spec.height <= 0 || spec.nchannels <= 0) {
        error = "the image has no pixels";
        return nullptr;
    }
    int c = spec.alpha_channel >= 0 && spec.alpha_channel < spec.nchannels ? spec.alpha_channel
            : spec.nchannels == 2                                           ? 1
                                                                            : -1;
    if (c < 0 && channel == OpacityChannel::AlphaOnly) return nullptr;
    if (c < 0) c = 0;
    const double texels = static_cast<double>(spec.width) * spec.height;
    if (texels > kMaxOpacityTexels) {
        error = fmt::format("a {}x{} opacity texture is read whole and may hold at most 8192x8192 pixels; resize it "
                            "(e.g. OpenImageIO's oiiotool --resize)", spec.width, spec.height);
        return nullptr;
    }
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
    return hash_combine(h, m.opacity_map ? m.opacity_map->hash : 0);
}

const char* alpha_mode_name(AlphaMode mode) {
    switch (mode) {
        case AlphaMode::Mask: return "mask";
        case AlphaMode::Blend: return "blend";
        case AlphaMode::Opaque: break;
    }
    return "opaque";
}

}  // namespace bounce
