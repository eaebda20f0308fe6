// The lighting tool's engine side: one scene with the lighter's edits, its deep file and
// irradiance cache in the output folder, and one render at a time on a worker thread that a
// new request cancels. The web server (server.h) is a thin front end over this, as the CLI is
// over render.h; tests drive it directly.
#pragma once

#include <array>
#include <condition_variable>
#include <filesystem>
#include <map>
#include <mutex>
#include <nlohmann/json.hpp>
#include <optional>
#include <string>
#include <thread>
#include <utility>
#include <vector>

#include "bounce/cache/cache_file.h"
#include "bounce/cache/irradiance_cache.h"
#include "bounce/core/image.h"
#include "bounce/deep/deep_buffer.h"
#include "bounce/core/progress.h"
#include "bounce/core/stats.h"
#include "bounce/render/frame_plan.h"
#include "bounce/render/render.h"
#include "bounce/scene/json_reader.h"
#include "bounce/scene/load_resources.h"
#include "bounce/scene/scene.h"

namespace bounce {

/// What the 3D view draws: metadata and named float arrays. Sent as one JSON object (the arrays
/// as numbers), or for the page as bytes: the arrays' float32 values one after the other, the
/// metadata (with each array's name and length) beside them (server.h).
struct ViewArrays {
    nlohmann::json meta;
    std::vector<std::pair<std::string, std::vector<float>>> arrays;
    nlohmann::json to_json() const;
    /// The arrays' values, little-endian float32, in order.
    std::string bytes() const;
    /// `meta` with "arrays": [[name, length], ...].
    nlohmann::json layout() const;
};

struct SessionOptions {
    std::string scene;     ///< scene file
    std::string out_dir;   ///< where the session's deep file, cache and saved files go
    std::string deep_in;   ///< start from this deep file (copied in as the session's)
    std::string cache_in;  ///< start from this cache file (copied in as the session's)
    int threads = 0;       ///< render threads; 0 = all
    /// Edits applied at the start ("key=value", value JSON or a bare word), as the CLI's --set.
    std::vector<std::string> sets;
    /// When the scene renders no indirect light (render.gi none, no AO), start with the cache:
    /// bounce light is what the tool is for.
    bool default_to_cache = true;
    /// Unless the scene or `sets` say otherwise, records keep their bounce light per light
    /// (render.light_parts), so a light's colour or intensity edit updates it exactly.
    bool default_to_light_parts = true;
    /// How the view's colours are encoded (an OpenColorIO display and view, or the built-in sRGB).
    std::shared_ptr<const DisplayTransform> display = srgb_display();
    LoadResources resources;  ///< where the scene's loads keep parsed meshes and embedded images
};

/// What a render request does, least work first.
enum class SessionAction {
    Reshade,    ///< deep file and cache reused: shading (and gathers only where records miss)
    Regather,   ///< deep file reused, records flushed (inside the crop, if one is given)
    Rasterize,  ///< new deep file, new cache
    Frame,      ///< another frame of the shot: what the last frame left is kept, moved or redone by its plan
};
SessionAction parse_session_action(const std::string& name);  ///< InputError on another name
const char* session_action_name(SessionAction a);

/// Where the session's render is; the status carries its name and the page switches on it.
enum class SessionState : uint8_t {
    Idle,  ///< nothing rendered yet
    Running,
    Done,       ///< the last render finished: its image, deep file and cache are the session's
    Cancelled,  ///< stopped (or replaced by a newer request): the image before it stays
    Failed,     ///< the message says why; the image, deep file and cache before it stay
};
const char* session_state_name(SessionState s);

class LightingSession {
  public:
    /// Loads the scene (InputError on bad input); creates out_dir.
    explicit LightingSession(SessionOptions options);
    ~LightingSession();  ///< cancels and joins a running render
    LightingSession(const LightingSession&) = delete;
    LightingSession& operator=(const LightingSession&) = delete;

