// The `bounce` command line: parses options and calls the library. Nothing else lives here.
#include <unistd.h>

#include <CLI/CLI.hpp>
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <sstream>

#include <OpenImageIO/imageio.h>
#include <fmt/format.h>

#include "bounce/cache/cache_file.h"
#include "bounce/cache/cache_tools.h"
#include "bounce/core/atomic_file.h"
#include "bounce/core/error.h"
#include "bounce/core/image.h"
#include "bounce/core/image_compare.h"
#include "bounce/core/files.h"
#include "bounce/gather/ao_bake.h"
#include "bounce/render/frame.h"
#include "bounce/render/render.h"
#include "bounce/scene/params_cli.h"
#include "bounce/scene/scene_load.h"
#include "light.h"

namespace {

using namespace bounce;

struct RenderArgs {
    FrameFiles files;
    std::vector<std::string> sets;
    std::vector<Override> flags;  ///< from the parameter table's flags
    bool regather = false, force = false, reuse_any = false;
    std::string show = "beauty", frames;
    int frame = 0;
    bool stats = false, quiet = false;
};

Scene load_render_scene(const RenderArgs& a) {
    std::vector<Override> o(a.sets.begin(), a.sets.end());
    o.insert(o.end(), a.flags.begin(), a.flags.end());  // dedicated flags win over --set
    Scene scene = load_scene(a.files.scene, o);
    const bool cache = scene.render.indirect.gi == GiMode::Cache;
    if (!cache && !a.files.cache_out.empty())
        throw InputError("command line", "--cache-out " + a.files.cache_out, "only a --gi cache render makes a cache");
    if (!cache && !a.files.cache_in.empty() && a.show != "records")
        throw InputError("command line", "--cache-in " + a.files.cache_in,
                         "only a --gi cache render (or --show records) uses a cache");
    if (!a.files.base.empty() && !scene.render.visibility.has_crop())
        throw InputError("command line", "--base " + a.files.base, "--base fills the pixels outside --crop; give a crop");
    if (a.reuse_any && a.regather)
        throw InputError("command line", "--cache-reuse-any", "cannot be combined with --regather");
    return scene;
}

/// Progress on stderr: a bar on a terminal, log lines otherwise, nothing with -q.
std::unique_ptr<ProgressSink> make_progress(bool quiet) {
    if (quiet) return make_null_progress();
    return isatty(STDERR_FILENO) ? make_terminal_progress() : make_log_progress();
}

int render_frame(const RenderArgs& a, const FrameFiles& files, int frame) {
    Scene scene = load_render_scene(a);
    files.check();
    std::unique_ptr<ProgressSink> sink = make_progress(a.quiet);
    Stats stats;
    RenderRequest request;
    request.deep_in = files.deep_in;
    request.deep_out = files.deep_out;
    request.cache_in = files.cache_in;
    request.regather = a.regather;
    request.force = a.force;
    request.cache_reuse = a.reuse_any ? CacheReuse::Any : CacheReuse::Strict;
    request.frame = frame;
    if (scene.render.parallel.preview)
        request.preview = [&](const Image& img) {
            write_exr(files.output, img);
            write_png(files.png(), img, "beauty");
        };
    const FrameState none;  // a still, or a frame of a sequence that starts from cache files
    const FramePlan plan = plan_frame(scene, none, request);
    RenderResult r = run_frame(scene, plan, none, request, stats, sink.get());
    {
        PhaseTimer t(stats, "write images");
        write_frame_outputs(r, files, a.show);
    }
    if (!r.cache_differences.empty() && !a.quiet)
        std::fprintf(stderr, "bounce: %s: records reused although gathered with other settings (--cache-reuse-any)\n",
                     files.cache_in.c_str());
    if (a.stats) {
        std::printf("%s", stats.to_text().c_str());
        if (scene.render.indirect.any()) std::printf("\n%s", seed_table(stats.to_json()).c_str());
    }
    if (!files.stats_json.empty()) {
        std::string text = stats.to_json().dump(2) + "\n";
        write_atomically(files.stats_json, [&](const std::string& tmp) {
            std::ofstream out(tmp);
            out << text;
            if (!out) throw InputError(files.stats_json, "", "cannot write stats file");
        });
    }
    if (!a.quiet) std::fprintf(stderr, "wrote %s\n", files.output.c_str());
    return 0;
}

int run_render(const RenderArgs& a) {
    if (a.frames.empty()) return render_frame(a, expand_frame(a.files, a.frame), a.frame);
    auto [first, last] = parse_frame_range(a.frames, "--frames " + a.frames);
    if (a.files.cache_out.find('#') == std::string::npos || a.files.output.find('#') == std::string::npos)
        throw InputError("command line", "--frames", "-o and --cache-out need a #### frame pattern for a sequence");
    for (int f = first; f <= last; ++f)
        if (int rc = render_frame(a, sequence_frame(a.files, first, f), f)) return rc;
    return 0;
}

int run_params(bool json, bool markdown) {
    if (json) std::printf("%s\n", params_listing().dump(2).c_str());
    else if (markdown) std::printf("%s", params_markdown().c_str());
    else
        for (const Param& p : scene_params())
            std::printf("%-32s %-10s %-24s %s\n", p.key.c_str(), p.stage.c_str(), p.default_value().dump().c_str(), p.doc.c_str());
    return 0;
}

struct BakeAoArgs {
    std::string scene, object, output;
    int resolution = 1024, rays = 256;
    float distance = 0;
};

/// `bounce bake-ao`: an object's occlusion by its own fine detail, in its uv space (EXR, one
/// channel), for a material's ao_texture.
int run_bake_ao(const BakeAoArgs& a) {
    check_input_file(a.scene);
    check_output_file(a.output, {a.scene});
    if (!a.output.ends_with(".exr")) throw InputError("command line", "-o " + a.output, "the occlusion map is an OpenEXR file (.exr)");
    Scene scene = load_scene(a.scene);
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
    bs.distance = a.distance > 0 ? a.distance : 4 * scene.objects[id].displacement_bound;
    if (!(bs.distance > 0))
        throw InputError("command line", "--distance", "object " + a.object + " is not displaced: give the occlusion distance");
    SceneAccel accel(scene);
    Stats stats;
    const std::unique_ptr<ProgressSink> progress = make_progress(false);
    const std::vector<float> ao = bake_ao(scene, accel, id, bs, stats, progress.get());
    write_atomically(a.output, [&](const std::string& tmp) {
        auto out = OIIO::ImageOutput::create(tmp);
        OIIO::ImageSpec spec(bs.resolution, bs.resolution, 1, OIIO::TypeDesc::HALF);
        spec.channelnames = {"Y"};
        spec.attribute("compression", "zip");
        spec.attribute("bounce:ao_distance", bs.distance);
        spec.attribute("bounce:ao_rays", bs.rays);
        if (!out || !out->open(tmp, spec) || !out->write_image(OIIO::TypeDesc::FLOAT, ao.data()) || !out->close())
            throw std::runtime_error("cannot write " + a.output + ": " + OIIO::geterror());
    });
    std::fprintf(stderr, "wrote %s (%dx%d, %d rays per texel, distance %g)\n", a.output.c_str(), bs.resolution, bs.resolution, bs.rays,
                 static_cast<double>(bs.distance));
    return 0;
}

struct CompareArgs {
    std::string test, reference, layer, diff;
    bool json = false;
};

int run_compare(const CompareArgs& a) {
    if (!a.diff.empty()) check_output_file(a.diff, {a.test, a.reference});
    Image test = read_exr(a.test), ref = read_exr(a.reference);
    std::vector<LayerError> errors = compare_images(test, ref, a.layer, a.test);
    std::string diff_layer = a.layer.empty() ? (ref.find("indirect") ? "indirect" : "beauty") : a.layer;
    std::string diff = a.diff;
    if (diff.empty()) {
        std::filesystem::path p = a.test;
        diff = (p.parent_path() / (p.stem().string() + ".diff.png")).string();
    }
    double range = 0.1;
    for (const auto& e : errors)
        if (e.layer == diff_layer) range = std::max(1e-12, 0.1 * e.mean_ref);
    if (ref.find(diff_layer) && ref.find(diff_layer)->channels.size() >= 1)
        write_png_rgb8(diff, ref.width, ref.height, error_false_colour(test, ref, diff_layer, range));
    if (a.json) {
        nlohmann::json j = nlohmann::json::object();
        for (const auto& e : errors)
            j[e.layer] = {{"rmse", e.rmse}, {"rel_rmse", std::isnan(e.rel_rmse) ? nlohmann::json() : nlohmann::json(e.rel_rmse)}, {"relmse", e.relmse},
                          {"mean_abs", e.mean_abs}, {"max_abs", e.max_abs}, {"mean_ref", e.mean_ref}};
        std::printf("%s\n", j.dump(2).c_str());
    } else {
        std::printf("%-18s %12s %10s %12s %12s %12s %12s\n", "layer", "rmse", "rel_rmse", "relmse", "mean_abs", "max_abs", "mean_ref");
        for (const auto& e : errors)
            std::printf("%-18s %12.6g %10s %12.6g %12.6g %12.6g %12.6g\n", e.layer.c_str(), e.rmse,
                        std::isnan(e.rel_rmse) ? "n/a" : fmt::format("{:.4f}%", 100 * e.rel_rmse).c_str(), e.relmse, e.mean_abs,
                        e.max_abs, e.mean_ref);
        std::printf("difference image (%s, full scale = 10%% of the reference mean): %s\n", diff_layer.c_str(), diff.c_str());
    }
    return 0;
}

struct CacheArgs {
    std::vector<std::string> inputs;
    std::string output, box, sphere;
    std::vector<std::string> where;
    bool json = false, remove = false, force = false;
};

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
            seq.push_back({{"frame", frame}, {"file", file}, {"records", f.records.size()},
                           {"reused", f.records.size() - fresh}, {"new", fresh}});
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

int run_cache_merge(const CacheArgs& a) {
    check_output_file(a.output, a.inputs);
    if (a.inputs.size() < 2) throw InputError("command line", "cache merge", "give at least two caches to merge");
    CacheFile out = read_cache_file(a.inputs[0]);
    for (size_t i = 1; i < a.inputs.size(); ++i) out = merge_caches(out, read_cache_file(a.inputs[i]), a.inputs[0], a.inputs[i], a.force);
    write_cache_file(a.output, out);
    std::fprintf(stderr, "%s: %zu records, %zu fragment records\n", a.output.c_str(), out.records.size(), out.fragment_records.size());
    return 0;
}

int run_cache_filter(const CacheArgs& a) {
    check_output_file(a.output, a.inputs);
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
    for (const auto& w : a.where) check_where_term(w);
    filter.where = a.where;
    if (!filter.has_box && !filter.has_sphere && filter.where.empty())
        throw InputError("command line", "cache filter", "give --box, --sphere or --where");
    CacheFile in = read_cache_file(a.inputs.at(0));
    CacheFile out = filter_cache(in, filter, a.remove);
    write_cache_file(a.output, out);
    std::fprintf(stderr, "%s: kept %zu of %zu records, %zu of %zu fragment records\n", a.output.c_str(), out.records.size(),
                 in.records.size(), out.fragment_records.size(), in.fragment_records.size());
    return 0;
}

int run_cache_export(const CacheArgs& a) {
    check_output_file(a.output, a.inputs);
    CacheFile f = read_cache_file(a.inputs.at(0));
    export_ply(f, a.output);
    std::fprintf(stderr, "%s: %zu points\n", a.output.c_str(), f.records.size());
    return 0;
}

}  // namespace

