// libFuzzer target: the JSON scene parser must turn any text into a scene or an InputError.
// Structure-aware (issue 29): the first byte chooses how the rest is grown before parsing — as
// it is; wrapped in up to a million levels of arrays or objects; given an array of up to 2.5
// million elements; or with every number replaced by a hostile one (1e39, 1e400, -0, 2^64,
// denormals) — so inputs reach the shapes a 64 KB cap on plain text never could.
// Mesh files named by the input are not loaded from outside the corpus folder's reach: the
// fuzzer runs in an empty working directory.
#include <cctype>
#include <cstddef>
#include <cstdint>
#include <string>

#include "bounce/core/error.h"
#include "bounce/scene/scene_load.h"

namespace {

/// `text` with `value` added as the "description" of its top-level object (or as it is).
std::string with_description(const std::string& text, const std::string& value) {
    const auto brace = text.find('{');
    if (brace == std::string::npos) return value;
    return text.substr(0, brace + 1) + "\"description\": " + value + "," + text.substr(brace + 1);
}

std::string hostile_numbers(const std::string& text, uint8_t pick) {
    static const char* const numbers[] = {"1e39",       "-1e39",  "1e308",        "1e400",       "-0",  "18446744073709551616",
                                          "4294967296", "1e-320", "3.4028236e38", "-2147483649", "0.5", "1e18"};
    std::string out;
    size_t k = pick;
    for (size_t i = 0; i < text.size();) {
        const bool starts = (std::isdigit(static_cast<unsigned char>(text[i])) || text[i] == '-') &&
                            (i == 0 || !std::isalnum(static_cast<unsigned char>(text[i - 1])));
        if (!starts) {
            out += text[i++];
            continue;
        }
        size_t j = i + 1;
        while (j < text.size() &&
               (std::isdigit(static_cast<unsigned char>(text[j])) || std::string(".eE+-").find(text[j]) != std::string::npos))
            ++j;
        out += numbers[k++ % (sizeof(numbers) / sizeof(numbers[0]))];
        i = j;
    }
    return out;
}

std::string grow(const uint8_t* data, size_t size) {
    if (size < 2) return std::string(reinterpret_cast<const char*>(data), size);
    const uint8_t op = data[0] % 4, param = data[1];
    const std::string rest(reinterpret_cast<const char*>(data + 2), size - 2);
    switch (op) {
        case 1: {
            const size_t depth = (static_cast<size_t>(param) + 1) * 4096;  // up to ~10^6 levels
            const bool objects = param & 1;
            std::string nest;
            for (size_t i = 0; i < depth; ++i) nest += objects ? "{\"a\":" : "[";
            nest += "1";
            nest.append(depth, objects ? '}' : ']');
            return with_description(rest, nest);
        }
        case 2: {
            const size_t count = (static_cast<size_t>(param) + 1) * 10000;
            std::string array = "[0";
            for (size_t i = 1; i < count; ++i) array += ",0";
            return with_description(rest, array + "]");
        }
        case 3:
            return hostile_numbers(rest, param);
        default:
            return rest;
    }
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
    if (size > 1 << 20) return 0;
    std::string text = grow(data, size);
    // Keep sphere tessellation small so a fuzz run measures the parser, not icosphere building.
    if (text.find("subdivisions") != std::string::npos) return 0;
    try {
        // Fur: ~27k strands at most, so growing it stays quick.
        bounce::load_scene_text(text, "fuzz.json", {"render.memory_budget=0.01"});
    } catch (const bounce::InputError&) {}
    return 0;
}