    /// One row per parameter (the parameter table's camera and render rows, then every numeric
    /// field of every light and material): key, value, default, unit, range, doc, and `needs`,
    /// the least action that shows a change of it.
    nlohmann::json params() const;
    /// Sets `key` to `value` with the scene loader's validation (InputError, one line, on a bad
    /// key or value: nothing changes). Returns {key, value, needs}.
    /// Errors name the lighting tool's edit ("lighting tool: edit KEY=VALUE (/pointer): ..."),
    /// or with `cli_origin` the command line's ("--set ...", given when the session starts).
    nlohmann::json edit(const std::string& key, const nlohmann::json& value, const std::string& cli_origin = "");
    /// The least action that shows every edit since the last finished render.
    SessionAction pending() const;
    /// Moves to `frame` of the scene's shot (InputError outside it, for a fraction, or for a
    /// still) and starts its render, planned from what the last frame left as `bounce render
    /// --frames` plans a shot's next frame (a frame slider). A frame is the farm's however it
    /// is reached: a jump past the next frame renders the frames in between first, and a move
    /// back replays the sequence from its first frame (the frame its new deep file was made
    /// at), so frame k is `--frames F-k`'s frame k. Returns {frame, from}: the first frame the
    /// render goes through.
    nlohmann::json set_frame(double frame);

    /// Starts a render on the worker, cancelling a running one first. `crop` (full-frame pixel
    /// coordinates x0, x1, y0, y1) limits a re-shade or re-gather to a sub-viewport, pasted
    /// over the last full image.
    void start(SessionAction action, std::optional<std::array<int, 4>> crop = std::nullopt);
    void stop();  ///< cancels the running render (returns once it has stopped)
    void wait();  ///< until no render runs

    /// {state, action, message, progress {phase, done, total}, stats, image {version, width,
    /// height, layers}, records, pending}.
    nlohmann::json status() const;
    /// The current image's `layer` as 8-bit sRGB RGBA after `exposure` stops (data, width,
    /// height); InputError when there is no image or no such layer.
    struct Pixels {
        std::string rgba;
        int width = 0, height = 0;
        uint64_t version = 0;
    };
    Pixels pixels(const std::string& layer, float exposure) const;
    /// The current image, every layer in float (tests and benches compare it).
    Image image() const;
    /// Records of a cache file (the session's when `file` is empty; else a path confined to
    /// the allowed folders): {file, count, frame, ...} and the arrays p, n, r, E, ao, at most
    /// `limit` records; with `region` (x0, x1, y0, y1 in pixels) only those the camera sees inside it.
    ViewArrays records(const std::string& file, size_t limit, std::optional<std::array<int, 4>> region = std::nullopt) const;
    /// Cache files in the allowed folders (for the 3D view's frame slider).
    nlohmann::json cache_files() const;
    /// What the 3D view draws: camera, lights (with their parameter keys), and the array
    /// `triangles`: at most `max_triangles` triangles of the ray-traced tessellation.
    ViewArrays scene_view(size_t max_triangles) const;

    /// Writes the scene with every edit applied, atomically, into the scene's folder.
    std::string save_scene(const std::string& name) const;
    std::string save_cache(const std::string& name) const;  ///< copies the session's cache to out_dir/name
    /// Makes `file` the session's cache: InputError when it was gathered on other objects or
    /// for another camera; its bounce light is stale when it was gathered under other lights or
    /// materials (but colours and intensities, when its records keep their light parts).
    void load_cache(const std::string& file);

    /// `name` resolved inside the scene's folder or the output folder; InputError (naming
    /// `what`) for absolute paths, "..", or a symlink that leads out.
    std::filesystem::path confined(const std::string& name, const std::string& what) const;

    const std::filesystem::path& deep_path() const { return deep_path_; }
    /// The session's cache: session.bic, or in a shot the current frame's, session.NNNN.bic
    /// (every frame rendered keeps its own, for the 3D view's cache sequence).
    std::filesystem::path cache_path() const;

