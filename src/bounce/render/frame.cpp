#include "bounce/render/frame.h"

#include <filesystem>
#include <regex>

#include "bounce/cache/cache_file.h"
#include "bounce/core/error.h"
#include "bounce/core/files.h"

namespace bounce {

namespace fs = std::filesystem;

std::string FrameFiles::png() const { return fs::path(output).replace_extension(".png").string(); }

void FrameFiles::check() const {
    std::string ext = fs::path(output).extension().string();
    std::transform(ext.begin(), ext.end(), ext.begin(), ::tolower);
    if (ext != ".exr")
        throw InputError("command line", "-o " + output, "the output is an OpenEXR file (.exr); its PNG is written beside it");
    const std::vector<std::string> inputs{scene, deep_in, cache_in, base};
    std::vector<std::pair<std::string, std::string>> outputs{{"-o", output}, {"-o", png()}};
    if (!deep_out.empty()) outputs.emplace_back("--deep-out", deep_out);
    if (!cache_out.empty()) outputs.emplace_back("--cache-out", cache_out);
    if (!stats_json.empty()) outputs.emplace_back("--stats-json", stats_json);
    for (size_t i = 0; i < outputs.size(); ++i) {
        check_output_file(outputs[i].second, inputs);
        for (size_t j = 0; j < i; ++j)
            if (fs::path(outputs[i].second).lexically_normal() == fs::path(outputs[j].second).lexically_normal())
                throw InputError("command line", outputs[i].first + " " + outputs[i].second,
                                 "names the same file as " + outputs[j].first);
    }
    for (const auto& [flag, path] : outputs) remove_stale_temporaries(path);
}

FrameFiles expand_frame(const FrameFiles& p, int frame) {
    FrameFiles f = p;
    for (std::string* s : {&f.output, &f.deep_in, &f.deep_out, &f.cache_in, &f.cache_out, &f.stats_json, &f.base})
        *s = expand_frame_pattern(*s, frame);
    return f;
}

std::pair<int, int> parse_frame_range(const std::string& text, const std::string& origin) {
    std::smatch m;
    if (!std::regex_match(text, m, std::regex(R"((-?\d{1,6})-(-?\d{1,6}))")) || std::stoi(m[1]) > std::stoi(m[2]))
        throw InputError("command line", origin, "expected FIRST-LAST, e.g. 1-24");
    return {std::stoi(m[1]), std::stoi(m[2])};
}

FrameFiles sequence_frame(const FrameFiles& patterns, int first, int frame) {
    FrameFiles f = expand_frame(patterns, frame);
    if (frame > first) f.cache_in = expand_frame_pattern(patterns.cache_out, frame - 1);
    return f;
}

void write_frame_outputs(const RenderResult& result, const FrameFiles& files, const std::string& show) {
    const Image* image = &result.image;
    Image pasted;
    if (!files.base.empty()) {
        pasted = paste_over(read_exr(files.base), result.image, files.base);
        image = &pasted;
    }
    if (!image->find(show))
        throw InputError("command line", "--show " + show,
                         show == "records" ? "no records to show (render with --gi cache or give --cache-in)"
                                           : "the render has no layer \"" + show + "\"");
    write_exr(files.output, *image);
    write_png(files.png(), *image, show);
    if (result.cache && !files.cache_out.empty()) write_cache_file(files.cache_out, result.cache->to_file(result.cache_info));
}

}  // namespace bounce
