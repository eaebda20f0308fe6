// The `bounce` command line: parses options and calls the library. Nothing else lives here:
// render_cmd.cpp runs frames and sequences, tools_cmd.cpp the tools, light.cpp the lighting tool.
#include <CLI/CLI.hpp>
#include <algorithm>
#include <chrono>
#include <memory>
#include <thread>
#include <cstdio>
#include <string>
#include <vector>

#include <fmt/format.h>

#include "frontend/environment.h"
#include "bounce/core/error.h"
#include "bounce/core/progress.h"
#include "bounce/dist/mpi.h"
#include "bounce/config/params.h"
#include "bounce/core/version.h"
#include "light.h"
#include "render_cmd.h"
#include "tools_cmd.h"

namespace {

using namespace bounce;

/// A command name that is not one of `app`'s subcommands: one line with the nearest and the list.
bool unknown_command(const CLI::App& app, const std::string& word, const std::string& prefix) {
    std::vector<std::string> names;
    for (const CLI::App* sub : app.get_subcommands({})) names.push_back(sub->get_name());
    if (std::find(names.begin(), names.end(), word) != names.end()) return false;
    const std::string hint = closest_match(word, names);
    std::fprintf(stderr, "bounce: command line: %s%s: error: unknown command%s (valid: %s)\n", prefix.c_str(), word.c_str(),
                 hint.empty() ? "" : (" (did you mean \"" + hint + "\"?)").c_str(), fmt::format("{}", fmt::join(names, ", ")).c_str());
    return true;
}

int run_params(bool json, bool markdown) {
    if (json)
        std::printf("%s\n", params_listing().dump(2).c_str());
    else if (markdown)
        std::printf("%s", params_markdown().c_str());
    else
        for (const Param& p : scene_params())
            std::printf("%-32s %-10s %-24s %s\n", p.key.c_str(), p.stage.c_str(), p.default_value().dump().c_str(), p.doc.c_str());
    return 0;
}

}  // namespace

/// One line on stderr for a failure; in a job of many ranks it names the rank. Ranks other than
/// 0 wait a moment first: when every rank fails alike (a bad scene), rank 0's abort ends the
/// others before they print, so the user reads the cause once.
void report_failure(const Communicator* comm, const std::string& text) {
    if (comm && comm->size() > 1) {
        if (comm->rank() > 0) std::this_thread::sleep_for(std::chrono::milliseconds(300));
        // A refusal that names the rank at fault (check_same_job) is printed as it is.
        if (text.starts_with("rank "))
            std::fprintf(stderr, "bounce: %s\n", text.c_str());
        else
            std::fprintf(stderr, "bounce: rank %d: %s\n", comm->rank(), text.c_str());
    } else {
        std::fprintf(stderr, "bounce: %s\n", text.c_str());
    }
    std::fflush(stderr);
}

/// Every subcommand's arguments and its CLI11 app (set once parsed when it was the one given).
struct Commands {
    RenderArgs ra;
    bool params_json = false, params_markdown = false;
    BakeAoArgs ba;
    InfoArgs ia;
    LightArgs la;
    CompareArgs ca;
    CacheArgs ka;
    CLI::App *render = nullptr, *params = nullptr, *bake = nullptr, *light = nullptr, *compare = nullptr, *info = nullptr;
    CLI::App *cache = nullptr, *cinfo = nullptr, *cmerge = nullptr, *cfilter = nullptr, *cexport = nullptr;
};

