// `bounce bake-ao`, `bounce compare` and `bounce cache ...`: the tools beside the renderer.
#include "tools_cmd.h"

#include <OpenImageIO/imageio.h>
#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <sstream>

#include "frontend/environment.h"
#include "bounce/accel/accel.h"
#include "bounce/cache/cache_file.h"
#include "bounce/cache/cache_tools.h"
#include "bounce/core/atomic_file.h"
#include "bounce/core/error.h"
#include "bounce/core/files.h"
#include "bounce/core/image.h"
#include "bounce/core/image_compare.h"
#include "bounce/core/sequence_compare.h"
#include "bounce/render/frame.h"
#include "bounce/core/memory.h"
#include "bounce/gather/ao_bake.h"
#include "bounce/scene/opacity.h"
#include "bounce/scene/scene_load.h"
#include "render_cmd.h"

namespace bounce {

namespace {

std::vector<float> parse_floats(const std::string& text, size_t count, const std::string& flag) {
    std::vector<float> v;
    std::stringstream ss(text);
    for (std::string part; std::getline(ss, part, ',');) {
        try {
            size_t used = 0;
            v.push_back(std::stof(part, &used));
            if (used != part.size()) throw std::invalid_argument(part);
        } catch (...) {
            throw InputError("command line", flag + " " + text, "\"" + part + "\" is not a number");
        }
    }
    if (v.size() != count) throw InputError("command line", flag + " " + text, fmt::format("expected {} comma-separated numbers", count));
    for (float x : v)
        if (!std::isfinite(x) || std::fabs(x) > kMaxCoordinate)
            throw InputError("command line", flag + " " + text, fmt::format("{} is not a finite coordinate within +-1e18", x));
    return v;
}

size_t file_size(const std::string& path) {
    std::error_code ec;
    auto n = std::filesystem::file_size(path, ec);
    return ec ? 0 : static_cast<size_t>(n);
}

/// Files of a sequence pattern (cache.####.bic) that exist, in frame order.
std::vector<std::pair<int, std::string>> sequence_files(const std::string& pattern) {
    std::vector<std::pair<int, std::string>> out;
    auto start = pattern.find('#');
    auto end = pattern.find_first_not_of('#', start);
    std::string prefix = pattern.substr(0, start), suffix = end == std::string::npos ? "" : pattern.substr(end);
    std::filesystem::path dir = std::filesystem::path(pattern).parent_path();
    std::error_code ec;
    for (const auto& e : std::filesystem::directory_iterator(dir.empty() ? "." : dir, ec)) {
        std::string p = dir.empty() ? e.path().filename().string() : e.path().string();
        if (p.size() <= prefix.size() + suffix.size() || p.rfind(prefix, 0) != 0 ||
            p.compare(p.size() - suffix.size(), suffix.size(), suffix) != 0)
            continue;
        std::string digits = p.substr(prefix.size(), p.size() - prefix.size() - suffix.size());
        if (digits.empty() || !std::all_of(digits.begin(), digits.end(), ::isdigit)) continue;
        out.emplace_back(std::stoi(digits), p);
    }
    std::sort(out.begin(), out.end());
    return out;
}

}  // namespace

/// `bounce bake-ao`: an object's occlusion by its own fine detail, in its uv space (EXR, one
/// channel), for a material's ao_texture.
namespace {

std::string rgb(const Color& c) {
    return c.x == c.y && c.y == c.z ? fmt::format("{:g}", c.x) : fmt::format("{:g} {:g} {:g}", c.x, c.y, c.z);
}

/// What a material reads, as one line: every field off its default, and its files by name.
std::string described(const Material& m) {
    const Material none;
    std::vector<std::string> parts{"colour " + rgb(m.color)};
    const auto file = [](const std::string& path) { return std::filesystem::path(path).filename().string(); };
    if (!m.color_texture.empty()) parts.back() += " x " + file(m.color_texture);
    if (m.is_emissive())
        parts.push_back("emission " + rgb(m.emission) + (m.emission_texture.empty() ? "" : " x " + file(m.emission_texture)));
    if (m.has_specular()) parts.push_back(fmt::format("specular {}, roughness {:g}", rgb(m.specular), m.roughness));
    if (!m.metallic_roughness_texture.empty())
        parts.push_back(fmt::format("metallic {:g} x {}", m.metallic, file(m.metallic_roughness_texture)));
    if (!m.bump_texture.empty()) parts.push_back("bump " + file(m.bump_texture));
    if (!m.normal_texture.empty()) parts.push_back("normal map " + file(m.normal_texture));
    if (!m.ao_texture.empty()) parts.push_back("occlusion " + file(m.ao_texture));
    if (!m.uv_transform.identity()) {
        const UvTransform& t = m.uv_transform;
        std::string xf = "uv transform";
        if (!(t.offset == Vec2{0, 0})) xf += fmt::format(" offset {:g} {:g}", t.offset.x, t.offset.y);
        if (t.rotation != 0) xf += fmt::format(" rotation {:g}", t.rotation);
        if (!(t.scale == Vec2{1, 1})) xf += fmt::format(" scale {:g} {:g}", t.scale.x, t.scale.y);
        parts.push_back(xf);
    }
    if (m.uv_set) parts.push_back(fmt::format("uv set {}", m.uv_set));
    if (!(m.mirror == none.mirror)) parts.push_back("mirror " + rgb(m.mirror));
    if (m.is_dielectric()) parts.push_back(fmt::format("transmission {}, ior {:g}", rgb(m.transmission), m.ior));
    if (m.is_cutout()) {
        std::string cut = fmt::format("cutout {}, opacity {:g}", alpha_mode_name(m.alpha_mode), m.opacity);
        if (!m.opacity_texture.empty()) cut += " x " + file(m.opacity_texture);
        if (m.alpha_mode == AlphaMode::Mask) cut += fmt::format(", cutoff {:g}", m.alpha_cutoff);
        parts.push_back(cut);
    }
    std::string line;
    for (const std::string& p : parts) line += (line.empty() ? "" : "; ") + p;
    if (!m.unread.empty()) {
        line += "; not read:";
        for (size_t i = 0; i < m.unread.size(); ++i) line += (i ? ", " : " ") + m.unread[i];
    }
    return line;
}

}  // namespace

int run_info(const InfoArgs& a) {
    const Scene scene = load_scene(a.scene, {}, load_options_from_environment());
    std::printf("%s: %zu objects, %zu materials, %zu lights\n", a.scene.c_str(), scene.objects.size(), scene.materials.size(),
                scene.lights.size());
    for (const Material& m : scene.materials) std::printf("material %s: %s\n", m.name.c_str(), described(m).c_str());
    for (const std::string& line : scene.unread) std::printf("%s\n", line.c_str());
    return 0;
}

int run_bake_ao(const BakeAoArgs& a) {
    check_input_file(a.scene);
    check_output_file(a.output, {a.scene});
    if (!a.output.ends_with(".exr")) throw InputError("command line", "-o " + a.output, "the occlusion map is an OpenEXR file (.exr)");
    // Checked before any work: the distance as given, the map's memory, the file it replaces.
    if (a.distance && !(*a.distance > 0 && *a.distance <= kMaxCoordinate))
        throw InputError("command line", fmt::format("--distance {:g}", *a.distance),
                         fmt::format("the occlusion distance must be a number in (0, {:g}]", kMaxCoordinate));
    const double texels = static_cast<double>(a.resolution) * a.resolution;
    check_memory(texels * 3 * sizeof(float), "command line", fmt::format("--res {}", a.resolution), "the occlusion map");
    Scene scene = load_scene(a.scene, {}, load_options_from_environment());
    check_output_file(a.output, scene.input_paths(), scene.input_folders);
    const auto it = std::find_if(scene.objects.begin(), scene.objects.end(), [&](const Object& o) { return o.name == a.object; });
    const auto id = static_cast<uint32_t>(it - scene.objects.begin());
    if (it == scene.objects.end()) {
        std::vector<std::string> names;
        for (const Object& o : scene.objects) names.push_back(o.name);
        const std::string hint = closest_match(a.object, names);
        throw InputError("command line", "--object " + a.object,
                         "no such object" + (hint.empty() ? std::string() : " (did you mean \"" + hint + "\"?)"));
    }
    AoBakeSettings bs;
    bs.resolution = a.resolution;
    bs.rays = a.rays;
    // By default only occluders within a few displacement heights: the cache sees the rest.
    bs.distance = a.distance ? static_cast<float>(*a.distance) : 4 * scene.objects[id].displacement_bound;
    if (!(bs.distance > 0))
        throw InputError("command line", "--distance", "object " + a.object + " is not displaced: give the occlusion distance");
    // The BVHs and ray offset a still of the scene would build (its plan says how).
    SceneAccel accel(scene, plan_frame(scene, FrameState{}, RenderRequest{}).find<AccelStep>()->lighting);
    Stats stats;
    const std::unique_ptr<ProgressSink> progress = make_progress(false);
    const std::vector<float> ao = bake_ao(scene, accel, id, bs, stats, progress.get());
    write_atomically(a.output, [&](const std::string& tmp) {
        auto out = OIIO::ImageOutput::create("openexr");
        OIIO::ImageSpec spec(bs.resolution, bs.resolution, 1, OIIO::TypeDesc::HALF);
        spec.channelnames = {"Y"};
        spec.attribute("compression", "zip");
        spec.attribute("bounce:ao_distance", bs.distance);
        spec.attribute("bounce:ao_rays", bs.rays);
        if (!out) throw InputError(a.output, "", "cannot write: " + OIIO::geterror());
        if (!out->open(tmp, spec) || !out->write_image(OIIO::TypeDesc::FLOAT, ao.data()) || !out->close())
            throw InputError(a.output, "", "cannot write: " + out->geterror());
    });
    std::fprintf(stderr, "wrote %s (%dx%d, %d rays per texel, distance %g)\n", a.output.c_str(), bs.resolution, bs.resolution, bs.rays,
                 static_cast<double>(bs.distance));
    return 0;
}

/// `bounce compare --sequence`: per-frame error, flicker and popping (sequence_compare.h).
int run_compare_sequence(const CompareArgs& a) {
    if (a.frames.empty()) throw InputError("command line", "--sequence", "give the frames: --frames FIRST-LAST");
    const auto [first, last] = parse_frame_range(a.frames, "--frames " + a.frames);
    for (const std::string& p : {a.test, a.reference})
        if (p.find('#') == std::string::npos) throw InputError("command line", p, "a sequence is a #### frame pattern");
    const std::string layer = a.layer.empty() ? "indirect" : a.layer;
    const auto name = [&](int t) { return expand_frame_pattern(a.test, t); };
    const auto test = [&](int t) { return read_exr(name(t)); };
    const auto ref = [&](int t) { return read_exr(expand_frame_pattern(a.reference, t)); };
    if (!a.strip.empty()) {
        if (!a.strip.ends_with(".png")) throw InputError("command line", "--strip " + a.strip, "the strip is a PNG file (.png)");
        std::vector<std::string> inputs;  // every frame read: the strip must not overwrite one
        for (int t = first; t <= last; ++t) inputs.push_back(name(t)), inputs.push_back(expand_frame_pattern(a.reference, t));
        check_output_file(a.strip, inputs);
    }
    const SequenceError e = compare_sequences(test, ref, first, last, layer, name);
    if (!a.strip.empty()) {
        int w = 0, h = 0;
        const std::vector<uint8_t> rgb = sequence_strip(test, first, last, layer, 6, w, h);
        write_png_rgb8(a.strip, w, h, rgb);
    }
    nlohmann::json j = {{"layer", layer},       {"frames", e.frames},  {"rel_rmse", e.rel_rmse}, {"mean_rel_rmse", e.mean_rel_rmse},
                        {"flicker", e.flicker}, {"popping", e.popping}};
    if (a.json) {
        std::printf("%s\n", j.dump(2).c_str());
        return 0;
    }
    std::printf("%-8s %10s\n", "frame", "rel_rmse");
    for (size_t i = 0; i < e.frames.size(); ++i) std::printf("%-8d %9.4f%%\n", e.frames[i], 100 * e.rel_rmse[i]);
    std::printf("mean per-frame error %.4f%%, flicker %.4f%%, popping (99.9th percentile) %.4f%%\n", 100 * e.mean_rel_rmse, 100 * e.flicker,
                100 * e.popping);
    return 0;
}

int run_compare(const CompareArgs& a) {
    if (a.sequence) return run_compare_sequence(a);
    std::string diff = a.diff;
    if (diff.empty()) {
        std::filesystem::path p = a.test;
        diff = (p.parent_path() / (p.stem().string() + ".diff.png")).string();
    } else if (!diff.ends_with(".png")) {
        throw InputError("command line", "--diff " + diff, "the difference image is a PNG file (.png)");
    }
    check_output_file(diff, {a.test, a.reference});  // the default name too: it may be the reference's
    Image test = read_exr(a.test), ref = read_exr(a.reference);
    std::vector<LayerError> errors = compare_images(test, ref, a.layer, a.test, a.reference);
    std::string diff_layer = a.layer.empty() ? (ref.find("indirect") ? "indirect" : "beauty") : a.layer;
    double range = 0.1;
    for (const auto& e : errors)
        if (e.layer == diff_layer) range = std::max(1e-12, 0.1 * e.mean_ref);
    if (ref.find(diff_layer) && ref.find(diff_layer)->channels.size() >= 1)
        write_png_rgb8(diff, ref.width, ref.height, error_false_colour(test, ref, diff_layer, range));
    if (a.json) {
        std::printf("%s\n", layer_errors_json(errors).dump(2).c_str());
    } else {
        std::printf("%-18s %12s %10s %12s %12s %12s %12s\n", "layer", "rmse", "rel_rmse", "relmse", "mean_abs", "max_abs", "mean_ref");
        for (const auto& e : errors)
            std::printf("%-18s %12.6g %10s %12.6g %12.6g %12.6g %12.6g\n", e.layer.c_str(), e.rmse,
                        std::isnan(e.rel_rmse) ? "n/a" : fmt::format("{:.4f}%", 100 * e.rel_rmse).c_str(), e.relmse, e.mean_abs, e.max_abs,
                        e.mean_ref);
        std::printf("difference image (%s, full scale = 10%% of the reference mean): %s\n", diff_layer.c_str(), diff.c_str());
    }
    return 0;
}

int run_cache_info(const CacheArgs& a) {
    const std::string& path = a.inputs.at(0);
    if (path.find('#') != std::string::npos) {
        auto files = sequence_files(path);
        if (files.empty()) throw InputError(path, "", "no files match this frame pattern");
        nlohmann::json seq = nlohmann::json::array();
        if (!a.json) std::printf("%-8s %10s %10s %10s\n", "frame", "records", "reused", "new");
        for (const auto& [frame, file] : files) {
            CacheFile f = read_cache_file(file);
            size_t fresh = 0;
            for (const Record& r : f.records) fresh += r.frame == frame;
            seq.push_back(
                {{"frame", frame}, {"file", file}, {"records", f.records.size()}, {"reused", f.records.size() - fresh}, {"new", fresh}});
            if (!a.json) std::printf("%-8d %10zu %10zu %10zu\n", frame, f.records.size(), f.records.size() - fresh, fresh);
        }
        if (a.json) std::printf("%s\n", seq.dump(2).c_str());
        return 0;
    }
    CacheFile f = read_cache_file(path);
    nlohmann::json info = cache_info(f, file_size(path));
    std::printf("%s", a.json ? (info.dump(2) + "\n").c_str() : cache_info_text(info, path).c_str());
    return 0;
}

namespace {
ToolCall cli_call(const CacheArgs& a, const char* command) { return {"command line", "-o " + a.output, command}; }
}  // namespace

int run_cache_merge(const CacheArgs& a) {
    const CacheFile out = merge_cache_files(cli_call(a, "cache merge"), a.inputs, a.output, a.force);
    std::fprintf(stderr, "%s: %zu records, %zu fragment records\n", a.output.c_str(), out.records.size(), out.fragment_records.size());
    return 0;
}

int run_cache_filter(const CacheArgs& a) {
    RecordFilter filter;
    if (!a.box.empty()) {
        auto v = parse_floats(a.box, 6, "--box");
        filter.has_box = true;
        filter.box_lo = {std::min(v[0], v[3]), std::min(v[1], v[4]), std::min(v[2], v[5])};
        filter.box_hi = {std::max(v[0], v[3]), std::max(v[1], v[4]), std::max(v[2], v[5])};
    }
    if (!a.sphere.empty()) {
        auto v = parse_floats(a.sphere, 4, "--sphere");
        filter.has_sphere = true;
        filter.center = {v[0], v[1], v[2]};
        filter.radius = v[3];
        if (!(filter.radius > 0)) throw InputError("command line", "--sphere " + a.sphere, "the radius must be > 0");
    }
    for (const auto& w : a.where) filter.where.push_back(WhereTerm::parse(w));
    const auto [in, out] = filter_cache_file(cli_call(a, "cache filter"), a.inputs.at(0), a.output, filter, a.remove);
    std::fprintf(stderr, "%s: kept %zu of %zu records, %zu of %zu fragment records\n", a.output.c_str(), out.records.size(),
                 in.records.size(), out.fragment_records.size(), in.fragment_records.size());
    return 0;
}

int run_cache_export(const CacheArgs& a) {
    check_tool_output(cli_call(a, "cache export"), a.output, ".ply", "the exported point cloud", a.inputs);
    CacheFile f = read_cache_file(a.inputs.at(0));
    export_ply(f, a.output);
    std::fprintf(stderr, "%s: %zu points\n", a.output.c_str(), f.records.size());
    return 0;
}

}  // namespace bounce
