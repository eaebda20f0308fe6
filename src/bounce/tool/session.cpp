#include "bounce/tool/session.h"

#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <functional>
#include <fstream>

#include "bounce/cache/cache_file.h"
#include "bounce/cache/cache_identity.h"
#include "bounce/core/json_limits.h"
#include "bounce/core/atomic_file.h"
#include "bounce/core/error.h"
#include "bounce/core/files.h"
#include "bounce/core/stats.h"
#include "bounce/deep/deep_buffer.h"
#include "bounce/render/frame.h"
#include "bounce/render/render.h"
#include "bounce/scene/item_readers.h"
#include "bounce/config/params.h"
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

const char* session_state_name(SessionState s) {
    switch (s) {
        case SessionState::Idle:
            return "idle";
        case SessionState::Running:
            return "running";
        case SessionState::Done:
            return "done";
        case SessionState::Cancelled:
            return "cancelled";
        case SessionState::Failed:
            return "failed";
    }
    return "?";
}

const char* session_action_name(SessionAction a) {
    switch (a) {
        case SessionAction::Reshade:
            return "reshade";
        case SessionAction::Regather:
            return "regather";
        case SessionAction::Rasterize:
            return "rasterize";
        case SessionAction::Frame:
            return "frame";
    }
    return "?";
}

namespace {

/// An edit request as an override: its errors name the tool's edit, not the command line.
Override edit_override(const std::string& key, const json& value) {
    const std::string assignment = key + "=" + value.dump();
    Override o{assignment, "edit " + assignment, "lighting tool"};
    o.scene_relative = true;  // the edit is saved into the scene: its folders are the scene's
    return o;
}

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

/// Light and material rows of the effective scene description: every numeric key the item
/// reads, with the scene's value or, where the scene leaves it out, the default.
void add_scene_rows(const json& description, json& rows) {
    auto add = [&](const std::string& stage, const std::string& prefix, const json& item, const json& defaults, const std::string& doc) {
        json keys = defaults;
        for (const auto& [k, v] : item.items())
            if (editable(v)) keys[k] = v;
        for (const auto& [k, v] : keys.items())
            rows.push_back({{"key", prefix + k},
                            {"stage", stage},
                            {"value", v},
                            {"default", defaults.contains(k) ? defaults[k] : json(nullptr)},
                            {"unit", ""},
                            {"range", nullptr},
                            {"doc", doc},
                            {"needs", "reshade"}});
    };
    if (description.contains("lights") && description["lights"].is_array())
        for (size_t i = 0; i < description["lights"].size(); ++i) {
            const json& l = description["lights"][i];
            if (!l.is_object()) continue;
            const std::string type = l.value("type", "?");
            add("light", fmt::format("lights.{}.", i), l, light_defaults(type),
                fmt::format("{} light {}; a re-gather updates its bounce light", type, i));
        }
    if (description.contains("materials") && description["materials"].is_object())
        for (const auto& [name, m] : description["materials"].items())
            if (m.is_object())
                add("material", "materials." + name + ".", m, material_defaults(),
                    "material " + name + "; a re-gather updates its bounce light");
}

}  // namespace