/// info, bake-ao, light and compare.
void add_tool_commands(CLI::App& app, Commands& c) {
    c.info = app.add_subcommand("info", "what a scene's materials read, and what its mesh files carry that bounce does not");
    c.info->add_option("scene", c.ia.scene, "scene file")->required();

    c.bake = app.add_subcommand("bake-ao", "bake an object's occlusion by its fine (displaced) detail into its uv space");
    c.bake->add_option("scene", c.ba.scene, "scene file")->required();
    c.bake->add_option("--object", c.ba.object, "the object's name")->required();
    c.bake->add_option("-o,--output", c.ba.output, "occlusion map (EXR) for a material's ao_texture")->required();
    c.bake->add_option("--res", c.ba.resolution, "texels per side")->check(CLI::Range(1, 16384));
    c.bake->add_option("--rays", c.ba.rays, "rays per texel")->check(CLI::Range(1, 1 << 20));
    c.bake->add_option("--distance", c.ba.distance, "occluders beyond this do not count; default 4x the displacement bound");

    c.light = app.add_subcommand("light", "the lighting tool: a local web page to edit, re-gather and re-shade");
    c.light->add_option("scene", c.la.scene, "scene file")->required();
    c.light->add_option("--port", c.la.port, "port (0 = any free one)")->check(CLI::Range(0, 65535));
    c.light->add_option("--bind", c.la.bind, "loopback address to listen on (127.0.0.1, ::1, localhost)");
    c.light->add_option("--out", c.la.out_dir, "folder for the session's deep file, cache and saved files");
    c.light->add_option("--deep-in", c.la.deep_in, "start from this deep file");
    c.light->add_option("--cache-in", c.la.cache_in, "start from this irradiance cache");
    c.light->add_option("--threads", c.la.threads, "render threads (0 = all)")->check(CLI::Range(0, 4096));
    add_display_options(*c.light, c.la.display);
    c.light->add_option("--set", c.la.sets, "start with this edit: key.path=value (render.gi defaults to cache)")->take_all();

    c.compare = app.add_subcommand("compare", "error of a render against a reference, per layer");
    c.compare->add_option("test", c.ca.test, "the render to judge (EXR)")->required();
    c.compare->add_option("reference", c.ca.reference, "the reference (EXR)")->required();
    c.compare->add_option(
        "--layer", c.ca.layer,
        "only this layer (beauty, direct, indirect, ao, ..., or beauty_ref_direct: the beauty with the reference's direct light)");
    c.compare->add_option("--diff", c.ca.diff, "false-colour difference PNG (default: TEST.diff.png)");
    c.compare->add_flag("--json", c.ca.json, "print JSON");
    c.compare->add_flag("--sequence", c.ca.sequence, "TEST and REFERENCE are #### frame patterns: per-frame error, flicker, popping");
    c.compare->add_option("--frames", c.ca.frames, "with --sequence: FIRST-LAST");
    c.compare->add_option("--strip", c.ca.strip, "with --sequence: a PNG strip of six frames of the test (and their record dots)");
}

/// cache info, merge, filter and export.
void add_cache_commands(CLI::App& app, Commands& c) {
    c.cache = app.add_subcommand("cache", "inspect, merge, filter and export irradiance cache files");
    c.cache->require_subcommand(1);
    c.cinfo = c.cache->add_subcommand("info", "counts, bounds, parameters, radius histogram, memory (FILE or a #### sequence)");
    c.cinfo->add_option("file", c.ka.inputs, "cache file, or a frame pattern like cache.####.bic")->required()->expected(1);
    c.cinfo->add_flag("--json", c.ka.json, "print JSON");
    c.cmerge = c.cache->add_subcommand("merge", "merge caches without duplicates");
    c.cmerge->add_option("inputs", c.ka.inputs, "caches to merge")->required();
    c.cmerge->add_option("-o,--output", c.ka.output, "merged cache")->required();
    c.cmerge->add_flag("--force", c.ka.force, "merge caches of different scenes or cameras");
    c.cfilter = c.cache->add_subcommand("filter", "keep (or --remove) records by region or value");
    c.cfilter->add_option("input", c.ka.inputs, "cache file")->required()->expected(1);
    c.cfilter->add_option("-o,--output", c.ka.output, "filtered cache")->required();
    c.cfilter->add_option("--box", c.ka.box, "x0,y0,z0,x1,y1,z1: records inside the box");
    c.cfilter->add_option("--sphere", c.ka.sphere, "cx,cy,cz,r: records inside the sphere");
    c.cfilter->add_option("--where", c.ka.where, "FIELD OP NUMBER, e.g. \"pixels<2\" (repeatable, all must hold)");
    c.cfilter->add_flag("--remove", c.ka.remove, "remove the matching records instead of keeping them");
    c.cexport = c.cache->add_subcommand("export", "write a PLY point cloud (MeshLab, CloudCompare, Blender)");
    c.cexport->add_option("input", c.ka.inputs, "cache file")->required()->expected(1);
    c.cexport->add_option("-o,--output", c.ka.output, "PLY file")->required();
}

