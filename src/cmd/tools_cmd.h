// `bounce bake-ao`, `bounce compare` and `bounce cache info|merge|filter|export`.
#pragma once

#include <optional>
#include <string>
#include <vector>

namespace bounce {

struct BakeAoArgs {
    std::string scene, object, output;
    int resolution = 1024, rays = 256;
    std::optional<double> distance;  ///< not given: 4x the displacement bound (double: 1e39 is shown as given, not as inf)
};

struct InfoArgs {
    std::string scene;
};

struct CompareArgs {
    std::string test, reference, layer, diff;
    bool json = false;
    bool sequence = false;  ///< test and reference are #### frame patterns
    std::string frames;     ///< with sequence: FIRST-LAST
    std::string strip;      ///< with sequence: a PNG strip of the test's frames and record dots
};

struct CacheArgs {
    std::vector<std::string> inputs;
    std::string output, box, sphere;
    std::vector<std::string> where;
    bool json = false, remove = false, force = false;
};

/// `bounce bake-ao`: an object's occlusion by its own fine detail, in its uv space (EXR, one
/// channel), for a material's ao_texture.
int run_bake_ao(const BakeAoArgs& a);
/// `bounce info SCENE`: per material what was read and what was not, and the files' unread features.
int run_info(const InfoArgs& a);
int run_compare(const CompareArgs& a);
int run_cache_info(const CacheArgs& a);
int run_cache_merge(const CacheArgs& a);
int run_cache_filter(const CacheArgs& a);
int run_cache_export(const CacheArgs& a);

}  // namespace bounce
