#include "frontend/frame_job.h"

#include <fmt/format.h>

#include <cmath>

#include "bounce/config/params.h"
#include "bounce/core/error.h"

namespace bounce {

void check_job(const FrameJob& job, const Scene& scene, bool sequence) {
    const bool cache = param_value(scene, "render.gi") == "cache";
    const FrameFiles& f = job.files;
    if (!cache && !f.cache_out.empty())
        throw InputError("command line", "--cache-out " + f.cache_out, "only a --gi cache render makes a cache");
    if (!cache && !f.cache_in.empty() && job.show != "records")
        throw InputError("command line", "--cache-in " + f.cache_in, "only a --gi cache render (or --show records) uses a cache");
    VisibilitySettings visibility;  // for has_crop(): what a crop is is the settings' to say
    visibility.crop = param_value(scene, "render.crop").get<std::array<int, 4>>();
    if (!f.base.empty() && !visibility.has_crop())
        throw InputError("command line", "--base " + f.base, "--base fills the pixels outside --crop; give a crop");
    if (job.reuse_any && job.regather) throw InputError("command line", "--cache-reuse-any", "cannot be combined with --regather");
    if (job.regather && sequence)
        throw InputError("command line", "--regather",
                         "a sequence's frames start from the frame before; render a frame alone (--frame) to gather it anew");
}

void check_job_frame(const FrameJob& job, const FrameFiles& files, const Scene& scene, const FramePlan& plan) {
    files.check(scene);
    check_show_layer(job.show, plan);
    if (!files.base.empty()) check_base(files.base, scene);
}

RenderRequest job_request(const FrameJob& job, const FrameFiles& files, int frame) {
    RenderRequest request;
    request.deep_in = files.deep_in;
    request.deep_out = files.deep_out;
    request.cache_in = files.cache_in;
    request.kind = job.regather ? FrameKind::Regather : FrameKind::Still;
    request.force = job.force;
    request.cache_reuse = job.reuse_any ? CacheReuse::Any : CacheReuse::Strict;
    request.frame = frame;
    return request;
}

int still_frame_number(double frame, const FrameFiles& files, const std::string& source, const std::string& origin) {
    if (!is_frame_number(frame)) throw InputError(source, origin, fmt::format("a frame must be a finite number within +-{:g}", kMaxFrame));
    const int whole = static_cast<int>(std::lround(frame));
    if (frame != whole && files.patterned()) throw InputError(source, origin, "a #### file name needs a whole frame number");
    return whole;
}

void check_sequence_names(const FrameFiles& files, const std::string& source,
                          const std::function<std::string(const std::string& field, const std::string& path)>& origin) {
    for (const auto& [field, path] : {std::pair<const char*, const std::string&>{"output", files.output},
                                      {"cache_out", files.cache_out},
                                      {"deep_out", files.deep_out},
                                      {"stats_json", files.stats_json}})
        if (!path.empty() && path.find('#') == std::string::npos)
            throw InputError(source, origin(field, path), "a sequence needs a #### frame pattern in it");
}

void add_load_phases(Stats& stats, const Scene& scene) {
    stats.add_phase("scene load", scene.load_times.seconds - scene.load_times.mesh_parse_seconds);
    stats.add_phase("mesh parse", scene.load_times.mesh_parse_seconds);
}

}  // namespace bounce
