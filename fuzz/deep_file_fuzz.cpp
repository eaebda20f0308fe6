// libFuzzer target (issue 29): deep files. The first byte chooses the mode:
//  - 0: the rest is a deep EXR's bytes, read with read_deep (headers, channels, counts);
//  - else: the rest is a list of edits (fragment, field, 4 value bytes) applied to a valid
//    deep buffer of a small scene, which is written and then rendered at 16x16 through the
//    irradiance cache from it, as --deep-in would: crafted values (3e38 positions, NaN normals,
//    zero normals) must end in an InputError, never a crash, an abort in Embree or NaN pixels.
#include <unistd.h>

#include <cmath>
#include <cstddef>
#include <cstdint>
#include <cstring>
#include <fstream>
#include <string>

#include "bounce/core/error.h"
#include "bounce/render/render.h"
#include "bounce/scene/scene_load.h"

namespace {

const char* const kScene = R"({"camera": {"position": [0, 1, 5], "look_at": [0, 0, 0], "fov": 40, "resolution": [16, 16]},
 "render": {"spp": 2, "gi": "cache", "rays": 16, "threads": 1, "light_samples": 1},
 "lights": [{"type": "point", "position": [0, 3, 0], "color": 5}, {"type": "sky", "color": 0.2}],
 "objects": [{"type": "quad", "vertices": [[-2, 0, -2], [2, 0, -2], [2, 0, 2], [-2, 0, 2]]},
             {"type": "sphere", "center": [0, 0.5, 0], "radius": 0.5}]})";

const bounce::Scene& scene() {
    static const bounce::Scene s = bounce::load_scene_text(kScene, "fuzz.json");
    return s;
}

/// The scene's own deep buffer, traced once.
const bounce::DeepBuffer& good_deep(const std::string& path) {
    static const bounce::DeepBuffer deep = [&] {
        bounce::RenderRequest req;
        req.deep_out = path;
        bounce::Stats stats;
        bounce::render(scene(), req, stats, nullptr);
        return bounce::read_deep(path);
    }();
    return deep;
}

/// Field `which` of fragment `f` as a float slot to overwrite.
float* field(bounce::Fragment& f, uint8_t which) {
    float* slots[] = {&f.p.x,  &f.p.y,   &f.n.x,    &f.n.z,       &f.ng.y,      &f.p_base.x, &f.n_base.y,
                      &f.uv.x, &f.depth, &f.weight, &f.footprint, &f.tangent.x, &f.strand_v};
    return slots[which % (sizeof(slots) / sizeof(slots[0]))];
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
    if (size < 1 || size > 1 << 20) return 0;
    const std::string path = "deep_fuzz." + std::to_string(::getpid()) + ".exr";
    try {
        if (data[0] == 0) {
            std::ofstream(path, std::ios::binary).write(reinterpret_cast<const char*>(data + 1), static_cast<std::streamsize>(size - 1));
            bounce::read_deep(path);
        } else {
            bounce::DeepBuffer deep = good_deep(path);
            for (size_t i = 1; i + 6 <= size; i += 6) {
                uint16_t which = 0;
                std::memcpy(&which, data + i, 2);
                if (deep.fragments.empty()) break;
                bounce::Fragment& f = deep.fragments[which % deep.fragments.size()];
                std::memcpy(field(f, data[i + 2]), data + i + 2, 4);
            }
            bounce::write_deep(path, deep);
            bounce::RenderRequest req;
            req.deep_in = path;
            bounce::Stats stats;
            const bounce::RenderResult r = bounce::render(scene(), req, stats, nullptr);
            for (float v : r.image.find("beauty")->data)
                if (!std::isfinite(v)) __builtin_trap();  // accepted values must shade to a finite image
        }
    } catch (const bounce::InputError&) {}
    ::unlink(path.c_str());
    return 0;
}
