// The `bounce` command line: parses options and calls the library. Nothing else lives here.
#include <unistd.h>

#include <CLI/CLI.hpp>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <regex>

#include "bounce/core/atomic_file.h"
#include "bounce/core/error.h"
#include "bounce/core/image.h"
#include "bounce/render/render.h"
#include "bounce/scene/scene_load.h"

namespace {

using namespace bounce;

struct RenderArgs {
    std::string scene, output, res, crop, deep_in, deep_out, stats_json;
    std::vector<std::string> sets;
    int threads = -1, spp = -1;
    int64_t seed = -1;
    bool stats = false, quiet = false;
};

/// Turns the dedicated flags into `--set` assignments so that validation and error messages
/// follow one path (and one name per parameter).
std::vector<std::string> overrides_from(const RenderArgs& a) {
    std::vector<std::string> o = a.sets;
    if (!a.res.empty()) {
        std::smatch m;
        if (!std::regex_match(a.res, m, std::regex(R"((\d{1,6})x(\d{1,6}))")))
            throw InputError("command line", "--res " + a.res, "expected WIDTHxHEIGHT, e.g. 640x480");
        o.push_back("camera.resolution=[" + m[1].str() + "," + m[2].str() + "]");
    }
    if (!a.crop.empty()) {
        if (!std::regex_match(a.crop, std::regex(R"(\d{1,6},\d{1,6},\d{1,6},\d{1,6})")))
            throw InputError("command line", "--crop " + a.crop, "expected x0,x1,y0,y1 (pixels, ends exclusive)");
        o.push_back("render.crop=[" + a.crop + "]");
    }
    if (a.threads >= 0) o.push_back("render.threads=" + std::to_string(a.threads));
    if (a.spp >= 0) o.push_back("render.spp=" + std::to_string(a.spp));
    if (a.seed >= 0) o.push_back("render.seed=" + std::to_string(a.seed));
    return o;
}

int run_render(const RenderArgs& a) {
    Scene scene = load_scene(a.scene, overrides_from(a));
    std::unique_ptr<ProgressSink> sink = a.quiet ? make_null_progress()
                                         : isatty(STDERR_FILENO) ? make_terminal_progress()
                                                                 : make_log_progress();
    Stats stats;
    RenderResult r = render(scene, RenderRequest{a.deep_in, a.deep_out}, stats, sink.get());
    {
        PhaseTimer t(stats, "write images");
        write_exr(a.output, r.image);
        std::filesystem::path png = a.output;
        png.replace_extension(".png");
        write_png(png.string(), r.image, "beauty");
    }
    if (a.stats) std::printf("%s", stats.to_text().c_str());
    if (!a.stats_json.empty()) {
        std::string text = stats.to_json().dump(2) + "\n";
        write_atomically(a.stats_json, [&](const std::string& tmp) {
            std::ofstream out(tmp);
            out << text;
            if (!out) throw InputError(a.stats_json, "", "cannot write stats file");
        });
    }
    if (!a.quiet) std::fprintf(stderr, "wrote %s\n", a.output.c_str());
    return 0;
}

}  // namespace

int main(int argc, char** argv) {
    CLI::App app{"bounce: one-bounce diffuse global illumination and ambient occlusion"};
    app.require_subcommand(1);
    app.set_version_flag("--version", std::string("bounce ") + BOUNCE_VERSION + " (" + BOUNCE_GIT_REV + ")");

    RenderArgs ra;
    CLI::App* render = app.add_subcommand("render", "render a scene to a multi-layer EXR and a PNG");
    render->add_option("scene", ra.scene, "scene file (.json, or a glTF/OBJ/PLY with a camera)")->required();
    render->add_option("-o,--output", ra.output, "output EXR (a PNG is written beside it)")->required();
    render->add_option("--res", ra.res, "resolution WIDTHxHEIGHT (camera.resolution)");
    render->add_option("--threads", ra.threads, "worker threads, 0 = all cores (render.threads)");
    render->add_option("--spp", ra.spp, "subsamples per pixel (render.spp)");
    render->add_option("--seed", ra.seed, "random seed (render.seed)");
    render->add_option("--crop", ra.crop, "render only pixels x0,x1,y0,y1 (render.crop)");
    render->add_option("--set", ra.sets, "override any scene value: key.path=value")->take_all();
    render->add_option("--deep-out", ra.deep_out, "write the deep buffer (OpenEXR deep)");
    render->add_option("--deep-in", ra.deep_in, "shade from a deep buffer instead of tracing visibility");
    render->add_flag("--stats", ra.stats, "print statistics");
    render->add_option("--stats-json", ra.stats_json, "write statistics as JSON");
    render->add_flag("-q,--quiet", ra.quiet, "no progress output");

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
    } catch (const InputError& e) {
        std::fprintf(stderr, "bounce: %s\n", e.what());
        return 2;
    } catch (const std::exception& e) {
        std::fprintf(stderr, "bounce: internal error: %s\n", e.what());
        return 1;
    }
    return 0;
}
