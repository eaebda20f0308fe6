#include "bounce/core/image.h"

#include <OpenImageIO/imageio.h>
#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <cstring>
#include <nlohmann/json.hpp>
#include <filesystem>

#include "bounce/core/atomic_file.h"
#include "bounce/core/error.h"
#include "bounce/core/files.h"
#include "bounce/core/image_input.h"
#include "bounce/core/parallel.h"
#include "bounce/core/version.h"

namespace bounce {

#ifdef BOUNCE_TSAN
namespace {
// OpenEXR compresses on its own (uninstrumented) worker pool; under ThreadSanitizer EXR files
// are written and read on the calling thread so the pool's hand-offs are not reported.
const bool exr_single_threaded = OIIO::attribute("exr_threads", -1);
}  // namespace
#endif

Layer& Image::add_layer(const std::string& name, const std::vector<std::string>& channels) {
    layers.push_back({name, channels, std::vector<float>(static_cast<size_t>(width) * height * channels.size(), 0.0f)});
    return layers.back();
}

const Layer* Image::find(const std::string& name) const {
    for (const auto& l : layers)
        if (l.name == name) return &l;
    return nullptr;
}

Layer* Image::find(const std::string& name) {
    for (auto& l : layers)
        if (l.name == name) return &l;
    return nullptr;
}

void write_exr(const std::string& path, const Image& image) {
    std::vector<std::string> names;
    for (const auto& l : image.layers) names.insert(names.end(), l.channels.begin(), l.channels.end());
    OIIO::ImageSpec spec(image.width, image.height, static_cast<int>(names.size()), OIIO::TypeDesc::FLOAT);
    spec.x = image.x0, spec.y = image.y0;
    spec.full_x = 0, spec.full_y = 0;
    spec.full_width = image.full_width, spec.full_height = image.full_height;
    spec.channelnames = names;
    spec.alpha_channel = -1;
    for (size_t i = 0; i < names.size(); ++i)
        if (names[i] == "A") spec.alpha_channel = static_cast<int>(i);
    spec.attribute("compression", "zip");
    // Scene-linear Rec.709 / sRGB primaries, D65 white (red, green, blue, white as x, y pairs):
    // said in the file so a compositor's colour management need not assume it.
    static constexpr float rec709[8] = {0.64f, 0.33f, 0.30f, 0.60f, 0.15f, 0.06f, 0.3127f, 0.3290f};
    spec.attribute("chromaticities", OIIO::TypeDesc(OIIO::TypeDesc::FLOAT, 8), rec709);
    spec.attribute("Software", bounce_software());
    for (const auto& [k, v] : image.metadata) spec.attribute("bounce:" + k, v);
    std::vector<float> pixels(static_cast<size_t>(image.width) * image.height * names.size());
    size_t stride = names.size(), offset = 0;
    for (const auto& l : image.layers) {
        size_t nc = l.channels.size();
        for (size_t p = 0; p < static_cast<size_t>(image.width) * image.height; ++p)
            for (size_t c = 0; c < nc; ++c) pixels[p * stride + offset + c] = l.data[p * nc + c];
        offset += nc;
    }
    write_atomically(path, [&](const std::string& tmp) {
        auto out = OIIO::ImageOutput::create("openexr");
        if (!out || !out->open(tmp, spec)) throw InputError(path, "", "cannot write image: " + (out ? out->geterror() : OIIO::geterror()));
        if (!out->write_image(OIIO::TypeDesc::FLOAT, pixels.data()) || !out->close())
            throw InputError(path, "", "cannot write image: " + out->geterror());
    });
}

Image read_exr(const std::string& path) {
    check_input_file(path);
    auto in = OIIO::ImageInput::open(path);
    if (!in) throw InputError(path, "", "cannot read image: " + OIIO::geterror());
    const OIIO::ImageSpec& spec = in->spec();
    if (spec.deep) throw InputError(path, "", "is a deep image; expected a flat image");
    Image img;
    img.x0 = spec.x, img.y0 = spec.y, img.width = spec.width, img.height = spec.height;
    img.full_width = spec.full_width, img.full_height = spec.full_height;
    std::vector<float> pixels(static_cast<size_t>(spec.width) * spec.height * spec.nchannels);
    if (!in->read_image(0, 0, 0, spec.nchannels, OIIO::TypeDesc::FLOAT, pixels.data()))
        throw InputError(path, "", "cannot read image: " + in->geterror());
    for (const auto& p : spec.extra_attribs) {
        std::string name = p.name().string();
        if (name.rfind("bounce:", 0) == 0) img.metadata[name.substr(7)] = spec.get_string_attribute(name);
    }
    // Group channels by prefix ("direct.R" -> layer "direct"; R,G,B,A -> "beauty").
    std::vector<std::pair<std::string, std::vector<int>>> groups;
    for (int c = 0; c < spec.nchannels; ++c) {
        const std::string& n = spec.channelnames[static_cast<size_t>(c)];
        auto dot = n.rfind('.');
        std::string layer = dot == std::string::npos ? (n == "Z" ? "depth" : "beauty") : n.substr(0, dot);
        auto it = std::find_if(groups.begin(), groups.end(), [&](const auto& g) { return g.first == layer; });
        if (it == groups.end())
            groups.push_back({layer, {c}});
        else
            it->second.push_back(c);
    }
    for (const auto& [name, idx] : groups) {
        std::vector<std::string> chans;
        for (int c : idx) chans.push_back(spec.channelnames[static_cast<size_t>(c)]);
        Layer& l = img.add_layer(name, chans);
        for (size_t p = 0; p < static_cast<size_t>(spec.width) * spec.height; ++p)
            for (size_t k = 0; k < idx.size(); ++k)
                l.data[p * idx.size() + k] = pixels[p * static_cast<size_t>(spec.nchannels) + static_cast<size_t>(idx[k])];
    }
    return img;
}

float srgb_encode(float x) {
    x = std::clamp(x, 0.0f, 1.0f);
    return x <= 0.0031308f ? 12.92f * x : 1.055f * std::pow(x, 1 / 2.4f) - 0.055f;
}

uint8_t srgb8(float linear) { return static_cast<uint8_t>(std::lround(255.0f * srgb_encode(linear))); }

void write_png_rgb8(const std::string& path, int width, int height, const std::vector<uint8_t>& rgb) {
    OIIO::ImageSpec spec(width, height, 3, OIIO::TypeDesc::UINT8);
    write_atomically(path, [&](const std::string& tmp) {
        auto out = OIIO::ImageOutput::create("png");
        if (!out || !out->open(tmp, spec)) throw InputError(path, "", "cannot write image: " + (out ? out->geterror() : OIIO::geterror()));
        if (!out->write_image(OIIO::TypeDesc::UINT8, rgb.data()) || !out->close())
            throw InputError(path, "", "cannot write image: " + out->geterror());
    });
}

std::string serialize_image(const Image& img) {
    nlohmann::json head = {{"size", {img.full_width, img.full_height, img.x0, img.y0, img.width, img.height}}, {"metadata", img.metadata}};
    for (const Layer& l : img.layers) head["layers"].push_back({{"name", l.name}, {"channels", l.channels}});
    std::string out = head.dump();
    const auto n = static_cast<uint64_t>(out.size());
    out.insert(0, reinterpret_cast<const char*>(&n), sizeof(n));
    for (const Layer& l : img.layers) out.append(reinterpret_cast<const char*>(l.data.data()), l.data.size() * sizeof(float));
    return out;
}

Image parse_image(const std::string& bytes) {
    uint64_t n = 0;
    std::memcpy(&n, bytes.data(), sizeof(n));
    const nlohmann::json head = nlohmann::json::parse(bytes.substr(sizeof(n), n));
    Image img;
    const auto s = head["size"].get<std::vector<int>>();
    img.full_width = s[0], img.full_height = s[1], img.x0 = s[2], img.y0 = s[3], img.width = s[4], img.height = s[5];
    img.metadata = head["metadata"].get<std::map<std::string, std::string>>();
    size_t at = sizeof(n) + n;
    if (head.contains("layers"))
        for (const auto& l : head["layers"]) {
            Layer& layer = img.add_layer(l["name"], l["channels"].get<std::vector<std::string>>());
            std::memcpy(layer.data.data(), bytes.data() + at, layer.data.size() * sizeof(float));
            at += layer.data.size() * sizeof(float);
        }
    return img;
}

Image assemble_tiles(const std::array<int, 4>& w, const std::vector<Image>& tiles) {
    Image out;
    out.full_width = tiles.front().full_width, out.full_height = tiles.front().full_height;
    out.x0 = w[0], out.y0 = w[2], out.width = w[1] - w[0], out.height = w[3] - w[2];
    out.metadata = tiles.front().metadata;
    for (const Layer& l : tiles.front().layers) out.add_layer(l.name, l.channels);
    for (const Image& t : tiles)
        for (size_t li = 0; li < out.layers.size(); ++li) {
            const size_t nc = out.layers[li].channels.size();
            for (int y = 0; y < t.height; ++y)
                std::copy_n(&t.layers[li].data[static_cast<size_t>(y) * t.width * nc], static_cast<size_t>(t.width) * nc,
                            out.at(out.layers[li], t.x0 - out.x0, t.y0 - out.y0 + y));
        }
    return out;
}

std::string texture_problem(const std::string& path) {
    std::string why;
    auto in = open_image(path, why);
    if (!in) return "not a readable image: " + why;
    const OIIO::ImageSpec& spec = in->spec();
    if (spec.width <= 0 || spec.height <= 0 || spec.nchannels <= 0) return "the image has no pixels";
    const bool mipmapped = in->seek_subimage(0, 1);
    if (static_cast<int64_t>(spec.width) * spec.height > int64_t{8192} * 8192 && !(spec.tile_width > 0 && mipmapped))
        return fmt::format(
            "a {}x{} image that is not tiled and MIP-mapped would be read whole for every lookup; convert it "
            "with OpenImageIO's maketx",
            spec.width, spec.height);
    return "";
}

std::vector<uint8_t> display_rgb8(const Image& image, const Layer& l, float exposure, const DisplayTransform& display) {
    const size_t n = static_cast<size_t>(image.width) * static_cast<size_t>(image.height), nc = l.channels.size();
    std::vector<uint8_t> rgb(3 * n);
    if (nc == 0) return rgb;
    const auto byte = [](float v) { return static_cast<uint8_t>(std::lround(std::clamp(v, 0.0f, 1.0f) * 255)); };
    std::vector<float> value(3 * n);
    for (size_t p = 0; p < n; ++p)
        for (size_t c = 0; c < 3; ++c) value[3 * p + c] = l.data[p * nc + std::min(c, nc - 1)];
    // Directions, depth, occlusion and masks are shown as values, not light: no exposure, no
    // display transform (the page says the exposure does not apply to them).
    if (l.name == "N" || l.name == "bentnormal") {
        for (size_t i = 0; i < 3 * n; ++i) rgb[i] = byte(0.5f + 0.5f * value[i]);
    } else if (l.name == "depth") {
        float near = INFINITY, far = 0;
        for (const float z : value)
            if (z > 0 && std::isfinite(z)) near = std::min(near, z), far = std::max(far, z);
        for (size_t i = 0; i < 3 * n; ++i) {
            const float z = value[i];
            rgb[i] = byte(z > 0 && std::isfinite(z) ? 1 - 0.9f * (z - near) / std::max(far - near, 1e-30f) : 0);
        }
    } else if (l.name == "ao") {
        // Occlusion is a fraction, not light: its value as a grey (1, unoccluded, is white).
        for (size_t i = 0; i < 3 * n; ++i) rgb[i] = byte(value[i]);
    } else if (l.name == "refined") {
        // A coverage mask of the few pixels refinement gathered at: any coverage shows plainly.
        for (size_t i = 0; i < 3 * n; ++i) rgb[i] = byte(value[i] > 0 ? 0.3f + 0.7f * value[i] : 0);
    } else {
        const float scale = std::exp2(exposure);
        for (float& v : value) v *= scale;
        display.apply(value.data(), n);
        for (size_t i = 0; i < 3 * n; ++i) rgb[i] = byte(value[i]);
    }
    return rgb;
}

void write_png(const std::string& path, const Image& image, const std::string& layer, const DisplayTransform& display) {
    const Layer* l = image.find(layer);
    if (!l) throw InputError(path, "", "the image has no layer \"" + layer + "\"");
    write_png_rgb8(path, image.width, image.height, display_rgb8(image, *l, 0.0f, display));
}

}  // namespace bounce
