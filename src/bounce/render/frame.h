// A frame's files and a sequence of frames, as a farm driver or the lighting tool needs them:
// the checks made before any work (outputs that would destroy an input, a device or a
// directory), the order outputs are written in (image first, then the cache), and frame
// sequences in which each frame starts from the previous frame's cache.
#pragma once

#include <string>
#include <utility>
#include <vector>

#include "bounce/render/render.h"

namespace bounce {

struct FrameFiles {
    std::string scene;       ///< input
    std::string output;      ///< the EXR; the PNG is written beside it
    std::string deep_in, deep_out, cache_in, cache_out, stats_json;
    std::string base;        ///< with a crop: an earlier full-frame EXR the crop is pasted over
    /// The PNG written beside `output`.
    std::string png() const;
    /// Refuses (InputError) outputs that are not regular files or new names, that name an input
    /// or each other, and an `output` that is not an .exr; removes stale temporary files that
    /// killed renders left beside the outputs.
    void check() const;
};

/// Expands #### in every file name with `frame`.
FrameFiles expand_frame(const FrameFiles& patterns, int frame);

/// "FIRST-LAST" -> {first, last}; InputError(origin) otherwise.
std::pair<int, int> parse_frame_range(const std::string& text, const std::string& origin);

/// The files of `frame` of a sequence starting at `first`: after the first frame, the cache
/// comes from the previous frame's cache output (records are reused, new ones added).
FrameFiles sequence_frame(const FrameFiles& patterns, int first, int frame);

/// Writes the image (EXR, then the PNG of layer `show`) and then the cache, so that a render
/// killed while writing never leaves a new cache beside an old image. With `files.base` the
/// image is the base frame with the render's window pasted over it.
void write_frame_outputs(const RenderResult& result, const FrameFiles& files, const std::string& show);

}  // namespace bounce
