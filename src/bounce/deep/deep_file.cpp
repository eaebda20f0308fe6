// Deep file I/O: OpenEXR deep scanlines through OpenImageIO.
#include <OpenImageIO/deepdata.h>
#include <algorithm>
#include <OpenImageIO/imageio.h>
#include <fmt/format.h>

#include "bounce/core/atomic_file.h"
#include "bounce/core/error.h"
#include "bounce/core/files.h"
#include "bounce/core/image_input.h"
#include "bounce/deep/deep_buffer.h"
#include "bounce/core/version.h"

namespace bounce {

namespace {

// Version 2 added the fur channels (T, v); version 1 files read with them zero.
constexpr int kDeepVersion = 2;
constexpr size_t kFirstFurChannel = 23;

struct Channel {
    const char* name;
    OIIO::TypeDesc type;
};

// Z and A first: the layout deep-aware compositors expect.
const std::vector<Channel>& deep_channels() {
    static const std::vector<Channel> ch = {
        {"Z", OIIO::TypeDesc::FLOAT},      {"A", OIIO::TypeDesc::FLOAT},          {"P.X", OIIO::TypeDesc::FLOAT},
        {"P.Y", OIIO::TypeDesc::FLOAT},    {"P.Z", OIIO::TypeDesc::FLOAT},        {"N.X", OIIO::TypeDesc::FLOAT},
        {"N.Y", OIIO::TypeDesc::FLOAT},    {"N.Z", OIIO::TypeDesc::FLOAT},        {"Ng.X", OIIO::TypeDesc::FLOAT},
        {"Ng.Y", OIIO::TypeDesc::FLOAT},   {"Ng.Z", OIIO::TypeDesc::FLOAT},       {"Pref.X", OIIO::TypeDesc::FLOAT},
        {"Pref.Y", OIIO::TypeDesc::FLOAT}, {"Pref.Z", OIIO::TypeDesc::FLOAT},     {"Nref.X", OIIO::TypeDesc::FLOAT},
        {"Nref.Y", OIIO::TypeDesc::FLOAT}, {"Nref.Z", OIIO::TypeDesc::FLOAT},     {"uv.U", OIIO::TypeDesc::FLOAT},
        {"uv.V", OIIO::TypeDesc::FLOAT},   {"id.material", OIIO::TypeDesc::UINT}, {"id.object", OIIO::TypeDesc::UINT},
        {"id.prim", OIIO::TypeDesc::UINT}, {"footprint", OIIO::TypeDesc::FLOAT},  {"T.X", OIIO::TypeDesc::FLOAT},
        {"T.Y", OIIO::TypeDesc::FLOAT},    {"T.Z", OIIO::TypeDesc::FLOAT},        {"v", OIIO::TypeDesc::FLOAT},
    };
    return ch;
}

/// Float channel values of a fragment in deep_channels() order (ids handled separately).
std::array<float, 27> float_values(const Fragment& f) {
    return {f.depth, f.weight, f.p.x,      f.p.y,      f.p.z,       f.n.x,       f.n.y,       f.n.z,       f.ng.x,
            f.ng.y,  f.ng.z,   f.p_base.x, f.p_base.y, f.p_base.z,  f.n_base.x,  f.n_base.y,  f.n_base.z,  f.uv.x,
            f.uv.y,  0,        0,          0,          f.footprint, f.tangent.x, f.tangent.y, f.tangent.z, f.strand_v};
}

}  // namespace

namespace {

/// Per fragment (parallel to deep.fragments): the alpha that over-compositing in depth order
/// needs for the fragments' coverages to come out as they are, a_i = w_i / (1 - the coverage
/// of the fragments in front) (ties in depth keep their order), and 1 / (1 - that coverage) to
/// premultiply colours by.
void over_alphas(const DeepBuffer& deep, std::vector<float>& alpha, std::vector<float>& unshadowed) {
    alpha.assign(deep.fragments.size(), 0);
    unshadowed.assign(deep.fragments.size(), 1);
    std::vector<uint32_t> order;
    for (size_t i = 0; i < deep.pixel_count(); ++i) {
        order.clear();
        for (uint32_t k = deep.offsets[i]; k < deep.offsets[i + 1]; ++k) order.push_back(k);
        std::stable_sort(order.begin(), order.end(),
                         [&](uint32_t a, uint32_t b) { return deep.fragments[a].depth < deep.fragments[b].depth; });
        double in_front = 0;
        for (uint32_t k : order) {
            const double open = std::max(1 - in_front, 1e-9);
            alpha[k] = static_cast<float>(std::min(1.0, deep.fragments[k].weight / open));
            unshadowed[k] = static_cast<float>(1 / open);
            in_front += deep.fragments[k].weight;
        }
    }
}

}  // namespace

void write_deep(const std::string& path, const DeepBuffer& deep, const std::vector<Color>* colour) {
    std::vector<Channel> chans = deep_channels();
    // Colour channels after bounce's own: their indices below are bounce's.
    const size_t first_colour = chans.size();
    if (colour)
        for (const char* name : {"R", "G", "B", "coverage"}) chans.push_back({name, OIIO::TypeDesc::FLOAT});
    OIIO::ImageSpec spec(deep.width, deep.height, static_cast<int>(chans.size()), OIIO::TypeDesc::FLOAT);
    spec.x = deep.x0, spec.y = deep.y0;
    spec.full_x = 0, spec.full_y = 0;
    spec.full_width = deep.full_width, spec.full_height = deep.full_height;
    spec.deep = true;
    spec.channelnames.clear();
    spec.channelformats.clear();
    for (const auto& c : chans) {
        spec.channelnames.emplace_back(c.name);
        spec.channelformats.push_back(c.type);
    }
    spec.z_channel = 0;
    spec.alpha_channel = 1;
    std::vector<float> alpha, unshadowed;
    if (colour) over_alphas(deep, alpha, unshadowed);
    spec.attribute("compression", "zips");
    spec.attribute("bounce:deep_version", kDeepVersion);
    spec.attribute("bounce:spp", deep.spp);
    spec.attribute("bounce:seed", fmt::format("{}", deep.seed));
    spec.attribute("bounce:scene_fingerprint", fmt::format("{:016x}", deep.scene_fingerprint));
    spec.attribute("Software", std::string("bounce ") + bounce_version());

    OIIO::DeepData dd;
    dd.init(static_cast<int64_t>(deep.pixel_count()), static_cast<int>(chans.size()), spec.channelformats, spec.channelnames);
    for (size_t i = 0; i < deep.pixel_count(); ++i)
        dd.set_samples(static_cast<int64_t>(i), static_cast<int>(deep.offsets[i + 1] - deep.offsets[i]));
    for (size_t i = 0; i < deep.pixel_count(); ++i) {
        for (uint32_t k = deep.offsets[i]; k < deep.offsets[i + 1]; ++k) {
            const Fragment& f = deep.fragments[k];
            auto vals = float_values(f);
            int s = static_cast<int>(k - deep.offsets[i]);
            auto pix = static_cast<int64_t>(i);
            for (int c = 0; c < static_cast<int>(first_colour); ++c) {
                if (chans[static_cast<size_t>(c)].type == OIIO::TypeDesc::UINT) continue;
                dd.set_deep_value(pix, c, s, vals[static_cast<size_t>(c)]);
            }
            if (colour) {
                // Premultiplied by the sample's alpha: over in depth order then adds exactly the fragment's part.
                const Color c = (*colour)[k] * unshadowed[k];
                const int at = static_cast<int>(first_colour);
                dd.set_deep_value(pix, 1, s, alpha[k]);
                dd.set_deep_value(pix, at, s, c.x), dd.set_deep_value(pix, at + 1, s, c.y), dd.set_deep_value(pix, at + 2, s, c.z);
                dd.set_deep_value(pix, at + 3, s, f.weight);
            }
            dd.set_deep_value(pix, 19, s, f.material);
            dd.set_deep_value(pix, 20, s, f.object);
            dd.set_deep_value(pix, 21, s, f.prim);
        }
    }
    write_atomically(path, [&](const std::string& tmp) {
        auto out = OIIO::ImageOutput::create("openexr");
        if (!out || !out->open(tmp, spec))
            throw InputError(path, "", "cannot write deep file: " + (out ? out->geterror() : OIIO::geterror()));
        if (!out->write_deep_image(dd)) throw InputError(path, "", "cannot write deep file: " + out->geterror());
        if (!out->close()) throw InputError(path, "", "cannot write deep file: " + out->geterror());
    });
}

const char* invalid_fragment_field(const Fragment& f) {
    const auto coordinate = [](const Vec3& v) {
        return isfinite(v) && std::fabs(v.x) <= kMaxCoordinate && std::fabs(v.y) <= kMaxCoordinate && std::fabs(v.z) <= kMaxCoordinate;
    };
    // Normals are written unit length; a tolerance far above half-float rounding.
    const auto unit = [](const Vec3& v) { return isfinite(v) && std::fabs(length(v) - 1) < 1e-3f; };
    if (!(f.depth >= 0 && f.depth <= 2 * kMaxCoordinate)) return "Z";
    if (!(f.weight > 0 && f.weight <= 1)) return "A";
    if (!coordinate(f.p)) return "P";
    if (!unit(f.n)) return "N";
    if (!unit(f.ng)) return "Ng";
    if (!coordinate(f.p_base)) return "Pref";
    if (!unit(f.n_base)) return "Nref";
    if (!(std::isfinite(f.uv.x) && std::isfinite(f.uv.y) && std::fabs(f.uv.x) <= 1e9f && std::fabs(f.uv.y) <= 1e9f)) return "uv";
    if (!(f.footprint > 0 && f.footprint <= kMaxCoordinate)) return "footprint";
    if (!(f.is_hair() ? unit(f.tangent) : f.tangent == Vec3(0))) return "T";
    if (!(f.strand_v >= 0 && f.strand_v <= 1)) return "v";
    return nullptr;
}

namespace {

/// Where each of our channels is in the file (OpenEXR stores them sorted by name); -1 for the
/// fur channels a version-1 file lacks. InputError for a missing channel or another type.
std::vector<int> deep_channel_index(const OIIO::ImageSpec& spec, int version, const std::string& path) {
    const auto& chans = deep_channels();
    std::vector<int> index(chans.size(), -1);
    for (size_t c = 0; c < chans.size(); ++c) {
        for (int k = 0; k < spec.nchannels; ++k)
            if (spec.channelnames[static_cast<size_t>(k)] == chans[c].name) index[c] = k;
        if (index[c] < 0 && version == 1 && c >= kFirstFurChannel) continue;
        if (index[c] < 0) throw InputError(path, "channels", fmt::format("missing channel \"{}\"", chans[c].name));
        if (spec.channelformat(index[c]) != chans[c].type)
            throw InputError(path, fmt::format("channel {}", chans[c].name),
                             fmt::format("expected type {}, found {}", chans[c].type.c_str(), spec.channelformat(index[c]).c_str()));
    }
    // A deep file with colour keeps the coverage in its own channel (A is then the over-alpha).
    for (int k = 0; k < spec.nchannels; ++k)
        if (spec.channelnames[static_cast<size_t>(k)] == "coverage" && spec.channelformat(k) == OIIO::TypeDesc::FLOAT) index[1] = k;
    return index;
}

/// The buffer's window, samples, seed and scene fingerprint from the header, checked.
DeepBuffer deep_header(const OIIO::ImageSpec& spec, const std::string& path) {
    DeepBuffer deep;
    deep.x0 = spec.x, deep.y0 = spec.y, deep.width = spec.width, deep.height = spec.height;
    deep.full_width = spec.full_width, deep.full_height = spec.full_height;
    deep.spp = spec.get_int_attribute("bounce:spp", 0);
    try {
        deep.seed = std::stoull(spec.get_string_attribute("bounce:seed", "x"));
        deep.scene_fingerprint = std::stoull(spec.get_string_attribute("bounce:scene_fingerprint", "x"), nullptr, 16);
    } catch (const std::exception&) {
        throw InputError(path, "header", "missing or malformed bounce:seed / bounce:scene_fingerprint");
    }
    // render.spp's range (1 .. 4096): a crafted 2e9 would size every later buffer by it.
    if (deep.spp > 4096) throw InputError(path, "header/bounce:spp", fmt::format("{} samples per pixel is outside 1 .. 4096", deep.spp));
    if (deep.spp <= 0 || deep.width <= 0 || deep.height <= 0 || deep.x0 < 0 || deep.y0 < 0 || deep.x0 + deep.width > deep.full_width ||
        deep.y0 + deep.height > deep.full_height)
        throw InputError(path, "header", "inconsistent image window or sample count");
    return deep;
}

/// Every pixel's fragments from the file's deep samples, each field checked.
void read_fragments(const OIIO::DeepData& dd, const std::vector<int>& index, const std::string& path, DeepBuffer& deep) {
    deep.offsets.resize(deep.pixel_count() + 1);
    deep.offsets[0] = 0;
    for (size_t i = 0; i < deep.pixel_count(); ++i) {
        int n = dd.samples(static_cast<int64_t>(i));
        if (n < 0 || n > deep.spp)
            throw InputError(path, fmt::format("pixel {}", i), fmt::format("{} fragments exceed spp {}", n, deep.spp));
        deep.offsets[i + 1] = deep.offsets[i] + static_cast<uint32_t>(n);
    }
    deep.fragments.resize(deep.offsets.back());
    for (size_t i = 0; i < deep.pixel_count(); ++i) {
        auto pix = static_cast<int64_t>(i);
        for (uint32_t k = deep.offsets[i]; k < deep.offsets[i + 1]; ++k) {
            int s = static_cast<int>(k - deep.offsets[i]);
            auto v = [&](int c) {
                const int at = index[static_cast<size_t>(c)];
                return at < 0 ? 0.0f : dd.deep_value(pix, at, s);
            };
            auto id = [&](int c) { return dd.deep_value_uint(pix, index[static_cast<size_t>(c)], s); };
            Fragment& f = deep.fragments[k];
            f.depth = v(0), f.weight = v(1);
            f.p = {v(2), v(3), v(4)}, f.n = {v(5), v(6), v(7)}, f.ng = {v(8), v(9), v(10)};
            f.p_base = {v(11), v(12), v(13)}, f.n_base = {v(14), v(15), v(16)};
            f.uv = {v(17), v(18)};
            f.material = id(19);
            f.object = id(20);
            f.prim = id(21);
            f.footprint = v(22);
            f.tangent = {v(23), v(24), v(25)}, f.strand_v = v(26);
            if (const char* bad = invalid_fragment_field(f))
                throw InputError(
                    path,
                    fmt::format("pixel ({}, {}) fragment {} channel {}", deep.x0 + static_cast<int>(i % static_cast<size_t>(deep.width)),
                                deep.y0 + static_cast<int>(i / static_cast<size_t>(deep.width)), s, bad),
                    "value out of range (not finite, beyond +-1e18, or a normal that is not unit length)");
        }
    }
}

}  // namespace

DeepBuffer read_deep(const std::string& path) {
    check_input_file(path);
    std::string why;
    auto in = open_image(path, why);
    if (!in) throw InputError(path, "", "not a readable deep file: " + why);
    const OIIO::ImageSpec& spec = in->spec();
    if (!spec.deep) throw InputError(path, "", "not a deep image (expected an OpenEXR deep file from --deep-out)");
    int version = spec.get_int_attribute("bounce:deep_version", -1);
    if (version != kDeepVersion && version != 1)
        throw InputError(path, "bounce:deep_version",
                         version < 0 ? "not a bounce deep file (no bounce:deep_version attribute)"
                                     : fmt::format("unsupported version {} (this bounce reads 1 to {})", version, kDeepVersion));
    const std::vector<int> index = deep_channel_index(spec, version, path);
    DeepBuffer deep = deep_header(spec, path);
    OIIO::DeepData dd;
    if (!in->read_native_deep_image(0, 0, dd)) throw InputError(path, "", "cannot read deep data: " + in->geterror());
    read_fragments(dd, index, path, deep);
    return deep;
}

}  // namespace bounce
