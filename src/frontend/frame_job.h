// A frame as a front end asks for it (the CLI's `render`, Python's `Scene.render`): its files
// and how it treats a cache, the refusals made once its scene is loaded and before any work,
// and the request handed to the render driver. One place, so that every front end refuses the
// same things with the same words and asks the driver the same way.
#pragma once

#include <functional>
#include <string>

#include "bounce/core/stats.h"
#include "bounce/render/frame.h"
#include "bounce/scene/scene.h"

namespace bounce {

struct FrameJob {
    FrameFiles files;
    bool regather = false;        ///< gather the cache anew (--regather)
    bool force = false;           ///< accept a cache made for another scene or camera
    bool reuse_any = false;       ///< keep a cache gathered with other settings (--cache-reuse-any)
    std::string show = "beauty";  ///< the layer the PNG shows
};

/// InputError for options the loaded scene cannot take: a cache out (or in) of a render that
/// makes (or uses) none, a base without a crop, --regather with --cache-reuse-any or in a
/// sequence (`sequence`).
void check_job(const FrameJob& job, const Scene& scene, bool sequence);
/// Refusals of frame `files` (expanded from job.files) once it is planned: outputs against every
/// input, the layer to show, the base.
void check_job_frame(const FrameJob& job, const FrameFiles& files, const Scene& scene, const FramePlan& plan);
/// The driver's request for frame `frame` of the job, whose files are `files`.
RenderRequest job_request(const FrameJob& job, const FrameFiles& files, int frame);
/// The whole frame number a still at `frame` expands #### with. InputError(source, origin) for
/// a frame beyond the shot's range of frame numbers, and for a subframe with #### file names
/// (it would write, and overwrite, a neighbouring frame's files).
int still_frame_number(double frame, const FrameFiles& files, const std::string& source, const std::string& origin);
/// InputError(source, origin(field, path)) for the first output a sequence writes without a ####
/// pattern (fields "output", "cache_out", "deep_out", "stats_json", in that order; an empty
/// name is not written).
void check_sequence_names(const FrameFiles& files, const std::string& source,
                          const std::function<std::string(const std::string& field, const std::string& path)>& origin);
/// The scene's load as the first phases of its frame's statistics (mesh files apart).
void add_load_phases(Stats& stats, const Scene& scene);

}  // namespace bounce