LightingSession::LightingSession(SessionOptions options) : options_(std::move(options)) {
    LoadOptions first;
    first.resources = options_.resources;
    scene_ = load_scene(options_.scene, {}, first);
    frame_ = scene_.frame;
    scene_dir_ = fs::weakly_canonical(fs::absolute(options_.scene)).parent_path();
    std::error_code ec;
    fs::create_directories(options_.out_dir, ec);
    if (ec || !fs::is_directory(options_.out_dir))
        throw InputError(options_.out_dir, "", "cannot create the output folder (" + ec.message() + ")");
    out_dir_ = fs::canonical(options_.out_dir);
    deep_path_ = out_dir_ / "session.deep.exr";
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
    if (options_.default_to_cache && param_value(scene_, "render.gi") == "none" && param_value(scene_, "render.ao") == false)
        edit("render.gi", "cache");
    const json& render_keys = scene_.description.contains("render") ? scene_.description["render"] : json();
    if (options_.default_to_light_parts && !(render_keys.is_object() && render_keys.contains("light_parts")))
        edit("render.light_parts", true);
    copy_in(options_.deep_in, deep_path_, [&](const std::string& f) { validate_deep_for_scene(read_deep(f), scene_, f); });
    copy_in(options_.cache_in, cache_path_locked(), [&](const std::string& f) { adopt_cache_locked(read_cache_file(f), f); });
    // Nothing rendered yet: the first render makes what the session has no file of.
    const bool cached = param_value(scene_, "render.gi") == "cache";
    pending_ = static_cast<int>(!fs::exists(deep_path_)                      ? SessionAction::Rasterize
                                : cached && !fs::exists(cache_path_locked()) ? SessionAction::Regather
                                                                             : SessionAction::Reshade);
}

LightingSession::~LightingSession() {
    std::lock_guard control(control_);
    stop();
    if (worker_.joinable()) worker_.join();
}

