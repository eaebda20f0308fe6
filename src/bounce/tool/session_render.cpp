// The lighting session's renders (session.h): one at a time on a worker thread that a new
// request cancels, each one plan of the session's frame (plan_frame, run_frame) from what the
// last render left, its files written by write_frame_outputs once it has finished.
#include <fmt/format.h>

#include <cmath>

#include "bounce/core/error.h"
#include "bounce/core/stats.h"
#include "bounce/config/params.h"
#include "bounce/render/frame.h"
#include "bounce/render/render.h"
#include "bounce/scene/scene_load.h"
#include "bounce/tool/session.h"

namespace bounce {

namespace fs = std::filesystem;
using nlohmann::json;

class LightingSession::Sink : public ProgressSink {
  public:
    explicit Sink(LightingSession& s) : s_(s) {}
    void update(const std::string& name, uint64_t done, uint64_t total, double) override {
        std::lock_guard lock(s_.mutex_);
        s_.phase_ = name, s_.done_ = done, s_.total_ = total;
    }
    void finish(const std::string& name, uint64_t total, double) override {
        std::lock_guard lock(s_.mutex_);
        s_.phase_ = name, s_.done_ = total, s_.total_ = total;
    }

  private:
    LightingSession& s_;
};

void LightingSession::start(SessionAction action, std::optional<std::array<int, 4>> crop) {
    std::lock_guard control(control_);  // two requests at once: one after the other
    stop();
    if (worker_.joinable()) worker_.join();
    std::lock_guard lock(mutex_);
    if (crop) {
        const auto& c = *crop;
        if (c[0] < 0 || c[2] < 0 || c[1] > scene_.camera.width || c[3] > scene_.camera.height || c[0] >= c[1] || c[2] >= c[3])
            throw InputError("request", "crop",
                             fmt::format("[{}, {}, {}, {}] is not a rectangle inside the {}x{} frame", c[0], c[1], c[2], c[3],
                                         scene_.camera.width, scene_.camera.height));
        if (image_.width != scene_.camera.width || image_.height != scene_.camera.height || !fs::exists(deep_path_))
            throw InputError("request", "crop", "render the whole frame once before a sub-viewport");
        if (action == SessionAction::Rasterize) throw InputError("request", "crop", "a new deep file is always the whole frame");
    }
    if (action == SessionAction::Frame) start_replay_locked();
    cancel_ = std::make_unique<CancelToken>();
    running_ = true;
    state_ = SessionState::Running, message_.clear(), action_ = action;
    phase_.clear(), done_ = total_ = 0;
    worker_ = std::thread([this, action, crop] { run(action, crop); });
}

void LightingSession::stop() {
    std::unique_lock lock(mutex_);
    if (cancel_) cancel_->cancel();
    idle_.wait(lock, [&] { return !running_; });
}

void LightingSession::wait() {
    std::unique_lock lock(mutex_);
    idle_.wait(lock, [&] { return !running_; });
}

void LightingSession::render_once(SessionAction action, std::optional<std::array<int, 4>> crop, Stats& stats, ProgressSink& sink) {
    Scene scene;
    RenderRequest req;
    uint64_t edits_seen = 0;
    FrameState previous;
    fs::path cache_file;
    {
        // The scene as the last edit loaded it (no file is read again); the request's own
        // settings are not part of any identity.
        std::lock_guard lock(mutex_);
        scene = scene_;
        edits_seen = edit_count_;
        if (crop) set_param_value(scene, "render.crop", *crop);
        if (options_.threads > 0) set_param_value(scene, "render.threads", options_.threads);
        // Renders stream their previews unless the lighter turned them off.
        if (!edits_.count("render.preview")) set_param_value(scene, "render.preview", true);
        req = request_locked(action, param_value(scene, "render.gi") == "cache", crop.has_value(), previous);
        cache_file = cache_path_locked();
    }
    // Called only where the plan previews (render.preview, a cache render).
    req.preview = [&](const Image& img) {
        std::lock_guard lock(mutex_);
        // Over the last full frame when there is one: layers a preview lacks stay shown.
        // (A frame with other layers, e.g. rendered before GI was on, is replaced instead.)
        const bool over = crop || (image_.width == img.full_width && image_.height == img.full_height);
        try {
            image_ = over ? paste_over(image_, img, "session image") : img;
        } catch (const InputError&) {
            if (crop) return;  // the final paste says why
            image_ = img;
        }
        ++version_;
    };
    // The session's deep file follows a new deep buffer (a shot's frame may keep the last one,
    // whose file is on disk: asking for it every frame would copy the buffer for nothing).
    req.deep_out_if_traced = deep_path_.string();
    const FramePlan plan = plan_frame(scene, previous, req);
    RenderResult r = run_frame(scene, plan, previous, req, stats, &sink);
    // Only a finished render replaces the deep file and the cache (atomically) and the image.
    FrameFiles files;
    files.deep_out = plan.deep_out;
    if (plan.indirect() == IndirectFrom::Cache && (r.cache_changed() || action != SessionAction::Reshade || !fs::exists(cache_file)))
        files.cache_out = cache_file.string();
    write_frame_outputs(r, files, "", stats);
    std::lock_guard lock(mutex_);
    keep_locked(action, crop.has_value(), edits_seen, std::move(scene), r);
}

RenderRequest LightingSession::request_locked(SessionAction action, bool cached, bool crop, FrameState& previous) const {
    RenderRequest req;
    req.cancel = cancel_.get();
    req.frame = static_cast<int>(std::lround(frame_));
    previous = last_;
    // In a shot, a whole frame stepped to, made anew or gathered anew is planned as --frames
    // plans a frame (a new deep file or the kept one, the records keeping what the next frame
    // reuses), so the next frame starts from what it would start from in a sequence.
    const bool shot = scene_.shot.animated && !crop;
    const bool anew = action == SessionAction::Rasterize || !previous.deep;
    if (action == SessionAction::Frame || (shot && action == SessionAction::Rasterize) ||
        (shot && action == SessionAction::Regather && !anew)) {
        req.kind = FrameKind::ShotFrame;
        if (action == SessionAction::Rasterize) previous = {};
        if (action == SessionAction::Regather) previous.cache.reset(), previous.waiting.reset(), previous.gathers.reset();
        return req;
    }
    set_session_files(action, req, previous, cached);
    return req;
}

void LightingSession::set_session_files(SessionAction action, RenderRequest& req, FrameState& previous, bool cached) const {
    // The session's deep buffer and cache, from memory when it holds them, else from its files.
    req.kind = action == SessionAction::Reshade    ? FrameKind::Reshade
               : action == SessionAction::Regather ? FrameKind::Regather
                                                   : FrameKind::Still;
    if (action == SessionAction::Rasterize || !fs::exists(deep_path_))
        req.deep_out = deep_path_.string(), previous.deep.reset();
    else if (!previous.deep)
        req.deep_in = deep_path_.string();
    const fs::path cache_file = cache_path_locked();
    if (cached && action != SessionAction::Rasterize && fs::exists(cache_file)) {
        // The session knows its cache's history: lights and materials may have changed since
        // it was gathered (a re-shade keeps its bounce light on purpose).
        if (!previous.cache) req.cache_in = cache_file.string();
        req.force = true;
        req.cache_reuse = CacheReuse::Any;
    } else {
        previous.cache.reset();
    }
}

void LightingSession::keep_locked(SessionAction action, bool crop, uint64_t edits_seen, Scene scene, RenderResult& r) {
    image_ = crop ? paste_over(image_, r.image, "session image") : std::move(r.image);
    ++version_;
    if (!crop && edit_count_ == edits_seen) {  // edits made while it ran still need showing
        pending_ = -1;
        if (action == SessionAction::Regather || action == SessionAction::Rasterize) bounce_stale_ = false;
    }
    // The state kept is the sequence's at this frame: the next frame steps from it (set_frame).
    if (!crop && scene.shot.animated) {
        const int frame = static_cast<int>(std::lround(frame_));
        if (action == SessionAction::Rasterize || !sequence_frame_) sequence_first_ = frame;
        sequence_frame_ = frame;
    }
    FrameState next = r.release_state();
    if (!next.cache) next.cache = last_.cache;  // what the file still holds
    if (crop) {                                 // the frame's deep buffer, scene and BVHs stay; the cache is what the file now holds
        last_.cache = next.cache;
        return;
    }
    next.scene = std::make_shared<const Scene>(std::move(scene));
    last_ = std::move(next);
}

void LightingSession::render_action(SessionAction action, std::optional<std::array<int, 4>> crop, ProgressSink& sink, json& stats) {
    const auto render = [&](SessionAction a, std::optional<std::array<int, 4>> c) {
        Stats one;
        struct Keep {  // the statistics also of a render that throws
            Stats& from;
            json& to;
            ~Keep() { to = from.to_json(); }
        } keep{one, stats};
        render_once(a, c, one, sink);
    };
    if (action != SessionAction::Frame) return render(action, crop);
    while (const std::optional<SessionAction> step = next_replay_frame()) render(*step, std::nullopt);
}

std::optional<SessionAction> LightingSession::next_replay_frame() {
    std::lock_guard lock(mutex_);
    if (replay_.next > replay_.target) return std::nullopt;
    LoadOptions at;
    at.frame = replay_.next;
    at.resources = options_.resources;
    scene_ = load_scene(options_.scene, overrides_locked(), at);
    frame_ = replay_.next;
    // A replay from the sequence's start makes its first frame anew, as --frames does.
    const bool anew = replay_.fresh && replay_.next == replay_.first;
    ++replay_.next;
    return anew ? SessionAction::Rasterize : SessionAction::Frame;
}

void LightingSession::run(SessionAction action, std::optional<std::array<int, 4>> crop) {
    SessionState state = SessionState::Done;
    std::string message;
    json stats_json;
    // A render that is stopped or fails leaves the image it started from, not its previews.
    Image before;
    uint64_t before_version = 0;
    {
        std::lock_guard lock(mutex_);
        before = image_, before_version = version_;
    }
    {
        // Everything the render allocated is freed before the session says it is idle.
        Sink sink(*this);
        try {
            render_action(action, crop, sink, stats_json);
        } catch (const Cancelled&) {
            state = SessionState::Cancelled;
        } catch (const std::exception& e) {
            state = SessionState::Failed, message = e.what();  // the previous image and cache stay
        }
    }
    std::lock_guard lock(mutex_);
    if (state != SessionState::Done && version_ != before_version) image_ = std::move(before), ++version_;
    stats_ = std::move(stats_json);
    state_ = state, message_ = message;
    running_ = false;
    idle_.notify_all();
}

}  // namespace bounce