/// Runs the subcommand given; InputError and the like become a one-line message and a status.
int dispatch(const Commands& c, Communicator* comm, const char* command) {
    try {
        if (*c.render) return run_render(c.ra);
        if (comm && comm->size() > 1) throw InputError("command line", command, "only render runs as an MPI job of many ranks");
        if (*c.params) return run_params(c.params_json, c.params_markdown);
        if (*c.compare) return run_compare(c.ca);
        if (*c.bake) return run_bake_ao(c.ba);
        if (*c.info) return run_info(c.ia);
        if (*c.light) return run_light(c.la);
        if (*c.cinfo) return run_cache_info(c.ka);
        if (*c.cmerge) return run_cache_merge(c.ka);
        if (*c.cfilter) return run_cache_filter(c.ka);
        if (*c.cexport) return run_cache_export(c.ka);
    } catch (const InputError& e) {
        report_failure(comm, e.what());
        return 2;
    } catch (const std::bad_alloc&) {
        // Estimates refuse what cannot fit before allocating; this is what slipped past them.
        report_failure(
            comm,
            "error: out of memory while rendering (lower the resolution, the dicing rate, the fur density or the number of placements)");
        return 2;
    } catch (const Cancelled&) {
        report_failure(comm, "cancelled");
        return 130;
    } catch (const std::exception& e) {
        report_failure(comm, std::string("internal error: ") + e.what());
        return 1;
    }
    return 0;
}

int run_command(int argc, char** argv, Communicator* comm) {
    CLI::App app{"bounce: one-bounce diffuse global illumination and ambient occlusion"};
    app.require_subcommand(1);
    app.set_version_flag("--version", std::string(bounce::bounce_software()));
    Commands c;
    c.ra.comm = comm;
    c.render = app.add_subcommand("render", "render a scene to a multi-layer EXR and a PNG");
    add_render_options(*c.render, c.ra);
    c.params = app.add_subcommand("params", "list every scene parameter: key, stage, default, range, unit, doc");
    c.params->add_flag("--json", c.params_json, "print JSON (the lighting tool's spreadsheet)");
    c.params->add_flag("--markdown", c.params_markdown, "print the Markdown table of docs/scene-format.md");
    add_tool_commands(app, c);
    add_cache_commands(app, c);
    // CLI11 would only say "A subcommand is required".
    if (argc > 1 && argv[1][0] != '-' && unknown_command(app, argv[1], "")) return 2;
    if (argc > 2 && std::string(argv[1]) == "cache" && argv[2][0] != '-' && unknown_command(*c.cache, argv[2], "cache ")) return 2;
    try {
        app.parse(argc, argv);
    } catch (const CLI::CallForHelp& e) {
        return app.exit(e);
    } catch (const CLI::CallForAllHelp& e) {
        return app.exit(e);
    } catch (const CLI::CallForVersion& e) {
        return app.exit(e);
    } catch (const CLI::ArgumentMismatch& e) {
        // CLI11 says "At Most 1 required but received 2" for an option given twice.
        std::string what = e.what();
        if (const auto at = what.find("At Most 1 required but received"); at != std::string::npos)
            what = what.substr(0, at) + "given more than once (an option takes one value; give it once)";
        std::fprintf(stderr, "bounce: command line: error: %s (see bounce --help)\n", what.c_str());
        return 2;
    } catch (const CLI::ParseError& e) {
        std::fprintf(stderr, "bounce: command line: error: %s (see bounce --help)\n", e.what());
        return 2;
    }
    return dispatch(c, comm, argv[1]);
}

int main(int argc, char** argv) {
    // Under mpirun (or srun) the job's ranks share each frame (docs/parallel.md); alone, or as
    // a job of one rank, bounce is the one-process renderer.
    std::unique_ptr<MpiCommunicator> mpi;
    if (launched_by_mpi()) mpi = std::make_unique<MpiCommunicator>(&argc, &argv);
    const int code = run_command(argc, argv, mpi.get());
    // A failed rank must not leave the others waiting at a collective call forever.
    if (code != 0 && mpi && mpi->size() > 1) MpiCommunicator::abort(code);
    return code;
}
