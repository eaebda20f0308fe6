#include "render_cmd.h"

#include <fmt/format.h>
#include <unistd.h>

#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <map>
#include <memory>
#include <regex>

#include "frontend/environment.h"
#include "bounce/core/error.h"
#include "bounce/core/image.h"
#include "bounce/core/image_input.h"
#include "bounce/deep/deep_buffer.h"
#include "bounce/scene/json_reader.h"
#include "bounce/dist/mpi.h"
#include "bounce/cache/cache_file.h"
#include "bounce/render/render.h"
#include "bounce/render/shot.h"
#include "bounce/config/params.h"
#include "bounce/scene/params_cli.h"
#include "bounce/scene/scene_load.h"
#include "bounce/core/version.h"

namespace bounce {

namespace {

Scene load_render_scene(const RenderArgs& a, std::optional<double> frame) {
    std::vector<Override> o(a.sets.begin(), a.sets.end());
    o.insert(o.end(), a.flags.begin(), a.flags.end());  // dedicated flags win over --set
    LoadOptions options = load_options_from_environment();
    options.frame = frame;
    if (frame) options.frame_origin = a.frames.empty() ? fmt::format("--frame {:g}", *frame) : "--frames " + a.frames;
    Scene scene = load_scene(a.job.files.scene, o, options);
    check_job(a.job, scene, !a.frames.empty());
    return scene;
}

/// Rank 0 writes a frame's outputs and talks to the user; every rank renders.
bool writes(const Communicator* comm) { return !comm || comm->rank() == 0; }

/// Rank 0's answer to a question about files (are the outputs there?), so that every rank
/// takes the same branch whatever its view of a shared folder.
bool rank0_says(Communicator* comm, bool mine) {
    if (!comm || comm->size() == 1) return mine;
    return comm->allgather(mine ? "1" : "0").front() == "1";
}

/// Refuses a job whose ranks run another build, command line or scene (check_same_job).
void check_ranks(const RenderArgs& a, const Scene& scene) {
    if (!a.comm || a.comm->size() == 1) return;
    std::string command;
    for (const auto& o : a.sets) command += " --set " + o;
    const std::string identity =
        fmt::format("bounce {} ({}), {} {}{} (scene {:016x})", bounce_version(), bounce_revision(), a.job.files.scene, a.job.files.output,
                    command, scene.fingerprint({"objects", "materials", "lights", "camera", "render"}));
    check_same_job(*a.comm, identity);
}

void print_stats(const Stats& stats, const FramePlan& plan) {
    std::printf("%s", stats.to_text().c_str());
    if (plan.indirect() != IndirectFrom::None) std::printf("\n%s", seed_table(stats.to_json()).c_str());
}

/// Everything that can be refused is refused before any work: outputs against every file the
/// scene reads, the layer --show names, the base a crop is pasted over.
void check_frame(const RenderArgs& a, const FrameFiles& files, const Scene& scene, const FramePlan& plan) {
    check_job_frame(a.job, files, scene, plan);
    // Nothing dropped in silence: what the mesh files carry that is not read, once a run (a
    // sequence's frames read the same files), once the frame is sure to render.
    static bool noted = false;
    for (const std::string& line : noted ? std::vector<std::string>{} : scene.unread) std::fprintf(stderr, "bounce: %s\n", line.c_str());
    noted = true;
}

void report(const RenderArgs& a, const RenderResult& r, const FrameFiles& files, const Stats& stats) {
    if (!r.cache_differences.empty() && !a.quiet)
        std::fprintf(stderr, "bounce: %s: records reused although gathered with other settings (--cache-reuse-any)\n",
                     files.cache_in.c_str());
    if (r.cache_other_lighting && !a.quiet)
        std::fprintf(stderr,
                     "bounce: %s: lights or materials differ from the cache's: its bounce light is theirs (--regather gathers it anew)\n",
                     files.cache_in.c_str());
    if (a.stats) print_stats(stats, r.plan);
    if (!a.quiet) std::fprintf(stderr, "wrote %s\n", files.output.c_str());
}

int render_frame(const RenderArgs& a, const FrameFiles& files) {
    const Scene scene = load_render_scene(a, a.frame);
    check_ranks(a, scene);
    RenderRequest request = job_request(a.job, files, static_cast<int>(std::lround(scene.frame)));
    request.comm = a.comm;
    // The plan calls it where render.preview asks for one; a preview needs every band.
    if (!a.comm || a.comm->size() == 1)
        request.preview = [&](const Image& img) {
            write_exr(files.output, img);
            write_png(files.png(), img, "beauty", *files.display);
        };
    const FrameState none;  // a still, or a frame of a sequence that starts from cache files
    const FramePlan plan = plan_frame(scene, none, request);
    if (writes(a.comm)) check_frame(a, files, scene, plan);
    std::unique_ptr<ProgressSink> sink = make_progress(a.quiet || !writes(a.comm));
    Stats stats;
    add_load_phases(stats, scene);
    RenderResult r = run_frame(scene, plan, none, request, stats, sink.get());
    if (!writes(a.comm)) return 0;
    write_frame_outputs(r, files, a.job.show, stats);
    report(a, r, files, stats);
    return 0;
}

/// A range that runs past the end of the shot is refused before any frame renders (the first
/// frame's scene says where the shot ends; its start was checked as that frame loaded).
void check_range_in_shot(const RenderArgs& a, const Scene& scene, int last) {
    if (scene.shot.animated && !scene.shot.contains(last))
        throw InputError("command line", "--frames " + a.frames, scene.shot.outside(last));
}

/// Whether `read` reads `path` back whole (a file cut short, or overwritten by something else,
/// throws on the way).
template <typename Read>
bool reads_back(const std::string& path, Read&& read) {
    if (path.empty()) return true;
    if (!std::filesystem::is_regular_file(path)) return false;
    try {
        read(path);
        return true;
    } catch (const std::exception&) {
        return false;
    }
}

/// Every output of a frame is there and reads back whole: each is written by rename, but a
/// disk that filled or a copy cut short leaves a file that is there and is not the frame.
bool outputs_complete(const FrameFiles& f) {
    const auto image = [](const std::string& p) { (void)read_exr(p); };
    const auto png = [](const std::string& p) {
        std::string error;
        auto in = open_image(p, error);
        if (!in) throw std::runtime_error(error);
        std::vector<unsigned char> pixels(static_cast<size_t>(in->spec().image_bytes()));
        if (!in->read_image(0, 0, 0, -1, OIIO::TypeDesc::UINT8, pixels.data())) throw std::runtime_error(in->geterror());
    };
    const auto json = [](const std::string& p) {
        if (nlohmann::json::parse(read_text_file(p)).is_discarded()) throw std::runtime_error(p);
    };
    return reads_back(f.output, image) && reads_back(f.png(), png) &&
           reads_back(f.deep_out, [](const std::string& p) { (void)read_deep(p); }) &&
           reads_back(f.cache_out, [](const std::string& p) { (void)read_cache_file(p); }) && reads_back(f.stats_json, json);
}

/// Frames `first`..`last` of a shot that starts at `shot_first`, in order, each starting from
/// what the one before left (Shot), spread over `comm`'s ranks (null: this process). A frame
/// that fails stops the sequence there: the frames before it are written. `before_ok`: the
/// cache file of the frame before `first` may be started from (decided before any rank ran).
int render_sequence(const RenderArgs& a, int first, int last, int shot_first, Communicator* comm, bool before_ok) {
    Shot shot;
    std::unique_ptr<ProgressSink> sink = make_progress(a.quiet || !writes(comm));
    for (int f = first; f <= last; ++f) {
        const FrameFiles files = expand_frame(a.job.files, f);
        if (a.resume && rank0_says(comm, outputs_complete(files))) {
            shot.forget();
            if (!a.quiet && writes(comm)) std::fprintf(stderr, "frame %d: outputs complete, skipped\n", f);
            continue;
        }
        auto scene = std::make_shared<const Scene>(load_render_scene(a, f));
        if (f == first && comm) check_ranks(a, *scene);
        check_range_in_shot(a, *scene, last);
        if (writes(comm)) check_frame(a, files, *scene, plan_frame(*scene, {}, job_request(a.job, files, f)));
        // A resumed shot starts from the cache the frame before left, when there is one.
        const std::string before =
            f > shot_first && !a.job.files.cache_out.empty() ? expand_frame_pattern(a.job.files.cache_out, f - 1) : "";
        if (!shot.has_previous() && !before.empty() && (f > first || before_ok) &&
            rank0_says(comm, std::filesystem::is_regular_file(before)))
            shot.start_from(std::make_shared<const Scene>(load_render_scene(a, f - 1)), before);
        Stats stats;
        add_load_phases(stats, *scene);
        RenderRequest request = job_request(a.job, files, f);
        request.comm = comm;
        if (f > shot_first || shot.has_previous()) request.cache_in.clear();  // the shot carries its own cache
        RenderResult r = shot.render(scene, request, stats, sink.get());
        if (writes(comm)) {
            write_frame_outputs(r, files, a.job.show, stats);
            report(a, r, files, stats);
        }
        shot.keep(r, scene);
    }
    return 0;
}

/// --distribute frames: each rank renders a contiguous chunk of the range alone. A chunk starts
/// from the cache file of the frame before it only if that file was there before any rank
/// started (a file another rank writes meanwhile would make the result depend on timing).
int render_frame_chunks(const RenderArgs& a, int first, int last) {
    const Scene scene = load_render_scene(a, first);
    check_ranks(a, scene);  // every rank's chunk is of the same shot
    check_range_in_shot(a, scene, last);
    const int ranks = a.comm->size(), r = a.comm->rank(), n = last - first + 1;
    const int lo = first + static_cast<int>(static_cast<int64_t>(n) * r / ranks);
    const int hi = first + static_cast<int>(static_cast<int64_t>(n) * (r + 1) / ranks) - 1;
    const bool before_ok = lo > first && !a.job.files.cache_out.empty() &&
                           std::filesystem::is_regular_file(expand_frame_pattern(a.job.files.cache_out, lo - 1));
    a.comm->allgather("");  // every rank has looked before any renders
    if (lo > hi) return 0;  // more ranks than frames
    return render_sequence(a, lo, hi, first, nullptr, before_ok);
}

}  // namespace

std::unique_ptr<ProgressSink> make_progress(bool quiet) {
    if (quiet) return make_null_progress();
    return isatty(STDERR_FILENO) ? make_terminal_progress() : make_log_progress();
}

void add_display_options(CLI::App& command, DisplaySettings& display) {
    command
        .add_option("--ocio-config", display.config,
                    "OpenColorIO config for the PNG and the tool's view (default: $OCIO, else built-in sRGB); EXRs stay scene-linear")
        ->each([&display](const std::string&) { display.config_given = true; });
    command.add_option("--display", display.display, "the config's display (default: its default display)");
    command.add_option("--view", display.view, "the display's view (default: its default view)");
}

Distribute parse_distribute(const std::string& name) {
    if (name == "tiles") return Distribute::Tiles;
    if (name == "frames") return Distribute::Frames;
    throw InputError("command line", "--distribute " + name, "is tiles or frames");
}

int run_render(const RenderArgs& given) {
    RenderArgs a = given;
    a.job.files.display = std::make_shared<const DisplayTransform>(a.display, std::getenv("OCIO"));
    const bool chunks = parse_distribute(a.distribute) == Distribute::Frames;
    if (a.frames.empty()) {
        if (a.resume) throw InputError("command line", "--resume", "goes with --frames");
        if (chunks) throw InputError("command line", "--distribute frames", "goes with --frames");
        // The range a key's frame may have (a still has no shot to refuse the frame otherwise).
        const int whole = a.frame ? still_frame_number(*a.frame, a.job.files, "command line", fmt::format("--frame {:g}", *a.frame)) : 0;
        return render_frame(a, expand_frame(a.job.files, whole));
    }
    if (a.frame) throw InputError("command line", "--frame", "give --frame or --frames, not both");
    auto [first, last] = parse_frame_range(a.frames, "--frames " + a.frames);
    check_sequence_names(a.job.files, "command line", [](const std::string& field, const std::string& path) {
        static const std::map<std::string, std::string> flags{
            {"output", "-o"}, {"cache_out", "--cache-out"}, {"deep_out", "--deep-out"}, {"stats_json", "--stats-json"}};
        return flags.at(field) + " " + path;
    });
    if (chunks && a.comm && a.comm->size() > 1) return render_frame_chunks(a, first, last);
    return render_sequence(a, first, last, first, a.comm, false);
}

void add_render_options(CLI::App& render, RenderArgs& ra) {
    render.add_option("scene", ra.job.files.scene, "scene file (.json, or a glTF/OBJ/PLY with a camera)")->required();
    render.add_option("-o,--output", ra.job.files.output, "output EXR (a PNG is written beside it; #### = frame)")->required();
    add_param_flags(render, scene_params(), ra.flags);
    render.add_option("--cache-in", ra.job.files.cache_in, "start from this irradiance cache file (#### = frame)");
    render.add_option("--cache-out", ra.job.files.cache_out, "write the irradiance cache (#### = frame)");
    render.add_flag("--regather", ra.job.regather, "flush the cache before gathering (with --crop: only the crop's records)");
    render.add_flag("--cache-reuse-any", ra.job.reuse_any,
                    "keep a --cache-in gathered with other settings, gather only where it misses (the stats say so)");
    render.add_flag("--force", ra.job.force, "use a cache made for another scene or camera");
    render.add_option("--base", ra.job.files.base, "with --crop: an earlier full-frame EXR to paste the crop over");
    // A decimal number only: strtod also reads "0x2" as 2, and an empty value left frame 1.
    render.add_option("--frame", ra.frame, "render this frame of the shot (keyed values taken then; expands #### in file names)")
        ->check(CLI::Validator(
            [](const std::string& v) {
                static const std::regex decimal(R"([+-]?(\d+\.?\d*|\.\d+)([eE][+-]?\d+)?)");
                return std::regex_match(v, decimal) ? std::string() : "'" + v + "' is not a decimal frame number";
            },
            "FRAME"));
    render.add_option("--frames", ra.frames, "render frames FIRST-LAST of the shot, each starting from what the one before left");
    render.add_flag("--resume", ra.resume, "with --frames: skip frames whose outputs are all there");
    render.add_option("--distribute", ra.distribute,
                      "under mpirun with --frames: tiles (every rank on every frame) or frames (a chunk of frames per rank)");
    render.add_option("--show", ra.job.show, "layer written to the PNG: beauty (default), records, indirect, ao ...");
    render.add_option("--set", ra.sets, "override any scene value: key.path=value")->take_all();
    render.add_option("--deep-out", ra.job.files.deep_out, "write the deep buffer (OpenEXR deep)");
    render.add_option("--deep-in", ra.job.files.deep_in, "shade from a deep buffer instead of tracing visibility");
    render.add_flag("--stats", ra.stats, "print statistics");
    render.add_option("--stats-json", ra.job.files.stats_json, "write statistics as JSON");
    render.add_flag("-q,--quiet", ra.quiet, "no progress output");
    add_display_options(render, ra.display);
}

}  // namespace bounce
