// The frames of a shot rendered in order: each frame's plan starts from what the frame before
// left (its scene, BVHs, radiosity texels, records), so a sequence is a loop of plans
// (docs/animation.md). It holds one frame's state at a time: memory stays flat over any range.
#pragma once

#include <memory>
#include <string>

#include "bounce/render/render.h"

namespace bounce {

class Shot {
  public:
    /// Plans and renders `scene` (the shot at request.frame) after the frame kept last.
    RenderResult render(const std::shared_ptr<const Scene>& scene, RenderRequest request, Stats& stats, ProgressSink* progress);
    /// Keeps what `result` leaves for the next frame (once its outputs are written).
    void keep(RenderResult& result, const std::shared_ptr<const Scene>& scene);
    /// Starts from the cache file of the frame before (a resumed shot, or a rank's chunk of one):
    /// its records are judged against `before`, the scene of that frame. InputError for a bad file.
    void start_from(const std::shared_ptr<const Scene>& before, const std::string& cache_file);
    /// The next frame starts from nothing.
    void forget() { state_ = {}; }
    bool has_previous() const { return state_.scene != nullptr; }

  private:
    FrameState state_;
};

}  // namespace bounce
