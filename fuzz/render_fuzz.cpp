// libFuzzer target: past the parser. An input is a JSON scene, optionally followed by a line
// "--cache--" and the bytes of a cache file; it is rendered at 16x16 (one subsample, few
// rays, one thread) through the irradiance cache started from that cache. Any input must end
// in an image or an InputError: never a crash, an abort inside Embree or a hang.
#include <unistd.h>

#include <cstddef>
#include <cstdint>
#include <fstream>
#include <string>

#include "bounce/core/error.h"
#include "bounce/render/render.h"
#include "bounce/scene/scene_load.h"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
    if (size > 1 << 16) return 0;
    std::string text(reinterpret_cast<const char*>(data), size);
    if (text.find("subdivisions") != std::string::npos) return 0;  // keep tessellation small
    std::string cache_bytes;
    const std::string mark = "\n--cache--\n";
    if (auto at = text.find(mark); at != std::string::npos) {
        cache_bytes = text.substr(at + mark.size());
        text.resize(at);
    }
    const std::string cache_path = "render_fuzz." + std::to_string(::getpid()) + ".bic";
    try {
        bounce::Scene scene = bounce::load_scene_text(text, "fuzz.json",
                                                      {"camera.resolution=[16,16]", "render.spp=1", "render.rays=16", "render.gi=\"cache\"",
                                                       "render.threads=1", "render.light_samples=1", "render.radiosity_light_samples=1",
                                                       "render.crop=[0,0,0,0]", "render.memory_budget=0.01"});  // fur: ~27k strands at most
        bounce::RenderRequest request;
        if (!cache_bytes.empty()) {
            std::ofstream(cache_path, std::ios::binary) << cache_bytes;
            request.cache_in = cache_path;
            request.force = true;
            request.cache_reuse = bounce::CacheReuse::Any;
        }
        bounce::Stats stats;
        bounce::render(scene, request, stats, nullptr);
    } catch (const bounce::InputError&) {}
    ::unlink(cache_path.c_str());
    return 0;
}