std::vector<Override> LightingSession::overrides_locked() const {
    std::vector<Override> out;
    for (const auto& key : edit_order_) out.push_back(edit_override(key, edits_.at(key)));
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

namespace {

/// Whether `key` is a light's colour or intensity ("lights.N.color"): what records with light
/// parts rescale exactly.
bool light_scale_key(const std::string& key) {
    if (!key.starts_with("lights.")) return false;
    return key.ends_with(".color") || key.ends_with(".intensity");
}

/// Whether an edit of `key` changes the light that bounces (lights, and materials but for the
/// keys that only change how a surface reflects light to the camera; Scene::fingerprint).
bool changes_bounce_light(const std::string& key) {
    if (key == "lights" || key.starts_with("lights.")) return true;
    if (!key.starts_with("materials.")) return false;
    for (const std::string& own : surface_shading_keys())
        if (key.ends_with("." + own)) return false;
    return true;
}

}  // namespace

json LightingSession::edit(const std::string& key, const json& value, const std::string& cli_origin) {
    if (key.empty() || key.size() > 256) throw InputError("request", "key", "a parameter key of 1..256 characters is required");
    std::lock_guard lock(mutex_);
    std::vector<Override> o = overrides_locked();
    o.push_back(cli_origin.empty() ? edit_override(key, value) : Override(key + "=" + value.dump(), cli_origin));
    LoadOptions at;
    at.frame = frame_;
    at.resources = options_.resources;
    if (cli_origin.empty()) at.check_path = edit_path_check(key);
    Scene s = load_scene(options_.scene, o, at);  // throws with the file and place on a bad value
    const Param* p = find_param(scene_params(), key);
    SessionAction needs = needs_for(p ? p->identity : kImageOnly);
    // A key the parameter table does not list (an object's mesh file or subdivision, an
    // instance, a material's cutout) that changes what the camera sees needs a new deep file:
    // the old one is another scene's. Lights and other material keys are re-shaded (or
    // re-gathered) over it.
    if (!p && !key.starts_with("lights") && s.visibility_fingerprint() != scene_.visibility_fingerprint()) needs = SessionAction::Rasterize;
    if (!edits_.count(key)) edit_order_.push_back(key);
    edits_[key] = value;
    ++edit_count_;
    scene_ = std::move(s);
    // Lights and materials: a re-shade shows them (the bounce light follows on a re-gather).
    pending_ = std::max(pending_, static_cast<int>(needs));
    // Records with light parts take a light's new colour or intensity on the re-shade, exactly
    // (a mesh light's is its material's emission: not a light key).
    const size_t lights = scene_.lights.size();
    const bool parts = last_.cache ? last_.cache->has_light_parts(lights) : file_parts_lights_ == lights;
    const bool rescaled = light_scale_key(key) && param_value(scene_, "render.light_parts") == true && parts;
    if (changes_bounce_light(key) && !rescaled) bounce_stale_ = true;
    return {{"key", key}, {"value", value}, {"needs", session_action_name(needs)}};
}

std::function<void(const std::string&, const std::string&)> LightingSession::edit_path_check(const std::string& key) const {
    std::string ptr = "/" + key;
    std::replace(ptr.begin(), ptr.end(), '.', '/');
    return [this, key, ptr](const std::string& path, const std::string& pointer) {
        // What the edit set: the key itself or anything under it (an edit of a whole object).
        if (pointer != ptr && !pointer.starts_with(ptr + "/")) return;
        if (inside(path, scene_dir_) || inside(path, out_dir_)) return;
        throw InputError("lighting tool", "edit " + key + " (" + pointer + ")",
                         fmt::format("'{}' is outside the scene's folder and the output folder", path));
    };
}

json LightingSession::set_frame(double frame) {
    {
        std::lock_guard lock(mutex_);
        if (!scene_.shot.animated) throw InputError("request", "frame", "the scene has no shot (no \"animation\" block)");
        if (!std::isfinite(frame) || !scene_.shot.contains(frame)) throw InputError("request", "frame", scene_.shot.outside(frame));
        // A shot steps in whole frames, as --frames does (each frame's cache is named by it).
        if (frame != std::floor(frame)) throw InputError("request", "frame", fmt::format("{:g} is not a whole frame", frame));
        frame_asked_ = static_cast<int>(frame);
        ++edit_count_;
    }
    start(SessionAction::Frame);  // plans the frames to render (start_replay_locked)
    std::lock_guard lock(mutex_);
    const Replay replay = replay_;
    return {{"frame", frame}, {"from", replay.first}};
}

void LightingSession::start_replay_locked() {
    const int target = frame_asked_;
    // Forward from the sequence's last frame: the frames in between, then this one. Back
    // (or before any frame): the sequence again from its first frame, which no state kept in
    // memory could skip (a frame's records depend on every frame before it).
    if (sequence_frame_ && target > *sequence_frame_) {
        replay_ = {*sequence_frame_ + 1, *sequence_frame_ + 1, target, false};
    } else {
        const int first = std::min(sequence_frame_ ? sequence_first_ : target, target);
        replay_ = {first, first, target, true};
    }
}

fs::path LightingSession::cache_path() const {
    std::lock_guard lock(mutex_);
    return cache_path_locked();
}

fs::path LightingSession::cache_path_locked() const {
    if (!scene_.shot.animated) return out_dir_ / "session.bic";
    return out_dir_ / fmt::format("session.{:04}.bic", static_cast<long>(frame_));
}

SessionAction LightingSession::pending() const {
    std::lock_guard lock(mutex_);
    return static_cast<SessionAction>(std::max(pending_, 0));
}

json LightingSession::status() const {
    std::lock_guard lock(mutex_);
    json layers = json::array();
    for (const Layer& l : image_.layers) layers.push_back(l.name);
    return {
        {"state", session_state_name(state_)},
        {"serial", ++status_serial_},
        {"edits", edit_count_},
        {"action", action_ ? json(session_action_name(*action_)) : json(nullptr)},
        {"message", message_},
        {"progress", {{"phase", phase_}, {"done", done_}, {"total", total_}}},
        {"stats", stats_},
        {"image", {{"version", version_}, {"width", image_.width}, {"height", image_.height}, {"layers", layers}}},
        {"pending", pending_ < 0 ? json(nullptr) : json(session_action_name(static_cast<SessionAction>(pending_)))},
        {"bounce_stale", bounce_stale_},
        {"frame", frame_},
        {"replay", running_ && action_ == SessionAction::Frame ? json{{"from", replay_.first}, {"to", replay_.target}} : json(nullptr)},
        {"shot", {{"animated", scene_.shot.animated}, {"first", scene_.shot.first}, {"last", scene_.shot.last}, {"fps", scene_.shot.fps}}},
        {"scene", options_.scene},
        {"unread", scene_.unread}};
}

}  // namespace bounce
