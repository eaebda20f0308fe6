// One frame's steps as run_frame runs them: each step of the plan given what the steps before it
// left (the BVHs, the deep buffer, the radiosity textures, the cache, the sites, the light), and
// the frame's result assembled at the end. The plan decided what runs; this only runs it.
#pragma once

#include <optional>
#include <vector>

#include "bounce/render/frame_passes.h"
#include "bounce/render/render.h"

namespace bounce {

class FrameRun {
  public:
    FrameRun(const Scene& scene, const FramePlan& plan, const FrameState& previous, const RenderRequest& request, Stats& stats,
             ProgressSink* progress);
    FrameRun(const FrameRun&) = delete;
    FrameRun& operator=(const FrameRun&) = delete;

    /// Runs one step of the plan (the first must be its AccelStep), unless its `when` does not hold.
    void run(const PlannedStep& step);
    /// The frame's result once every step ran: the cache and its records layer, the deep buffer
    /// (and the one a deep_out writes), the radiosity textures for a shot's next frame.
    RenderResult finish();

  private:
    void step(const AccelStep& s);
    void step(const VisibilityStep& s);
    void step(const RadiosityStep& s);
    void step(const CacheStartStep& s);
    void step(const SpecularSitesStep& s);
    void step(const GatherRecordsStep& s);
    void step(const RefineStep& s);
    void step(const GatherSitesStep& s);
    void step(const BruteGatherStep& s);
    void step(const ShadeStep& s);
    void step(const FinishRadiosityStep& s);
    /// Runs a gathering step under the "gather" phase; gather_rays_per_s counts every one.
    template <class F>
    void timed_gather(F&& gather);
    const FrameContext& ctx() const { return *ctx_; }

    const Scene& scene_;
    const FramePlan& plan_;
    const FrameState& previous_;
    const RenderRequest& request_;
    Stats& stats_;
    ProgressSink* progress_;
    Materials materials_;
    std::optional<DirectLighting> lighting_;
    SingleProcess alone_;
    std::optional<FrameContext> ctx_;  ///< once the BVHs are there

    VisibilityResult deep_;
    RadiosityResult radiosity_;
    size_t baked_before_ = 0;  ///< radiosity sides baked before the frame's gathers
    CacheStartResult start_;
    SpecularSitesResult specular_;
    std::vector<Indirect> brute_;
    GatherPassResult gathered_;
    size_t shading_misses_ = 0;  ///< of the last shading step
    bool deep_colour_ = false;   ///< the shading step made each fragment's colour
    double gather_s_ = 0;
    uint64_t gather_rays_ = 0;
    RenderResult result_;
};

}  // namespace bounce