int main(int argc, char** argv) {
    CLI::App app{"bounce: one-bounce diffuse global illumination and ambient occlusion"};
    app.require_subcommand(1);
    app.set_version_flag("--version", std::string("bounce ") + BOUNCE_VERSION + " (" + BOUNCE_GIT_REV + ")");

    RenderArgs ra;
    CLI::App* render = app.add_subcommand("render", "render a scene to a multi-layer EXR and a PNG");
    render->add_option("scene", ra.files.scene, "scene file (.json, or a glTF/OBJ/PLY with a camera)")->required();
    render->add_option("-o,--output", ra.files.output, "output EXR (a PNG is written beside it; #### = frame)")->required();
    add_param_flags(*render, scene_params(), ra.flags);
    render->add_option("--cache-in", ra.files.cache_in, "start from this irradiance cache file (#### = frame)");
    render->add_option("--cache-out", ra.files.cache_out, "write the irradiance cache (#### = frame)");
    render->add_flag("--regather", ra.regather, "flush the cache before gathering (with --crop: only the crop's records)");
    render->add_flag("--cache-reuse-any", ra.reuse_any,
                     "keep a --cache-in gathered with other settings, gather only where it misses (the stats say so)");
    render->add_flag("--force", ra.force, "use a cache made for another scene or camera");
    render->add_option("--base", ra.files.base, "with --crop: an earlier full-frame EXR to paste the crop over");
    render->add_option("--frame", ra.frame, "frame number (expands #### in file names, stamps new records)");
    render->add_option("--frames", ra.frames, "render frames FIRST-LAST, each reusing the previous frame's cache");
    render->add_option("--show", ra.show, "layer written to the PNG: beauty (default), records, indirect, ao ...");
    render->add_option("--set", ra.sets, "override any scene value: key.path=value")->take_all();
    render->add_option("--deep-out", ra.files.deep_out, "write the deep buffer (OpenEXR deep)");
    render->add_option("--deep-in", ra.files.deep_in, "shade from a deep buffer instead of tracing visibility");
    render->add_flag("--stats", ra.stats, "print statistics");
    render->add_option("--stats-json", ra.files.stats_json, "write statistics as JSON");
    render->add_flag("-q,--quiet", ra.quiet, "no progress output");

    bool params_json = false, params_markdown_flag = false;
    CLI::App* params = app.add_subcommand("params", "list every scene parameter: key, stage, default, range, unit, doc");
    params->add_flag("--json", params_json, "print JSON (the lighting tool's spreadsheet)");
    params->add_flag("--markdown", params_markdown_flag, "print the Markdown table of docs/scene-format.md");

    BakeAoArgs ba;
    CLI::App* bake = app.add_subcommand("bake-ao", "bake an object's occlusion by its fine (displaced) detail into its uv space");
    bake->add_option("scene", ba.scene, "scene file")->required();
    bake->add_option("--object", ba.object, "the object's name")->required();
    bake->add_option("-o,--output", ba.output, "occlusion map (EXR) for a material's ao_texture")->required();
    bake->add_option("--res", ba.resolution, "texels per side")->check(CLI::Range(1, 16384));
    bake->add_option("--rays", ba.rays, "rays per texel")->check(CLI::Range(1, 1 << 20));
    bake->add_option("--distance", ba.distance, "occluders beyond this do not count; default 4x the displacement bound")
        ->check(CLI::Range(0.0, 1e18));

    LightArgs la;
    CLI::App* light = app.add_subcommand("light", "the lighting tool: a local web page to edit, re-gather and re-shade");
    light->add_option("scene", la.scene, "scene file")->required();
    light->add_option("--port", la.port, "port (0 = any free one)")->check(CLI::Range(0, 65535));
    light->add_option("--bind", la.bind, "loopback address to listen on (127.0.0.1, ::1, localhost)");
    light->add_option("--out", la.out_dir, "folder for the session's deep file, cache and saved files");
    light->add_option("--deep-in", la.deep_in, "start from this deep file");
    light->add_option("--cache-in", la.cache_in, "start from this irradiance cache");
    light->add_option("--threads", la.threads, "render threads (0 = all)")->check(CLI::Range(0, 4096));
    light->add_option("--set", la.sets, "start with this edit: key.path=value (render.gi defaults to cache)")->take_all();

    CompareArgs ca;
    CLI::App* compare = app.add_subcommand("compare", "error of a render against a reference, per layer");
    compare->add_option("test", ca.test, "the render to judge (EXR)")->required();
    compare->add_option("reference", ca.reference, "the reference (EXR)")->required();
    compare->add_option("--layer", ca.layer, "only this layer (beauty, direct, indirect, ao, ..., or beauty_ref_direct: the beauty with the reference's direct light)");
    compare->add_option("--diff", ca.diff, "false-colour difference PNG (default: TEST.diff.png)");
    compare->add_flag("--json", ca.json, "print JSON");

    CacheArgs ka;
    CLI::App* cache = app.add_subcommand("cache", "inspect, merge, filter and export irradiance cache files");
    cache->require_subcommand(1);
    CLI::App* cinfo = cache->add_subcommand("info", "counts, bounds, parameters, radius histogram, memory (FILE or a #### sequence)");
    cinfo->add_option("file", ka.inputs, "cache file, or a frame pattern like cache.####.bic")->required()->expected(1);
    cinfo->add_flag("--json", ka.json, "print JSON");
    CLI::App* cmerge = cache->add_subcommand("merge", "merge caches without duplicates");
    cmerge->add_option("inputs", ka.inputs, "caches to merge")->required();
    cmerge->add_option("-o,--output", ka.output, "merged cache")->required();
    cmerge->add_flag("--force", ka.force, "merge caches of different scenes or cameras");
    CLI::App* cfilter = cache->add_subcommand("filter", "keep (or --remove) records by region or value");
    cfilter->add_option("input", ka.inputs, "cache file")->required()->expected(1);
    cfilter->add_option("-o,--output", ka.output, "filtered cache")->required();
    cfilter->add_option("--box", ka.box, "x0,y0,z0,x1,y1,z1: records inside the box");
    cfilter->add_option("--sphere", ka.sphere, "cx,cy,cz,r: records inside the sphere");
    cfilter->add_option("--where", ka.where, "FIELD OP NUMBER, e.g. \"pixels<2\" (repeatable, all must hold)");
    cfilter->add_flag("--remove", ka.remove, "remove the matching records instead of keeping them");
    CLI::App* cexport = cache->add_subcommand("export", "write a PLY point cloud (MeshLab, CloudCompare, Blender)");
    cexport->add_option("input", ka.inputs, "cache file")->required()->expected(1);
    cexport->add_option("-o,--output", ka.output, "PLY file")->required();

    if (argc > 1 && argv[1][0] != '-') {  // CLI11 would only say "A subcommand is required"
        std::vector<std::string> names;
        for (const CLI::App* sub : app.get_subcommands({})) names.push_back(sub->get_name());
        if (std::find(names.begin(), names.end(), argv[1]) == names.end()) {
            std::string hint = closest_match(argv[1], names);
            std::fprintf(stderr, "bounce: command line: %s: error: unknown command%s (valid: %s)\n", argv[1],
                         hint.empty() ? "" : (" (did you mean \"" + hint + "\"?)").c_str(), fmt::format("{}", fmt::join(names, ", ")).c_str());
            return 2;
        }
    }
    try {
        app.parse(argc, argv);
    } catch (const CLI::CallForHelp& e) {
        return app.exit(e);
    } catch (const CLI::CallForAllHelp& e) {
        return app.exit(e);
    } catch (const CLI::CallForVersion& e) {
        return app.exit(e);
    } catch (const CLI::ParseError& e) {
        std::fprintf(stderr, "bounce: command line: error: %s (see bounce --help)\n", e.what());
        return 2;
    }
    try {
        if (*render) return run_render(ra);
        if (*params) return run_params(params_json, params_markdown_flag);
        if (*compare) return run_compare(ca);
        if (*bake) return run_bake_ao(ba);
        if (*light) return run_light(la);
        if (*cinfo) return run_cache_info(ka);
        if (*cmerge) return run_cache_merge(ka);
        if (*cfilter) return run_cache_filter(ka);
        if (*cexport) return run_cache_export(ka);
    } catch (const InputError& e) {
        std::fprintf(stderr, "bounce: %s\n", e.what());
        return 2;
    } catch (const Cancelled&) {
        std::fprintf(stderr, "bounce: cancelled\n");
        return 130;
    } catch (const std::exception& e) {
        std::fprintf(stderr, "bounce: internal error: %s\n", e.what());
        return 1;
    }
    return 0;
}