  private:
    class Sink;
    void run(SessionAction action, std::optional<std::array<int, 4>> crop);
    /// Renders `action` (a slider move: each frame of its replay in turn); `stats` ends as the
    /// statistics of the frame rendered last, also when it throws.
    void render_action(SessionAction action, std::optional<std::array<int, 4>> crop, ProgressSink& sink, nlohmann::json& stats);
    /// The next frame of a slider move made the session's (its scene loaded), and the action
    /// that renders it; none when the move is done.
    std::optional<SessionAction> next_replay_frame();
    /// One frame through its plan (plan_frame): a re-shade gathers only if records are missing.
    void render_once(SessionAction action, std::optional<std::array<int, 4>> crop, Stats& stats, ProgressSink& sink);
    std::vector<Override> overrides_locked() const;
    /// The loader's check (LoadOptions::check_path) for an edit of `key`: a file or folder it
    /// sets outside the scene's folder and the output folder (a mesh, a texture, the radiosity
    /// folder) is refused before it is read or made: the page reaches no further than the file API.
    std::function<void(const std::string&, const std::string&)> edit_path_check(const std::string& key) const;
    /// A re-shade, re-gather or new deep file: the session's deep buffer and cache (memory or files).
    void set_session_files(SessionAction action, RenderRequest& req, FrameState& previous, bool cached) const;
    /// The request of `action` at the session's frame, and the state it starts from.
    RenderRequest request_locked(SessionAction action, bool cached, bool crop, FrameState& previous) const;
    std::filesystem::path cache_path_locked() const;  ///< cache_path() with mutex_ held
    /// After a render: the frame's image, the state the next one starts from, what is pending.
    void keep_locked(SessionAction action, bool crop, uint64_t edits_seen, Scene scene, RenderResult& r);

    SessionOptions options_;
    std::filesystem::path scene_dir_, out_dir_, deep_path_;
    std::mutex control_;  ///< serialises start / load_cache / destruction (the worker thread's owners)
    mutable std::mutex mutex_;
    std::condition_variable idle_;
    std::map<std::string, nlohmann::json> edits_;  ///< key -> value, in the order of the table
    std::vector<std::string> edit_order_;
    Scene scene_;       ///< with every edit, at frame_
    double frame_ = 1;  ///< the shot's frame the session shows
    /// In a shot: the frame whose state last_ holds as the sequence left it (`--frames F-k`'s
    /// frame k, F = sequence_first_), so the next frame steps from it; none before a first frame.
    std::optional<int> sequence_frame_;
    int sequence_first_ = 1;
    /// A slider move's frames: next to render, the one asked for, and whether the first starts
    /// the sequence anew (no kept state).
    struct Replay {
        int first = 0, next = 0, target = 0;
        bool fresh = false;
    };
    Replay replay_;
    int frame_asked_ = 1;  ///< the frame set_frame was last asked for
    /// replay_ for frame_asked_, from the sequence as the last render left it (so called by
    /// start() once the render before has stopped: a move during a move starts from its end).
    void start_replay_locked();
    int pending_ = -1;         ///< SessionAction, or -1 = nothing to show
    uint64_t edit_count_ = 0;  ///< edits so far (a render clears pending_ only if none came while it ran)
    /// A light or material edit was re-shaded over records gathered with the old lights: the
    /// bounce light is the old one until a full-frame re-gather (or new deep file) is done.
    /// (A colour or intensity edit of a light is not, while the records keep light parts.)
    bool bounce_stale_ = false;
    /// The lights a cache file brought in keeps its records' parts for (0: none): until a
    /// render holds its records in last_, what says whether a light's edit rescales them.
    size_t file_parts_lights_ = 0;
    /// A cache file brought in (load_cache, --cache-in): checked against the scene (see load_cache).
    void adopt_cache_locked(const CacheFile& f, const std::string& name);
    // Worker state.
    std::thread worker_;
    std::unique_ptr<CancelToken> cancel_;
    bool running_ = false;
    SessionState state_ = SessionState::Idle;
    std::optional<SessionAction> action_;  ///< of the running or last render
    std::string message_;
    std::string phase_;
    uint64_t done_ = 0, total_ = 0;
    nlohmann::json stats_ = nlohmann::json::object();
    Image image_;  ///< the last full frame (a sub-viewport render is pasted over it)
    /// What the last render left, whole (frame_plan.h): its deep buffer and cache as the
    /// session's files hold them (kept for re-shades), and for the next frame of a shot the
    /// scene last rendered in full, its BVHs, radiosity textures, the records no fragment
    /// needed yet and refinement's gathers: the state a Shot carries from frame to frame.
    FrameState last_;
    uint64_t version_ = 0;
    mutable uint64_t status_serial_ = 0;  ///< numbers status snapshots: a page drops one older than it holds
};

}  // namespace bounce
