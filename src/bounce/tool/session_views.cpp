// What the lighting session shows and keeps (session.h): pixels of a layer, records and geometry
// for the 3D view, the scene and cache files saved to and loaded from its confined folders.
#include <fmt/format.h>

#include <algorithm>
#include <bit>
#include <cmath>
#include <fstream>

#include "bounce/cache/cache_file.h"
#include "bounce/cache/cache_identity.h"
#include "bounce/core/atomic_file.h"
#include "bounce/core/error.h"
#include "bounce/core/files.h"
#include "bounce/core/json_limits.h"
#include "bounce/config/params.h"
#include "bounce/scene/scene_load.h"
#include "bounce/tool/session.h"

namespace bounce {

namespace fs = std::filesystem;
using nlohmann::json;

Image LightingSession::image() const {
    std::lock_guard lock(mutex_);
    return image_;
}

LightingSession::Pixels LightingSession::pixels(const std::string& layer, float exposure) const {
    if (!std::isfinite(exposure) || std::abs(exposure) > 64) throw InputError("request", "exposure", "must be a number in [-64, 64]");
    std::lock_guard lock(mutex_);
    if (image_.layers.empty()) throw InputError("request", "image", "nothing rendered yet");
    const Layer* l = image_.find(layer);
    if (!l || l->channels.empty()) throw InputError("request", "layer", fmt::format("the image has no layer '{}'", layer));
    Pixels p;
    const std::vector<uint8_t> rgb = display_rgb8(image_, *l, exposure, *options_.display);
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
    if (p.is_absolute())
        throw InputError("request", what, fmt::format("'{}' is absolute; give a name inside the scene or output folder", name));
    for (const auto& part : p)
        if (part == "..") throw InputError("request", what, fmt::format("'{}' climbs out with '..'", name));
    for (const fs::path& base : {out_dir_, scene_dir_}) {
        const fs::path full = fs::weakly_canonical(base / p);  // resolves symlinks that exist
        const auto rel = full.lexically_relative(base);
        if (!rel.empty() && *rel.begin() != ".." && (fs::exists(full) || base == out_dir_)) return full;
    }
    throw InputError("request", what, fmt::format("'{}' is not inside the scene or output folder", name));
}

ViewArrays LightingSession::records(const std::string& file, size_t limit, std::optional<std::array<int, 4>> region) const {
    const fs::path path = file.empty() ? cache_path() : confined(file, "file");
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
    std::vector<float> p, nn, r, e, ao;
    // An even subset when the cache holds more than the view asked for.
    for (size_t k = 0; k < n; ++k) {
        const Record& rec = f.records[k * f.records.size() / std::max<size_t>(n, 1)];
        p.insert(p.end(), {rec.p.x, rec.p.y, rec.p.z});
        nn.insert(nn.end(), {rec.n.x, rec.n.y, rec.n.z});
        r.push_back(rec.radius);
        e.insert(e.end(), {rec.E.x, rec.E.y, rec.E.z});
        ao.push_back(rec.ao);
    }
    return {{{"file", path.filename().string()},
             {"count", all},
             {"in_region", f.records.size()},
             {"fragment_records", f.fragment_records.size()},
             {"shown", n},
             {"frame", f.info.frame}},
            {{"p", std::move(p)}, {"n", std::move(nn)}, {"r", std::move(r)}, {"E", std::move(e)}, {"ao", std::move(ao)}}};
}

json ViewArrays::to_json() const {
    json out = meta;
    for (const auto& [name, values] : arrays) out[name] = values;
    return out;
}

std::string ViewArrays::bytes() const {
    static_assert(std::endian::native == std::endian::little, "the page reads little-endian float32");
    std::string out;
    for (const auto& [name, values] : arrays) out.append(reinterpret_cast<const char*>(values.data()), values.size() * sizeof(float));
    return out;
}

json ViewArrays::layout() const {
    json out = meta;
    out["arrays"] = json::array();
    for (const auto& [name, values] : arrays) out["arrays"].push_back({name, values.size()});
    return out;
}

json LightingSession::cache_files() const {
    json out = json::array();
    std::error_code ec;
    for (const auto& e : fs::directory_iterator(out_dir_, ec))
        if (e.is_regular_file() && e.path().extension() == ".bic") out.push_back(e.path().filename().string());
    std::sort(out.begin(), out.end());
    return out;
}

ViewArrays LightingSession::scene_view(size_t max_triangles) const {
    std::lock_guard lock(mutex_);
    const json values = param_values(scene_, ~0u);
    json cam = {{"position", values["camera.position"]},
                {"look_at", values["camera.look_at"]},
                {"up", values["camera.up"]},
                {"fov", scene_.camera.fov},
                {"width", scene_.camera.width},
                {"height", scene_.camera.height}};
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
    for (const Object& o : scene_.objects) total += o.placed() ? o.coarse_mesh().triangle_count() : 0;
    const size_t stride = std::max<size_t>(1, (total + max_triangles - 1) / std::max<size_t>(max_triangles, 1));
    std::vector<float> tris;
    size_t t = 0;
    for (const Object& o : scene_.objects)
        for (uint32_t i = 0; o.placed() && i < o.coarse_mesh().triangle_count(); ++i, ++t) {
            if (t % stride) continue;
            for (const Vec3& v : triangle_vertices(o.coarse_mesh(), o.to_world(), i)) tris.insert(tris.end(), {v.x, v.y, v.z});
        }
    const Bounds b = scene_.bounds();
    return {
        {{"camera", cam}, {"lights", lights}, {"triangles_total", total}, {"bounds", {{b.lo.x, b.lo.y, b.lo.z}, {b.hi.x, b.hi.y, b.hi.z}}}},
        {{"triangles", std::move(tris)}}};
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
    const fs::path current = cache_path();
    if (!fs::exists(current)) throw InputError("request", "cache", "there is no cache yet (gather first)");
    if (target == current) return target.filename().string();
    CacheFile f = read_cache_file(current.string());
    write_cache_file(target.string(), f);
    return target.filename().string();
}

void LightingSession::load_cache(const std::string& file) {
    const fs::path from = confined(file, "file");
    CacheFile f = read_cache_file(from.string());  // refuses a bad file before anything changes
    std::lock_guard control(control_);
    stop();
    std::lock_guard lock(mutex_);
    adopt_cache_locked(f, file);
    write_cache_file(cache_path_locked().string(), f);
    last_.cache.reset();  // the next render reads the file
    // The image shown is not the loaded cache's.
    pending_ = std::max(pending_, static_cast<int>(SessionAction::Reshade));
}

void LightingSession::adopt_cache_locked(const CacheFile& f, const std::string& name) {
    // The cache's identity against the session's scene, as the CLI checks it: records of other
    // objects or another camera do not fit; other lights or materials make its bounce light
    // stale (shown until a re-gather), unless only colours and intensities differ and the
    // records keep their light parts (then they take the session's exactly).
    const CacheFileInfo want = cache_file_info(scene_, 0);
    const CacheFit fit = cache_fit(f, want, scene_.lights.size());
    if (fit == CacheFit::OtherObjects)
        throw InputError(name, "scene_fingerprint",
                         "the cache was gathered on other objects (or a file they read has changed since): Re-gather instead");
    if (f.info.camera_fingerprint != want.camera_fingerprint)
        throw InputError(name, "camera_fingerprint",
                         "the cache was gathered for another camera (its spacing is in that camera's pixels): Re-gather instead");
    bounce_stale_ = fit == CacheFit::OtherLighting;
    file_parts_lights_ = keeps_light_parts(f, scene_.lights.size()) ? scene_.lights.size() : 0;
}

}  // namespace bounce
