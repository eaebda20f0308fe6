// Which scene and settings a cache file belongs to, and loading one into a cache with the
// checks that keep a lighter from reusing records made for something else.
#pragma once

#include <cstdint>
#include <functional>
#include <string>
#include <vector>

#include "bounce/cache/cache_file.h"
#include "bounce/cache/irradiance_cache.h"
#include "bounce/scene/scene.h"

namespace bounce {

/// The header a cache made for `scene` carries: scene and camera fingerprints and, as
/// `parameters`, every parameter of the table whose identity includes the cache.
CacheFileInfo cache_file_info(const Scene& scene, int frame);

enum class CacheReuse {
    Strict,  ///< refuse a cache whose record-changing settings differ
    Any,     ///< keep its records whatever settings made them (gather only where they miss)
};

/// How a cache file's records fit a scene, best first.
enum class CacheFit : uint8_t {
    Same,           ///< made for these objects, lights and materials
    Rescaled,       ///< only the lights' colours or intensities differ, and every record keeps its
                    ///< light parts: loaded at the scene's scales, exactly
    OtherLighting,  ///< the same objects, other lights or materials: the records hold that bounce light
    OtherObjects,   ///< other objects (or a file they read has changed): the records do not fit
};
/// How `file` fits a scene whose cache_file_info is `want` and which has `lights` lights.
CacheFit cache_fit(const CacheFile& file, const CacheFileInfo& want, size_t lights);

struct LoadedCache {
    size_t records = 0;
    size_t fragment_records = 0;           ///< per-fragment refinement's records
    std::vector<std::string> differences;  ///< "key: was -> now", for the settings that differ
    /// Same objects, other lights or materials: the records hold the bounce light of those.
    bool other_lighting = false;
    /// Only the lights' colours or intensities differed: the records' parts took the scene's
    /// exactly (not other_lighting).
    bool rescaled = false;
};

/// Loads `path` into `cache`. Refuses (InputError, exit 2) a cache made for other objects or
/// another camera unless `force` (other lights or materials only: loaded, `other_lighting`), and one whose record-changing settings differ
/// unless reuse is Any, naming each differing key with both values. Records for which `keep` is false are left out.
LoadedCache load_cache(const std::string& path, const Scene& scene, bool force, CacheReuse reuse, IrradianceCache& cache,
                       const std::function<bool(const Record&)>& keep = {});

}  // namespace bounce
