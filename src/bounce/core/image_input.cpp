#include "bounce/core/image_input.h"

#include <openexr.h>

#include <algorithm>
#include <array>
#include <fstream>

#include "bounce/core/files.h"

namespace bounce {

namespace {

/// The first error OpenEXR reports while parsing (the most specific), kept to one printable line.
void keep_first_error(exr_const_context_t ctx, exr_result_t, const char* message) {
    std::string* first = nullptr;
    if (exr_get_user_data(ctx, reinterpret_cast<void**>(&first)) != EXR_ERR_SUCCESS || !first || !first->empty()) return;
    *first = message ? message : "";
    // A damaged header's names are arbitrary bytes.
    std::replace_if(
        first->begin(), first->end(), [](char c) { return c < 0x20 || c > 0x7e; }, '?');
    if (first->size() > 200) first->resize(200);
}

bool is_exr(const std::string& path) {
    std::array<unsigned char, 4> magic{};
    std::ifstream in(path, std::ios::binary);
    in.read(reinterpret_cast<char*>(magic.data()), magic.size());
    return in && magic == std::array<unsigned char, 4>{0x76, 0x2f, 0x31, 0x01};
}

/// Why OpenEXR's core library rejects the headers of the OpenEXR file `path`; empty when it
/// accepts them or the file is not OpenEXR (by its first four bytes).
std::string exr_header_problem(const std::string& path) {
    if (!is_exr(path)) return "";
    std::string first;
    exr_context_initializer_t init = EXR_DEFAULT_CONTEXT_INITIALIZER;
    init.error_handler_fn = keep_first_error;
    init.user_data = &first;
    exr_context_t ctx = nullptr;
    const exr_result_t rv = exr_start_read(&ctx, path.c_str(), &init);
    exr_finish(&ctx);
    if (rv == EXR_ERR_SUCCESS) return "";
    return "damaged OpenEXR header: " + (first.empty() ? std::string(exr_get_default_error_message(rv)) : first);
}

}  // namespace

std::unique_ptr<OIIO::ImageInput> open_image(const std::string& path, std::string& error) {
    error = not_a_regular_file(path);
    if (error.empty()) error = exr_header_problem(path);
    if (!error.empty()) return nullptr;
    auto in = OIIO::ImageInput::open(path);
    if (!in) error = OIIO::geterror();
    return in;
}

}  // namespace bounce
