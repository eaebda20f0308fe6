// A frame's files and a sequence of frames, as a farm driver or the lighting tool needs them:
// the checks made before any work (outputs that would destroy an input, a device or a
// directory; a --show layer the render does not make; a --base of another scene), the order
// outputs are written in at the end of the frame, and frame sequences in which each frame
// starts from the previous frame's cache.
#pragma once

#include <memory>
#include <optional>
#include <string>
#include <utility>
#include <vector>

#include "bounce/core/display.h"
#include "bounce/core/stats.h"
#include "bounce/render/render.h"

namespace bounce {

struct FrameFiles {
    std::string scene;   ///< input
    std::string output;  ///< the EXR; the PNG is written beside it
    std::string deep_in, deep_out, cache_in, cache_out, stats_json;
    std::string base;  ///< with a crop: an earlier full-frame EXR the crop is pasted over
    /// How the PNG's colours are encoded (an OpenColorIO display and view, or the built-in sRGB).
    std::shared_ptr<const DisplayTransform> display = srgb_display();
    /// The PNG written beside `output`.
    std::string png() const;
    /// Whether any file name holds a #### frame pattern (expand_frame expands them).
    bool patterned() const;
    /// Refuses (InputError) outputs that are not regular files or new names, that name an input
    /// (this frame's files, every file `loaded` reads: meshes, textures, maps, the sky, and the OpenColorIO config with its LUTs) or
    /// each other, that lie in a folder it reads (radiosity textures) or in a folder
    /// that cannot take a new file, and an `output` that is not an .exr; removes stale
    /// temporary files that killed renders left beside the outputs.
    void check(const Scene& loaded) const;
};

/// Expands #### in every file name with `frame`.
FrameFiles expand_frame(const FrameFiles& patterns, int frame);

/// "FIRST-LAST" -> {first, last}; InputError(origin) otherwise.
std::pair<int, int> parse_frame_range(const std::string& text, const std::string& origin);

/// The files of `frame` of a sequence starting at `first`: after the first frame, the cache
/// comes from the previous frame's cache output (records are reused, new ones added).
FrameFiles sequence_frame(const FrameFiles& patterns, int first, int frame);

/// The layers a frame of `plan` writes (records: a cache, or a cache file read for them).
std::vector<std::string> frame_layers(const FramePlan& plan);
/// InputError("command line", "--show ...") unless a frame of `plan` writes layer `show`.
void check_show_layer(const std::string& show, const FramePlan& plan);
/// InputError(base) unless `base` is a full-frame EXR rendered from this scene's camera and
/// objects (its lights and materials may differ: that is what a lighter's crop changes).
void check_base(const std::string& base, const Scene& scene);

/// Writes a frame's outputs once it has finished, in one order: the EXR, its PNG (layer
/// `show`), the deep file, the cache, then the stats. A render killed before this leaves every
/// earlier output as it was; killed during it, the outputs before the one being written are new
/// and those after it old — so a cache or stats file newer than the EXR never exists (each is
/// written to a temporary name and renamed). With `files.base` the image is the base frame with
/// the render's window pasted over it. Every front end writes a frame's files here (the CLI, a
/// rank 0, render(), the lighting tool); a file with no name is not written. Returns the pasted
/// full frame when there is a base (the image the EXR holds), none otherwise.
std::optional<Image> write_frame_outputs(const RenderResult& result, const FrameFiles& files, const std::string& show, Stats& stats);

}  // namespace bounce
