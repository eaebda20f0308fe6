// Error and flicker of a rendered sequence against a reference sequence, frame by frame
// (`bounce compare --sequence`, docs/animation.md). Frames are read one pair at a time, so
// memory stays that of two frames of each sequence.
#pragma once

#include <functional>
#include <string>
#include <vector>

#include "bounce/core/image.h"

namespace bounce {

struct SequenceError {
    std::vector<int> frames;
    std::vector<double> rel_rmse;  ///< per frame: RMSE(A_t - B_t) / mean|B_t| on the layer
    double mean_rel_rmse = 0;
    /// RMSE over every frame pair, pixel and channel of (A_t - A_{t-1}) - (B_t - B_{t-1}),
    /// divided by the mean |B| over the sequence: how much more (or other) the test changes
    /// from frame to frame than the reference does. 0 for a test that changes exactly as the
    /// reference does; a static test of a static reference: 0.
    double flicker = 0;
    /// 99.9th percentile over frame pairs and pixels of the per-pixel temporal error (mean over
    /// channels of |(A_t - A_{t-1}) - (B_t - B_{t-1})|), divided by the mean |B|: popping.
    double popping = 0;
};

/// Compares layer `layer` of test frames `test(t)` and reference frames `ref(t)` for t in
/// [first, last]. `name(t)` names a test frame in errors. InputError on mismatched frames.
SequenceError compare_sequences(const std::function<Image(int)>& test, const std::function<Image(int)>& ref, int first, int last,
                                const std::string& layer, const std::function<std::string(int)>& name);

/// A strip of up to `tiles` frames evenly spaced over [first, last]: one row of layer `layer`
/// of `frames(t)` and, when the frames have one, a row of their record dots. 8-bit RGB; its
/// size in `width`, `height`.
std::vector<uint8_t> sequence_strip(const std::function<Image(int)>& frames, int first, int last, const std::string& layer, int tiles,
                                    int& width, int& height);

}  // namespace bounce
