#include "bounce/scene/surface_textures.h"

#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <vector>

#include "bounce/core/image_input.h"
#include "bounce/core/memory.h"
#include "bounce/scene/texel_lookup.h"

namespace bounce {

Color EmissionMap::at(const Vec2& uv) const {
    return periodic_bilinear(width, height, uv, [&](size_t x, size_t y) {
        const float* t = &rgb[3 * (y * static_cast<size_t>(width) + x)];
        return Color(t[0], t[1], t[2]);
    });
}

Vec2 UvTransform::transformed(const Vec2& uv) const {
    const float s = uv.x * scale.x, t = (1 - uv.y) * scale.y;
    const float c = std::cos(rotation), n = std::sin(rotation);
    // KHR_texture_transform's matrix: rows (cos, sin) and (-sin, cos) in image space.
    return {offset.x + c * s + n * t, 1 - (offset.y - n * s + c * t)};
}

std::unique_ptr<OIIO::ImageInput> open_whole_texture(const std::string& path, const char* kind, std::string& error) {
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
    if (static_cast<double>(spec.width) * spec.height > kMaxWholeTextureTexels) {
        error = fmt::format(
            "a {}x{} {} texture is read whole and may hold at most 8192x8192 pixels; resize it "
            "(e.g. OpenImageIO's oiiotool --resize)",
            spec.width, spec.height, kind);
        return nullptr;
    }
    return in;
}

std::shared_ptr<const EmissionMap> load_emission_map(const std::string& path, std::string& error) {
    auto in = open_whole_texture(path, "emission", error);
    if (!in) return nullptr;
    const OIIO::ImageSpec& spec = in->spec();
    const double texels = static_cast<double>(spec.width) * spec.height;
    const int channels = std::min(spec.nchannels, 3);
    if (error = memory_shortfall(texels * (3 + channels) * sizeof(float), "reading " + path); !error.empty()) return nullptr;
    std::vector<float> values(static_cast<size_t>(texels) * static_cast<size_t>(channels));
    if (!in->read_image(0, 0, 0, channels, OIIO::TypeDesc::FLOAT, values.data())) {
        error = "cannot read its pixels: " + in->geterror();
        return nullptr;
    }
    auto map = std::make_shared<EmissionMap>();
    map->width = spec.width, map->height = spec.height;
    map->rgb.resize(static_cast<size_t>(texels) * 3);
    for (size_t i = 0; i < static_cast<size_t>(texels); ++i)
        for (size_t c = 0; c < 3; ++c) {
            const float v = values[i * static_cast<size_t>(channels) + std::min(c, static_cast<size_t>(channels) - 1)];
            if (!(v >= 0 && v <= kMaxRadiometric)) {
                error = fmt::format("texel ({}, {}) holds {}, not a number in [0, {:g}]", i % static_cast<size_t>(spec.width),
                                    i / static_cast<size_t>(spec.width), v, kMaxRadiometric);
                return nullptr;
            }
            map->rgb[3 * i + c] = v;
            map->peak[static_cast<int>(c)] = std::max(map->peak[static_cast<int>(c)], v);
        }
    return map;
}

bool make_uv_transform(const Vec2& offset, float rotation, const Vec2& scale, UvTransform& out, std::string& error) {
    for (const float v : {offset.x, offset.y, rotation, scale.x, scale.y})
        if (!(std::abs(v) <= 1e6f)) {
            error = fmt::format("{} is not a number within 1e6", v);
            return false;
        }
    if (scale.x == 0 || scale.y == 0) {
        error = "a scale of 0 reads one texel everywhere";
        return false;
    }
    out = {offset, rotation, scale};
    return true;
}

}  // namespace bounce
