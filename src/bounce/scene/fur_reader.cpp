#include "bounce/scene/fur_reader.h"

#include <OpenImageIO/imageio.h>
#include <fmt/format.h>

#include <cmath>

#include "bounce/core/image_input.h"
#include "bounce/core/memory.h"
#include "bounce/scene/link_reader.h"

namespace bounce {

const std::vector<std::string>& fur_keys() {
    static const std::vector<std::string> keys = {"count",
                                                  "density",
                                                  "length",
                                                  "length_variation",
                                                  "width_root",
                                                  "width_tip",
                                                  "segments",
                                                  "curl",
                                                  "curl_turns",
                                                  "gravity",
                                                  "clump",
                                                  "clump_size",
                                                  "lean",
                                                  "seed",
                                                  "color_root",
                                                  "color_tip",
                                                  "specular",
                                                  "specular_exponent",
                                                  "falloff_root",
                                                  "falloff_exponent",
                                                  "cast_indirect",
                                                  "cast_shadows",
                                                  "visible_to",
                                                  "indirect_at",
                                                  "density_texture",
                                                  "length_texture"};
    return keys;
}

const std::vector<std::string>& fur_lighting_keys() {
    static const std::vector<std::string> keys = {
        "color_root",       "color_tip",     "specular",     "specular_exponent", "falloff_root",
        "falloff_exponent", "cast_indirect", "cast_shadows", "indirect_at"};  // visible_to: its camera flag is visibility
    return keys;
}

namespace {

/// A map's first channel as floats in [0, 1].
std::shared_ptr<const UvMap> load_uv_map(const JsonReader& r, const std::string& key) {
    const std::string path = r.file(key, false);
    if (path.empty()) return nullptr;
    std::string unreadable;
    auto in = open_image(path, unreadable);
    if (!in) r.fail(key, "cannot read image \"" + path + "\": " + unreadable);
    const OIIO::ImageSpec& spec = in->spec();
    if (spec.width <= 0 || spec.height <= 0 || static_cast<int64_t>(spec.width) * spec.height > (int64_t{1} << 28))
        r.fail(key, fmt::format("image \"{}\" has an unusable size {}x{}", path, spec.width, spec.height));
    auto map = std::make_shared<UvMap>();
    map->width = spec.width, map->height = spec.height;
    const double texels = static_cast<double>(spec.width) * spec.height;
    if (std::string why = memory_shortfall(texels * (spec.nchannels + 1) * sizeof(float), "reading " + path); !why.empty())
        r.fail(key, why);
    std::vector<float> all(static_cast<size_t>(spec.width) * static_cast<size_t>(spec.height) * static_cast<size_t>(spec.nchannels));
    if (!in->read_image(0, 0, 0, spec.nchannels, OIIO::TypeDesc::FLOAT, all.data()))
        r.fail(key, "cannot read image \"" + path + "\": " + in->geterror());
    map->values.resize(static_cast<size_t>(spec.width) * static_cast<size_t>(spec.height));
    for (size_t i = 0; i < map->values.size(); ++i) {
        const float v = all[i * static_cast<size_t>(spec.nchannels)];
        // A NaN would silently remove the fur there: the map is broken, say where.
        if (!std::isfinite(v))
            r.fail(key, fmt::format("image \"{}\" pixel ({}, {}) is not a finite number", path, i % static_cast<size_t>(spec.width),
                                    i / static_cast<size_t>(spec.width)));
        map->values[i] = std::clamp(v, 0.0f, 1.0f);
    }
    return map;
}

}  // namespace

std::shared_ptr<Fur> read_fur(const JsonReader& r, const TriangleMesh& surface, const DicingSettings& dicing) {
    FurParams p;
    constexpr int kMaxStrands = 2'000'000'000;
    if (r.has("count") == r.has("density")) r.fail("", "fur needs one of \"count\" (strands) or \"density\" (strands per unit area)");
    if (r.has("count")) {
        p.count = static_cast<uint64_t>(r.integer("count", 0, 0, kMaxStrands));
    } else {
        const double n = static_cast<double>(r.number("density", 0, 0, 1e30)) * surface.area();
        if (!(n <= kMaxStrands)) r.fail("density", fmt::format("{:.3g} strands on this surface, more than {}", n, kMaxStrands));
        p.count = static_cast<uint64_t>(std::llround(n));
    }
    p.length = r.number("length", p.length, 0, kMaxCoordinate);
    if (!(p.length > 0)) r.fail("length", "length must be > 0");
    p.length_variation = r.number("length_variation", p.length_variation, 0, 1);
    p.width_root = r.number("width_root", p.width_root, 0, kMaxCoordinate);
    p.width_tip = r.number("width_tip", p.width_tip, 0, kMaxCoordinate);
    if (!(std::max(p.width_root, p.width_tip) > 0)) r.fail("width_root", "strands need a width > 0 at the root or the tip");
    p.segments = r.integer("segments", p.segments, 1, 64);
    p.curl = r.number("curl", p.curl, 0, 10);
    p.curl_turns = r.number("curl_turns", p.curl_turns, 0, 1000);
    p.gravity = r.number("gravity", p.gravity, 0, 1);
    p.clump = r.number("clump", p.clump, 0, 1);
    p.clump_size = r.number("clump_size", p.clump_size, 0, kMaxCoordinate);
    if (p.clump > 0 && !(p.clump_size > 0)) r.fail("clump_size", "clumping needs a clump_size > 0");
    p.lean = r.number("lean", p.lean, 0, 1.5707);
    p.seed = static_cast<uint64_t>(r.integer("seed", 1, 0, 2'147'483'647));
    p.color_root = r.color("color_root", p.color_root);
    p.color_tip = r.color("color_tip", p.color_tip);
    for (const auto& [key, c] : {std::pair{"color_root", p.color_root}, std::pair{"color_tip", p.color_tip}})
        for (int i = 0; i < 3; ++i)
            if (c[i] > 1) r.fail(key, "albedo components must be <= 1 (energy conservation)");
    p.specular = r.number("specular", p.specular, 0, 100);
    p.specular_exponent = r.number("specular_exponent", p.specular_exponent, 0, 1e4);
    p.falloff_root = r.number("falloff_root", p.falloff_root, 0, 1);
    p.falloff_exponent = r.number("falloff_exponent", p.falloff_exponent, 0.01, 100);
    // The older names of two of the flags: one name per flag in a block.
    for (const auto& [old, now] : {std::pair{"cast_indirect", "indirect"}, std::pair{"cast_shadows", "shadows"}})
        if (r.has(old) && r.has("visible_to") && r.raw("visible_to").is_object() && r.raw("visible_to").contains(now))
            r.fail(old, fmt::format("the older name of visible_to.{}: give one of them", now));
    p.visible_to.indirect = r.boolean("cast_indirect", p.visible_to.indirect);
    p.visible_to.shadows = r.boolean("cast_shadows", p.visible_to.shadows);
    read_visibility(r, p.visible_to);
    p.indirect_at = r.choice("indirect_at", "root", {"root", "fragment"}) == "root" ? FurIndirectAt::Root : FurIndirectAt::Fragment;
    p.density_map = load_uv_map(r, "density_texture");
    p.length_map = load_uv_map(r, "length_texture");
    if ((p.density_map || p.length_map) && surface.uvs.empty())
        r.fail(p.density_map ? "density_texture" : "length_texture", "the growing surface has no uvs to look the map up with");
    const double budget = static_cast<double>(dicing.memory_budget) * 1073741824.0;
    const auto bytes = static_cast<double>(p.memory_bytes(p.count));
    const std::string key = r.has("count") ? "count" : "density";
    if (bytes > budget)
        r.fail(key, fmt::format("{} strands would take {:.1f} GiB, over render.memory_budget ({:g} GiB)", p.count, bytes / 1073741824.0,
                                dicing.memory_budget));
    if (std::string why = memory_shortfall(bytes, fmt::format("growing {} strands", p.count)); !why.empty()) r.fail(key, why);
    return std::make_shared<Fur>(grow_fur(surface, p));
}

}  // namespace bounce
