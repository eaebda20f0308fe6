#include "bounce/cache/cache_identity.h"

#include <fmt/format.h>

#include "bounce/core/error.h"
#include "bounce/scene/params.h"

namespace bounce {

CacheFileInfo cache_file_info(const Scene& scene, int frame) {
    CacheFileInfo info;
    info.scene_fingerprint = scene.fingerprint({"objects", "materials", "lights"}, true);
    info.camera_fingerprint = scene.fingerprint({"camera"});
    info.geometry_fingerprint = scene.fingerprint({"objects"});
    info.parameters = param_values(scene, kCacheIdentity);
    info.frame = frame;
    return info;
}

LoadedCache load_cache(const std::string& path, const Scene& scene, bool force, CacheReuse reuse, IrradianceCache& cache,
                       const std::function<bool(const Record&)>& keep) {
    CacheFile f = read_cache_file(path);
    CacheFileInfo want = cache_file_info(scene, 0);
    // A lighter's re-shade after a light or material edit reuses the records on purpose (the
    // bounce light follows on a re-gather); other objects make them wrong.
    const bool same_objects = f.info.geometry_fingerprint != 0 && f.info.geometry_fingerprint == want.geometry_fingerprint;
    const bool other_scene = f.info.scene_fingerprint != want.scene_fingerprint;
    if (!force && other_scene && !same_objects)
        throw InputError(path, "scene_fingerprint",
                         "cache was made for another scene (its objects differ, or a file they read has changed since); "
                         "--force uses it anyway");
    if (!force && f.info.camera_fingerprint != want.camera_fingerprint)
        throw InputError(path, "camera_fingerprint",
                         "cache was made for another camera (its spacing is in that camera's pixels); --force uses it anyway");
    // AO and irradiance records hold different quantities: never mixed, whatever the flags.
    const std::string ao_key = "render.ao";
    if (f.info.parameters.contains(ao_key) && f.info.parameters[ao_key] != want.parameters[ao_key])
        throw InputError(path, "parameters/" + ao_key, scene.render.indirect.ao ? "cache holds irradiance, not AO" : "cache holds AO, not irradiance");
    LoadedCache out;
    out.other_lighting = other_scene && same_objects;
    out.differences = param_differences(f.info.parameters, want.parameters);
    if (!out.differences.empty() && reuse == CacheReuse::Strict)
        throw InputError(path, "parameters",
                         fmt::format("cache was gathered with other settings ({}); --regather starts over, "
                                     "--cache-reuse-any keeps its records",
                                     fmt::join(out.differences, "; ")));
    cache.set_luminance_floor(f.info.luminance_floor);
    for (const Record& r : f.records)
        if (!keep || keep(r)) {
            cache.insert_loaded(r);
            ++out.records;
        }
    for (const Record& r : f.fragment_records)
        if (!keep || keep(r)) {
            cache.insert_fragment_record(r);
            ++out.fragment_records;
        }
    return out;
}

}  // namespace bounce
