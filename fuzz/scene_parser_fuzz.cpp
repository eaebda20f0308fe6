// libFuzzer target: the JSON scene parser must turn any text into a scene or an InputError.
// Mesh files named by the input are not loaded from outside the corpus folder's reach: the
// fuzzer runs in an empty working directory.
#include <cstddef>
#include <cstdint>
#include <string>

#include "bounce/core/error.h"
#include "bounce/scene/scene_load.h"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
    if (size > 1 << 16) return 0;
    std::string text(reinterpret_cast<const char*>(data), size);
    // Keep sphere tessellation small so a fuzz run measures the parser, not icosphere building.
    if (text.find("subdivisions") != std::string::npos) return 0;
    try {
        // Fur: ~27k strands at most, so growing it stays quick.
        bounce::load_scene_text(text, "fuzz.json", {"render.memory_budget=0.01"});
    } catch (const bounce::InputError&) {
    }
    return 0;
}
