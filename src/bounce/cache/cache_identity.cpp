#include "bounce/cache/cache_identity.h"

#include <fmt/format.h>

#include "bounce/core/error.h"
#include "bounce/lighting/lighting.h"
#include "bounce/config/params.h"

namespace bounce {

CacheFileInfo cache_file_info(const Scene& scene, int frame) {
    CacheFileInfo info;
    info.scene_fingerprint = scene.fingerprint({"objects", "materials", "lights"}, true);
    info.camera_fingerprint = scene.fingerprint({"camera"});
    info.geometry_fingerprint = scene.fingerprint({"objects"});
    info.unscaled_fingerprint = scene.unscaled_fingerprint();
    info.parameters = param_values(scene, kCacheIdentity);
    info.frame = frame;
    return info;
}

CacheFit cache_fit(const CacheFile& file, const CacheFileInfo& want, size_t lights) {
    if (file.info.scene_fingerprint == want.scene_fingerprint) return CacheFit::Same;
    if (file.info.geometry_fingerprint == 0 || file.info.geometry_fingerprint != want.geometry_fingerprint) return CacheFit::OtherObjects;
    if (file.info.unscaled_fingerprint != 0 && file.info.unscaled_fingerprint == want.unscaled_fingerprint &&
        keeps_light_parts(file, lights))
        return CacheFit::Rescaled;
    return CacheFit::OtherLighting;
}

LoadedCache load_cache(const std::string& path, const Scene& scene, bool force, CacheReuse reuse, IrradianceCache& cache,
                       const std::function<bool(const Record&)>& keep) {
    CacheFile f = read_cache_file(path);
    CacheFileInfo want = cache_file_info(scene, 0);
    // A lighter's re-shade after a light or material edit reuses the records on purpose (the
    // bounce light follows on a re-gather); other objects make them wrong.
    const CacheFit fit = cache_fit(f, want, scene.lights.size());
    if (!force && fit == CacheFit::OtherObjects)
        throw InputError(path, "scene_fingerprint",
                         "cache was made for another scene (its objects differ, or a file they read has changed since); "
                         "--force uses it anyway");
    if (!force && f.info.camera_fingerprint != want.camera_fingerprint)
        throw InputError(path, "camera_fingerprint",
                         "cache was made for another camera (its spacing is in that camera's pixels); --force uses it anyway");
    // AO and irradiance records hold different quantities: never mixed, whatever the flags.
    const std::string ao_key = "render.ao";
    if (f.info.parameters.contains(ao_key) && f.info.parameters[ao_key] != want.parameters[ao_key])
        throw InputError(path, "parameters/" + ao_key,
                         want.parameters[ao_key] == true ? "cache holds irradiance, not AO" : "cache holds AO, not irradiance");
    LoadedCache out;
    // Records that keep a part per light (scales factored out) take this scene's colours and
    // intensities exactly when nothing else about the lights and materials differs.
    out.rescaled = fit == CacheFit::Rescaled;
    out.other_lighting = fit == CacheFit::OtherLighting;
    out.differences = param_differences(f.info.parameters, want.parameters);
    if (!out.differences.empty() && reuse == CacheReuse::Strict)
        throw InputError(path, "parameters",
                         fmt::format("cache was gathered with other settings ({}); --regather starts over, "
                                     "--cache-reuse-any keeps its records",
                                     fmt::join(out.differences, "; ")));
    cache.set_luminance_floor(f.info.luminance_floor);
    const std::vector<Color> scales = light_scales(scene);
    const auto scaled = [&](Record r) {
        if (r.parts && r.parts->light.size() == scales.size())
            apply_light_scales(r, scales);
        else
            r.parts.reset();
        return r;
    };
    for (const Record& r : f.records)
        if (!keep || keep(r)) {
            cache.insert_loaded(scaled(r));
            ++out.records;
        }
    for (const Record& r : f.fragment_records)
        if (!keep || keep(r)) {
            cache.insert_fragment_record(scaled(r));
            ++out.fragment_records;
        }
    return out;
}

}  // namespace bounce
