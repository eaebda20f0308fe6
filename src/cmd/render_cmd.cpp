#include "render_cmd.h"

#include <unistd.h>

#include <cstdio>

#include "bounce/core/error.h"
#include "bounce/core/image.h"
#include "bounce/render/render.h"
#include "bounce/scene/params.h"
#include "bounce/scene/params_cli.h"
#include "bounce/scene/scene_load.h"

namespace bounce {

namespace {

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

RenderRequest request_of(const RenderArgs& a, const FrameFiles& files, int frame) {
    RenderRequest request;
    request.deep_in = files.deep_in;
    request.deep_out = files.deep_out;
    request.cache_in = files.cache_in;
    request.regather = a.regather;
    request.force = a.force;
    request.cache_reuse = a.reuse_any ? CacheReuse::Any : CacheReuse::Strict;
    request.frame = frame;
    return request;
}

void print_stats(const Stats& stats, const Scene& scene) {
    std::printf("%s", stats.to_text().c_str());
    if (scene.render.indirect.any()) std::printf("\n%s", seed_table(stats.to_json()).c_str());
}

int render_frame(const RenderArgs& a, const FrameFiles& files, int frame) {
    Scene scene = load_render_scene(a);
    // Everything that can be refused is refused before any work: outputs against every file
    // the scene reads, the layer --show names, the base a crop is pasted over.
    files.check(scene);
    check_show_layer(a.show, scene, !files.cache_in.empty());
    if (!files.base.empty()) check_base(files.base, scene);
    std::unique_ptr<ProgressSink> sink = make_progress(a.quiet);
    Stats stats;
    RenderRequest request = request_of(a, files, frame);
    if (scene.render.parallel.preview)
        request.preview = [&](const Image& img) {
            write_exr(files.output, img);
            write_png(files.png(), img, "beauty");
        };
    const FrameState none;  // a still, or a frame of a sequence that starts from cache files
    const FramePlan plan = plan_frame(scene, none, request);
    RenderResult r = run_frame(scene, plan, none, request, stats, sink.get());
    write_frame_outputs(r, files, a.show, stats);
    if (!r.cache_differences.empty() && !a.quiet)
        std::fprintf(stderr, "bounce: %s: records reused although gathered with other settings (--cache-reuse-any)\n",
                     files.cache_in.c_str());
    if (a.stats) print_stats(stats, scene);
    if (!a.quiet) std::fprintf(stderr, "wrote %s\n", files.output.c_str());
    return 0;
}

}  // namespace

std::unique_ptr<ProgressSink> make_progress(bool quiet) {
    if (quiet) return make_null_progress();
    return isatty(STDERR_FILENO) ? make_terminal_progress() : make_log_progress();
}

int run_render(const RenderArgs& a) {
    if (a.frames.empty()) return render_frame(a, expand_frame(a.files, a.frame), a.frame);
    auto [first, last] = parse_frame_range(a.frames, "--frames " + a.frames);
    for (auto [flag, pattern] : {std::pair{"-o", a.files.output}, std::pair{"--cache-out", a.files.cache_out}})
        if (pattern.find('#') == std::string::npos)
            throw InputError("command line", std::string(flag) + " " + pattern,
                             pattern.empty() ? "a sequence needs it, with a #### frame pattern"
                                             : "a sequence needs a #### frame pattern in it");
    for (int f = first; f <= last; ++f)
        if (int rc = render_frame(a, sequence_frame(a.files, first, f), f)) return rc;
    return 0;
}

void add_render_options(CLI::App& render, RenderArgs& ra) {
    render.add_option("scene", ra.files.scene, "scene file (.json, or a glTF/OBJ/PLY with a camera)")->required();
    render.add_option("-o,--output", ra.files.output, "output EXR (a PNG is written beside it; #### = frame)")->required();
    add_param_flags(render, scene_params(), ra.flags);
    render.add_option("--cache-in", ra.files.cache_in, "start from this irradiance cache file (#### = frame)");
    render.add_option("--cache-out", ra.files.cache_out, "write the irradiance cache (#### = frame)");
    render.add_flag("--regather", ra.regather, "flush the cache before gathering (with --crop: only the crop's records)");
    render.add_flag("--cache-reuse-any", ra.reuse_any,
                    "keep a --cache-in gathered with other settings, gather only where it misses (the stats say so)");
    render.add_flag("--force", ra.force, "use a cache made for another scene or camera");
    render.add_option("--base", ra.files.base, "with --crop: an earlier full-frame EXR to paste the crop over");
    render.add_option("--frame", ra.frame, "frame number (expands #### in file names, stamps new records)");
    render.add_option("--frames", ra.frames, "render frames FIRST-LAST, each reusing the previous frame's cache");
    render.add_option("--show", ra.show, "layer written to the PNG: beauty (default), records, indirect, ao ...");
    render.add_option("--set", ra.sets, "override any scene value: key.path=value")->take_all();
    render.add_option("--deep-out", ra.files.deep_out, "write the deep buffer (OpenEXR deep)");
    render.add_option("--deep-in", ra.files.deep_in, "shade from a deep buffer instead of tracing visibility");
    render.add_flag("--stats", ra.stats, "print statistics");
    render.add_option("--stats-json", ra.files.stats_json, "write statistics as JSON");
    render.add_flag("-q,--quiet", ra.quiet, "no progress output");
}

}  // namespace bounce
