#include "bounce/tool/session.h"

#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <functional>
#include <fstream>

#include "bounce/cache/cache_file.h"
#include "bounce/core/json_limits.h"
#include "bounce/core/atomic_file.h"
#include "bounce/core/error.h"
#include "bounce/core/files.h"
#include "bounce/core/stats.h"
#include "bounce/deep/deep_buffer.h"
#include "bounce/render/render.h"
#include "bounce/scene/params.h"
#include "bounce/scene/scene_load.h"

namespace bounce {

namespace fs = std::filesystem;
using nlohmann::json;

SessionAction parse_session_action(const std::string& name) {
    if (name == "reshade") return SessionAction::Reshade;
    if (name == "regather") return SessionAction::Regather;
    if (name == "rasterize") return SessionAction::Rasterize;
    if (name == "frame") return SessionAction::Frame;
    throw InputError("request", "action", fmt::format("'{}' is not reshade, regather, rasterize or frame", name));
}

const char* session_action_name(SessionAction a) {
    switch (a) {
        case SessionAction::Reshade: return "reshade";
        case SessionAction::Regather: return "regather";
        case SessionAction::Rasterize: return "rasterize";
        case SessionAction::Frame: return "frame";
    }
    return "?";
}

namespace {

/// The least action that shows a change of a parameter with identity `identity`.
SessionAction needs_for(unsigned identity) {
    if (identity & kDeepIdentity) return SessionAction::Rasterize;
    if (identity & (kCacheIdentity | kRadiosityIdentity)) return SessionAction::Regather;
    return SessionAction::Reshade;
}

/// Light and material fields the spreadsheet edits: numbers, booleans and [x, y, z].
bool editable(const json& v) {
    if (v.is_number() || v.is_boolean()) return true;
    return v.is_array() && v.size() == 3 && std::all_of(v.begin(), v.end(), [](const json& e) { return e.is_number(); });
}

/// Light and material rows of the effective scene description.
void add_scene_rows(const json& description, json& rows) {
    auto row = [&](const std::string& key, const std::string& stage, const json& value, const std::string& doc) {
        rows.push_back({{"key", key}, {"stage", stage}, {"value", value}, {"default", nullptr}, {"unit", ""},
                        {"range", nullptr}, {"doc", doc}, {"needs", "reshade"}});
    };
    if (description.contains("lights") && description["lights"].is_array())
        for (size_t i = 0; i < description["lights"].size(); ++i) {
            const json& l = description["lights"][i];
            if (!l.is_object()) continue;
            for (const auto& [k, v] : l.items())
                if (editable(v))
                    row(fmt::format("lights.{}.{}", i, k), "light", v,
                        fmt::format("{} light {}; a re-gather updates its bounce light", l.value("type", "?"), i));
        }
    if (description.contains("materials") && description["materials"].is_object())
        for (const auto& [name, m] : description["materials"].items()) {
            if (!m.is_object()) continue;
            for (const auto& [k, v] : m.items())
                if (editable(v))
                    row(fmt::format("materials.{}.{}", name, k), "material", v, "material " + name + "; a re-gather updates its bounce light");
        }
}

}  // namespace

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

LightingSession::LightingSession(SessionOptions options) : options_(std::move(options)) {
    scene_ = load_scene(options_.scene);
    frame_ = scene_.frame;
    scene_dir_ = fs::weakly_canonical(fs::absolute(options_.scene)).parent_path();
    std::error_code ec;
    fs::create_directories(options_.out_dir, ec);
    if (ec || !fs::is_directory(options_.out_dir))
        throw InputError(options_.out_dir, "", "cannot create the output folder (" + ec.message() + ")");
    out_dir_ = fs::canonical(options_.out_dir);
    deep_path_ = out_dir_ / "session.deep.exr";
    cache_path_ = out_dir_ / "session.bic";
    // Start from the given files: copies, so the lighter's originals are never overwritten.
    // Each is read (and refused, naming it) before it replaces the session's own file.
    auto copy_in = [&](const std::string& from, const fs::path& to, const std::function<void(const std::string&)>& check) {
        if (from.empty()) return;
        check_input_file(from);
        check(from);
        if (fs::weakly_canonical(from) != to) fs::copy_file(from, to, fs::copy_options::overwrite_existing);
    };
    for (const std::string& s : options_.sets) {
        const auto eq = s.find('=');
        if (eq == std::string::npos) throw InputError("command line", "--set " + s, "expected key=value");
        const std::string text = s.substr(eq + 1);
        check_json_nesting(text, "--set " + s);
        json v = json::parse(text, nullptr, false);
        edit(s.substr(0, eq), v.is_discarded() ? json(text) : v, "--set " + s);
    }
    if (options_.default_to_cache && scene_.render.indirect.gi == GiMode::None && !scene_.render.indirect.ao) edit("render.gi", "cache");
    pending_ = -1;  // nothing rendered yet: the first render is a new deep file anyway
    copy_in(options_.deep_in, deep_path_, [&](const std::string& f) { validate_deep_for_scene(read_deep(f), scene_, f); });
    copy_in(options_.cache_in, cache_path_, [](const std::string& f) { read_cache_file(f); });
}

LightingSession::~LightingSession() {
    std::lock_guard control(control_);
    stop();
    if (worker_.joinable()) worker_.join();
}

std::vector<Override> LightingSession::overrides_locked() const {
    std::vector<Override> out;
    for (const auto& key : edit_order_) out.emplace_back(key + "=" + edits_.at(key).dump(), "edit of " + key);
    return out;
}

json LightingSession::params() const {
    std::lock_guard lock(mutex_);
    json rows = json::array();
    const json values = param_values(scene_, ~0u);
    for (json row : params_listing()) {
        const std::string key = row["key"];
        const Param* p = find_param(scene_params(), key);
        row["value"] = values.contains(key) ? values[key] : json(nullptr);
        row["needs"] = session_action_name(needs_for(p ? p->identity : kImageOnly));
        rows.push_back(std::move(row));
    }
    add_scene_rows(scene_.description, rows);
    return rows;
}

json LightingSession::edit(const std::string& key, const json& value, const std::string& origin) {
    if (key.empty() || key.size() > 256) throw InputError("request", "key", "a parameter key of 1..256 characters is required");
    std::lock_guard lock(mutex_);
    std::vector<Override> o = overrides_locked();
    o.emplace_back(key + "=" + value.dump(), origin.empty() ? "edit of " + key : origin);
    LoadOptions at;
    at.frame = frame_;
    Scene s = load_scene(options_.scene, o, at);  // throws with the file and place on a bad value
    if (!edits_.count(key)) edit_order_.push_back(key);
    edits_[key] = value;
    ++edit_count_;
    scene_ = std::move(s);
    const Param* p = find_param(scene_params(), key);
    // Lights and materials: a re-shade shows them (the bounce light follows on a re-gather).
    const SessionAction needs = needs_for(p ? p->identity : kImageOnly);
    pending_ = std::max(pending_, static_cast<int>(needs));
    return {{"key", key}, {"value", value}, {"needs", session_action_name(needs)}};
}

json LightingSession::set_frame(double frame) {
    {
        std::lock_guard lock(mutex_);
        if (!scene_.shot.animated) throw InputError("request", "frame", "the scene has no shot (no \"animation\" block)");
        if (!std::isfinite(frame) || !scene_.shot.contains(frame))
            throw InputError("request", "frame", fmt::format("{} is outside the shot, frames {} to {}", frame, scene_.shot.first, scene_.shot.last));
        LoadOptions at;
        at.frame = frame;
        scene_ = load_scene(options_.scene, overrides_locked(), at);
        frame_ = frame;
        ++edit_count_;
    }
    start(SessionAction::Frame);
    return {{"frame", frame}};
}

SessionAction LightingSession::pending() const {
    std::lock_guard lock(mutex_);
    return static_cast<SessionAction>(std::max(pending_, 0));
}

void LightingSession::start(SessionAction action, std::optional<std::array<int, 4>> crop) {
    std::lock_guard control(control_);  // two requests at once: one after the other
    stop();
    if (worker_.joinable()) worker_.join();
    std::lock_guard lock(mutex_);
    if (crop) {
        const auto& c = *crop;
        if (c[0] < 0 || c[2] < 0 || c[1] > scene_.camera.width || c[3] > scene_.camera.height || c[0] >= c[1] || c[2] >= c[3])
            throw InputError("request", "crop", fmt::format("[{}, {}, {}, {}] is not a rectangle inside the {}x{} frame", c[0], c[1],
                                                            c[2], c[3], scene_.camera.width, scene_.camera.height));
        if (image_.width != scene_.camera.width || image_.height != scene_.camera.height || !fs::exists(deep_path_))
            throw InputError("request", "crop", "render the whole frame once before a sub-viewport");
        if (action == SessionAction::Rasterize) throw InputError("request", "crop", "a new deep file is always the whole frame");
    }
    cancel_ = std::make_unique<CancelToken>();
    running_ = true;
    state_ = "running", message_.clear(), action_ = session_action_name(action);
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

void LightingSession::render_once(SessionAction action, std::optional<std::array<int, 4>> crop, Stats& stats,
                                  ProgressSink& sink) {
    Scene scene;
    RenderRequest req;
    uint64_t edits_seen = 0;
    FrameState previous;
    {
        // The scene as the last edit loaded it (no file is read again); the request's own
        // settings are not part of any identity.
        std::lock_guard lock(mutex_);
        scene = scene_;
        edits_seen = edit_count_;
        if (crop) scene.render.visibility.crop = *crop;
        if (options_.threads > 0) scene.render.parallel.threads = options_.threads;
        // Renders stream their previews unless the lighter turned them off.
        if (!edits_.count("render.preview")) scene.render.parallel.preview = true;
        req.cancel = cancel_.get();
        previous.deep = deep_, previous.cache = cache_;
        previous.scene = rendered_, previous.accel = accel_, previous.radiosity = radiosity_, previous.waiting = waiting_;
    }
    const bool cached = scene.render.indirect.gi == GiMode::Cache;
    if (action == SessionAction::Frame) {
        // Another frame of the shot: its plan keeps, moves or redoes what the last one left.
        req.sequence = true;
    } else {
        set_session_files(action, req, previous, cached);
    }
    if (cached && scene.render.parallel.preview)
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
    FramePlan plan = plan_frame(scene, previous, req);
    if (plan.visibility == VisibilityStep::Trace) plan.deep_out = deep_path_.string();  // the session's file follows
    RenderResult r = run_frame(scene, plan, previous, req, stats, &sink);
    // Only a finished render replaces the deep file and the cache (atomically) and the image.
    if (r.gathered_deep) write_deep(plan.deep_out, *r.gathered_deep);
    if (cached && r.cache && (r.cache_changed() || action != SessionAction::Reshade))
        write_cache_file(cache_path_.string(), r.cache->to_file(r.cache_info));
    std::lock_guard lock(mutex_);
    image_ = crop ? paste_over(image_, r.image, "session image") : std::move(r.image);
    ++version_;
    if (!crop && edit_count_ == edits_seen) pending_ = -1;  // edits made while it ran still need showing
    const bool new_deep = !crop && plan.visibility != VisibilityStep::Previous;
    FrameState next = r.release_state();
    if (new_deep) deep_ = next.deep;  // else deep_ holds it already
    if (next.cache) cache_ = next.cache;  // what the file now holds
    if (!crop) {
        rendered_ = std::make_shared<const Scene>(std::move(scene));
        accel_ = next.accel, radiosity_ = next.radiosity, waiting_ = std::move(next.waiting);
    }
}

void LightingSession::set_session_files(SessionAction action, RenderRequest& req, FrameState& previous, bool cached) const {
    // The session's deep buffer and cache, from memory when it holds them, else from its files.
    req.reuse_previous = action != SessionAction::Rasterize;
    if (action == SessionAction::Rasterize || !fs::exists(deep_path_))
        req.deep_out = deep_path_.string(), req.reuse_previous = false;
    else if (!previous.deep)
        req.deep_in = deep_path_.string();
    if (cached && action != SessionAction::Rasterize && fs::exists(cache_path_)) {
        // The session knows its cache's history: lights and materials may have changed since
        // it was gathered (a re-shade keeps its bounce light on purpose).
        if (!previous.cache) req.cache_in = cache_path_.string();
        req.force = true;
        req.cache_reuse = CacheReuse::Any;
        req.regather = action == SessionAction::Regather;
        req.reshade = action == SessionAction::Reshade;
    } else {
        previous.cache.reset();
    }
}

void LightingSession::run(SessionAction action, std::optional<std::array<int, 4>> crop) {
    std::string state = "done", message;
    json stats_json;
    {
        // Everything the render allocated is freed before the session says it is idle.
        Sink sink(*this);
        Stats stats;
        try {
            render_once(action, crop, stats, sink);
        } catch (const Cancelled&) {
            state = "cancelled";
        } catch (const std::exception& e) {
            state = "failed", message = e.what();  // the previous image and cache stay
        }
        stats_json = stats.to_json();
    }
    std::lock_guard lock(mutex_);
    stats_ = std::move(stats_json);
    state_ = state, message_ = message;
    running_ = false;
    idle_.notify_all();
}

json LightingSession::status() const {
    std::lock_guard lock(mutex_);
    json layers = json::array();
    for (const Layer& l : image_.layers) layers.push_back(l.name);
    return {{"state", state_},
            {"action", action_},
            {"message", message_},
            {"progress", {{"phase", phase_}, {"done", done_}, {"total", total_}}},
            {"stats", stats_},
            {"image", {{"version", version_}, {"width", image_.width}, {"height", image_.height}, {"layers", layers}}},
            {"pending", pending_ < 0 ? json(nullptr) : json(session_action_name(static_cast<SessionAction>(pending_)))},
            {"frame", frame_},
            {"shot", {{"animated", scene_.shot.animated}, {"first", scene_.shot.first}, {"last", scene_.shot.last}, {"fps", scene_.shot.fps}}},
            {"scene", options_.scene}};
}

LightingSession::Pixels LightingSession::pixels(const std::string& layer, float exposure) const {
    if (!std::isfinite(exposure) || std::abs(exposure) > 64) throw InputError("request", "exposure", "must be a number in [-64, 64]");
    std::lock_guard lock(mutex_);
    if (image_.layers.empty()) throw InputError("request", "image", "nothing rendered yet");
    const Layer* l = image_.find(layer);
    if (!l || l->channels.empty()) throw InputError("request", "layer", fmt::format("the image has no layer '{}'", layer));
    Pixels p;
    const std::vector<uint8_t> rgb = display_rgb8(image_, *l, exposure);
    p.rgba.resize(rgb.size() / 3 * 4);
    for (size_t i = 0; i < rgb.size() / 3; ++i)
        for (size_t c = 0; c < 4; ++c) p.rgba[4 * i + c] = static_cast<char>(c < 3 ? rgb[3 * i + c] : 255);
    p.width = image_.width, p.height = image_.height, p.version = version_;
    return p;
}

fs::path LightingSession::confined(const std::string& name, const std::string& what) const {
    if (name.empty() || name.size() > 1024 || name.find('\0') != std::string::npos)
        throw InputError("request", what, "a file name of 1..1024 characters is required");
    const fs::path p(name);
    if (p.is_absolute()) throw InputError("request", what, fmt::format("'{}' is absolute; give a name inside the scene or output folder", name));
    for (const auto& part : p)
        if (part == "..") throw InputError("request", what, fmt::format("'{}' climbs out with '..'", name));
    for (const fs::path& base : {out_dir_, scene_dir_}) {
        const fs::path full = fs::weakly_canonical(base / p);  // resolves symlinks that exist
        const auto rel = full.lexically_relative(base);
        if (!rel.empty() && *rel.begin() != ".." && (fs::exists(full) || base == out_dir_)) return full;
    }
    throw InputError("request", what, fmt::format("'{}' is not inside the scene or output folder", name));
}

json LightingSession::records(const std::string& file, size_t limit, std::optional<std::array<int, 4>> region) const {
    const fs::path path = file.empty() ? cache_path_ : confined(file, "file");
    CacheFile f = read_cache_file(path.string());
    const size_t all = f.records.size();
    if (region) {
        Camera camera;
        {
            std::lock_guard lock(mutex_);
            camera = scene_.camera;
        }
        const CameraRays rays(camera);
        std::erase_if(f.records, [&](const Record& r) { return !rays.projects_into(r.p, *region); });
    }
    const size_t n = std::min(limit, f.records.size());
    json p = json::array(), nn = json::array(), r = json::array(), e = json::array(), ao = json::array();
    // An even subset when the cache holds more than the view asked for.
    for (size_t k = 0; k < n; ++k) {
        const Record& rec = f.records[k * f.records.size() / std::max<size_t>(n, 1)];
        for (float v : {rec.p.x, rec.p.y, rec.p.z}) p.push_back(v);
        for (float v : {rec.n.x, rec.n.y, rec.n.z}) nn.push_back(v);
        r.push_back(rec.radius);
        for (float v : {rec.E.x, rec.E.y, rec.E.z}) e.push_back(v);
        ao.push_back(rec.ao);
    }
    return {{"file", path.filename().string()}, {"count", all}, {"in_region", f.records.size()}, {"fragment_records", f.fragment_records.size()},
            {"shown", n}, {"frame", f.info.frame}, {"p", p}, {"n", nn}, {"r", r}, {"E", e}, {"ao", ao}};
}

json LightingSession::cache_files() const {
    json out = json::array();
    std::error_code ec;
    for (const auto& e : fs::directory_iterator(out_dir_, ec))
        if (e.is_regular_file() && e.path().extension() == ".bic") out.push_back(e.path().filename().string());
    std::sort(out.begin(), out.end());
    return out;
}

json LightingSession::scene_view(size_t max_triangles) const {
    std::lock_guard lock(mutex_);
    const json values = param_values(scene_, ~0u);
    json cam = {{"position", values["camera.position"]}, {"look_at", values["camera.look_at"]}, {"up", values["camera.up"]},
                {"fov", scene_.camera.fov}, {"width", scene_.camera.width}, {"height", scene_.camera.height}};
    json lights = json::array();
    for (size_t i = 0; i < scene_.lights.size(); ++i) {
        const Light& l = scene_.lights[i];
        json j = {{"index", i}};
        if (l.type == LightType::Quad) {
            const Vec3 c = l.corner + (l.edge_u + l.edge_v) * 0.5f;
            j["position"] = {c.x, c.y, c.z}, j["key"] = fmt::format("lights.{}.corner", i);
            j["offset"] = {c.x - l.corner.x, c.y - l.corner.y, c.z - l.corner.z};
        } else if (l.type == LightType::Point || l.type == LightType::Spot) {
            j["position"] = {l.position.x, l.position.y, l.position.z}, j["key"] = fmt::format("lights.{}.position", i);
        } else if (l.type == LightType::Distant) {
            // A handle on the scene's bounding sphere, where the light comes from; dragging it
            // sets the direction towards the centre.
            const Bounds b = scene_.bounds();
            const Vec3 c = (b.lo + b.hi) * 0.5f, d = normalize(l.direction);
            const Vec3 h = c - d * (0.6f * length(b.hi - b.lo));
            j["position"] = {h.x, h.y, h.z}, j["key"] = fmt::format("lights.{}.direction", i);
            j["towards"] = {c.x, c.y, c.z};
        }
        lights.push_back(j);
    }
    size_t total = 0;
    for (const Object& o : scene_.objects) total += o.coarse.triangle_count();
    const size_t stride = std::max<size_t>(1, (total + max_triangles - 1) / std::max<size_t>(max_triangles, 1));
    json tris = json::array();
    size_t t = 0;
    for (const Object& o : scene_.objects)
        for (size_t i = 0; i < o.coarse.triangle_count(); ++i, ++t) {
            if (t % stride) continue;
            for (int k = 0; k < 3; ++k) {
                const Vec3& v = o.coarse.positions[o.coarse.indices[3 * i + static_cast<size_t>(k)]];
                for (float x : {v.x, v.y, v.z}) tris.push_back(x);
            }
        }
    const Bounds b = scene_.bounds();
    return {{"camera", cam}, {"lights", lights}, {"triangles", tris}, {"triangles_total", total},
            {"bounds", {{b.lo.x, b.lo.y, b.lo.z}, {b.hi.x, b.hi.y, b.hi.z}}}};
}

std::string LightingSession::save_scene(const std::string& name) const {
    // Beside the original: its mesh and texture paths are relative to that folder.
    if (name.empty() || name.size() > 255 || fs::path(name).filename() != name || name == "." || name == "..")
        throw InputError("request", "name", "a plain file name is required (the scene is saved beside the original)");
    const fs::path target = fs::weakly_canonical(scene_dir_ / name);
    if (target.parent_path() != scene_dir_) throw InputError("request", "name", "a symlink that leads out of the scene's folder");
    if (target.extension() != ".json") throw InputError("request", "name", "a scene file name ends in .json");
    if (fs::weakly_canonical(options_.scene) == target) throw InputError("request", "name", "would overwrite the original scene");
    json doc = parse_json_text(read_text_file(options_.scene), options_.scene);
    {
        std::lock_guard lock(mutex_);
        for (const Override& o : overrides_locked()) apply_override(doc, o);
    }
    const std::string text = doc.dump(2) + "\n";
    write_atomically(target, [&](const std::string& tmp) {
        std::ofstream out(tmp);
        out << text;
        if (!out.flush()) throw InputError(target.string(), "", "cannot write the scene");
    });
    return target.filename().string();
}

std::string LightingSession::save_cache(const std::string& name) const {
    const fs::path target = confined(name, "name");
    if (target.extension() != ".bic") throw InputError("request", "name", "a cache file name ends in .bic");
    if (!fs::exists(cache_path_)) throw InputError("request", "cache", "there is no cache yet (gather first)");
    if (target == cache_path_) return target.filename().string();
    CacheFile f = read_cache_file(cache_path_.string());
    write_cache_file(target.string(), f);
    return target.filename().string();
}

void LightingSession::load_cache(const std::string& file) {
    const fs::path from = confined(file, "file");
    CacheFile f = read_cache_file(from.string());  // refuses a bad file before anything changes
    std::lock_guard control(control_);
    stop();
    write_cache_file(cache_path_.string(), f);
    std::lock_guard lock(mutex_);
    cache_.reset();  // the next render reads the file
}

}  // namespace bounce
