#include "bounce/render/frame.h"

#include <filesystem>
#include <regex>

#include <OpenImageIO/imageio.h>
#include <fmt/format.h>

#include <algorithm>
#include <array>
#include <fstream>

#include "bounce/cache/cache_file.h"
#include "bounce/cache/passes.h"
#include "bounce/scene/shot.h"
#include "bounce/core/atomic_file.h"
#include "bounce/core/error.h"
#include "bounce/core/files.h"
#include "bounce/core/image_input.h"

namespace bounce {

namespace fs = std::filesystem;

std::string FrameFiles::png() const { return fs::path(output).replace_extension(".png").string(); }

void FrameFiles::check(const Scene& loaded) const {
    // No output: a front end that keeps the image in memory (Python, the lighting tool).
    if (!output.empty() && lower_extension(output) != ".exr")
        throw InputError("command line", "-o " + output, "the output is an OpenEXR file (.exr); its PNG is written beside it");
    std::vector<std::string> inputs = loaded.input_paths();
    inputs.insert(inputs.end(), {scene, deep_in, cache_in, base});
    inputs.insert(inputs.end(), display->files().begin(), display->files().end());  // the OpenColorIO config and its LUTs
    std::vector<std::pair<std::string, std::string>> outputs;
    if (!output.empty()) outputs = {{"-o", output}, {"-o", png()}};
    if (!deep_out.empty()) outputs.emplace_back("--deep-out", deep_out);
    if (!cache_out.empty()) outputs.emplace_back("--cache-out", cache_out);
    if (!stats_json.empty()) outputs.emplace_back("--stats-json", stats_json);
    for (size_t i = 0; i < outputs.size(); ++i) {
        check_output_file(outputs[i].second, inputs, loaded.input_folders);
        for (size_t j = 0; j < i; ++j)
            if (fs::path(outputs[i].second).lexically_normal() == fs::path(outputs[j].second).lexically_normal())
                throw InputError("command line", outputs[i].first + " " + outputs[i].second, "names the same file as " + outputs[j].first);
    }
    for (const auto& [flag, path] : outputs) remove_stale_temporaries(path);
}

namespace {

/// The names a frame number expands in.
template <typename Files>
auto frame_names(Files& f) {
    return std::array{&f.output, &f.deep_in, &f.deep_out, &f.cache_in, &f.cache_out, &f.stats_json, &f.base};
}

}  // namespace

bool FrameFiles::patterned() const {
    return std::ranges::any_of(frame_names(*this), [](const std::string* s) { return s->find('#') != std::string::npos; });
}

FrameFiles expand_frame(const FrameFiles& p, int frame) {
    FrameFiles f = p;
    for (std::string* s : frame_names(f)) *s = expand_frame_pattern(*s, frame);
    return f;
}

std::pair<int, int> parse_frame_range(const std::string& text, const std::string& origin) {
    std::smatch m;
    if (!std::regex_match(text, m, std::regex(R"((-?\d+)-(-?\d+))")))
        throw InputError("command line", origin, "expected FIRST-LAST, e.g. 1-24");
    // A frame number has at most 6 digits (the shots' bound, +-1e6): the message says which is past it.
    const auto frame = [&](const std::string& digits) {
        const std::string magnitude = digits.substr(digits[0] == '-' ? 1 : 0);
        if (magnitude.size() > 7 || std::stoi(magnitude) > kMaxFrame)
            throw InputError("command line", origin, fmt::format("frame {} is past the largest frame number, +-{:g}", digits, kMaxFrame));
        return std::stoi(digits);
    };
    const int first = frame(m[1]), last = frame(m[2]);
    if (first > last) throw InputError("command line", origin, fmt::format("the first frame {} is after the last {}", first, last));
    return {first, last};
}

FrameFiles sequence_frame(const FrameFiles& patterns, int first, int frame) {
    FrameFiles f = expand_frame(patterns, frame);
    if (frame > first) f.cache_in = expand_frame_pattern(patterns.cache_out, frame - 1);
    return f;
}

std::vector<std::string> frame_layers(const FramePlan& plan) {
    std::vector<std::string> layers{"beauty", "albedo", "N", "depth"};
    const IndirectFrom indirect = plan.indirect();
    if (!(plan.gather.ao && indirect != IndirectFrom::None)) layers.push_back("direct");
    if (indirect != IndirectFrom::None) layers.insert(layers.end(), {"indirect", "ao", "bentnormal"});
    if (plan.cache_start() != CacheStart::None) layers.push_back("records");
    const ShadeStep* shade = plan.find<ShadeStep>();
    if (indirect == IndirectFrom::Cache && shade && shade->refined_layer) layers.push_back("refined");
    return layers;
}

void check_show_layer(const std::string& show, const FramePlan& plan) {
    const std::vector<std::string> layers = frame_layers(plan);
    if (std::find(layers.begin(), layers.end(), show) != layers.end()) return;
    if (show == "records")
        throw InputError("command line", "--show " + show, "no records to show (render with --gi cache or give --cache-in)");
    throw InputError("command line", "--show " + show,
                     fmt::format("this render writes no layer \"{}\" (its layers: {})", show, fmt::join(layers, ", ")));
}

void check_base(const std::string& base, const Scene& scene) {
    check_input_file(base);
    std::string why;
    auto in = open_image(base, why);
    if (!in) throw InputError(base, "", "not a readable image: " + why);
    const OIIO::ImageSpec& spec = in->spec();
    if (spec.full_width != scene.camera.width || spec.full_height != scene.camera.height || spec.width != spec.full_width ||
        spec.height != spec.full_height)
        throw InputError(base, "",
                         fmt::format("base image is {}x{} ({}x{} stored); the render is a {}x{} frame", spec.full_width, spec.full_height,
                                     spec.width, spec.height, scene.camera.width, scene.camera.height));
    const std::string want = fmt::format("{:016x}", scene.visibility_fingerprint());
    const std::string have = spec.get_string_attribute("bounce:scene_fingerprint");
    if (have != want)
        throw InputError(base, "bounce:scene_fingerprint",
                         have.empty() ? "not a bounce render (no scene fingerprint)"
                                      : "base was rendered from another scene or camera: paste the crop over a render of this one");
}

std::optional<Image> write_frame_outputs(const RenderResult& result, const FrameFiles& files, const std::string& show, Stats& stats) {
    PhaseTimer t(stats, "write outputs");
    std::optional<Image> pasted;
    if (!files.base.empty()) pasted = paste_over(read_exr(files.base), result.image, files.base);
    const Image* image = pasted ? &*pasted : &result.image;
    if (!files.output.empty()) {  // the lighting tool keeps its image in memory
        write_exr(files.output, *image);
        write_png(files.png(), *image, show, *files.display);
    }
    if (!files.deep_out.empty() && result.gathered_deep)
        write_deep(files.deep_out, *result.gathered_deep, result.deep_colour.empty() ? nullptr : &result.deep_colour);
    if (result.cache && !files.cache_out.empty()) write_cache_file(files.cache_out, result.cache->to_file(result.cache_info));
    t.stop();
    if (files.stats_json.empty()) return pasted;
    const std::string text = stats.to_json().dump(2) + "\n";
    write_atomically(files.stats_json, [&](const std::string& tmp) {
        std::ofstream out(tmp);
        out << text;
        if (!out) throw InputError(files.stats_json, "", "cannot write stats file");
    });
    return pasted;
}

}  // namespace bounce
