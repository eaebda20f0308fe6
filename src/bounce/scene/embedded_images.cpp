#include "bounce/scene/embedded_images.h"

#include <OpenImageIO/hash.h>
#include <assimp/texture.h>
#include <fmt/format.h>

#include <cctype>
#include <filesystem>
#include <fstream>
#include <system_error>

#include "bounce/core/atomic_file.h"
#include "bounce/core/error.h"

namespace bounce {

namespace fs = std::filesystem;

bool is_embedded_image(const std::string& file, const std::string& folder) {
    return !folder.empty() && fs::absolute(file).lexically_normal().parent_path() == fs::absolute(folder).lexically_normal();
}

std::string embedded_image_file(const aiTexture& texture, const std::string& images, const std::string& path, const std::string& where) {
    if (texture.mHeight != 0) throw InputError(path, where, "an embedded image of raw texels (not an encoded PNG or JPEG) is not read");
    // The format hint names the file's type ("png", "jpg"); anything else is kept out of the name.
    std::string ext;
    for (const char* c = texture.achFormatHint; *c && ext.size() < 8; ++c)
        if (std::isalnum(static_cast<unsigned char>(*c))) ext += static_cast<char>(std::tolower(static_cast<unsigned char>(*c)));
    if (ext.empty()) ext = "img";
    const auto* bytes = reinterpret_cast<const char*>(texture.pcData);
    const size_t size = texture.mWidth;
    if (images.empty())
        throw InputError(path, where,
                         "it embeds an image and no folder was given to write it to (LoadResources::images; BOUNCE_IMAGE_CACHE)");
    const fs::path folder = images;
    const fs::path file = folder / fmt::format("{:016x}.{}", OIIO::xxhash::XXH64(bytes, size, 61), ext);
    std::error_code ec;
    if (fs::is_regular_file(file, ec) && fs::file_size(file, ec) == size) return file.string();
    fs::create_directories(folder, ec);
    try {
        write_atomically(file, [&](const std::string& tmp) {
            std::ofstream out(tmp, std::ios::binary);
            out.write(bytes, static_cast<std::streamsize>(size));
            if (!out) throw std::runtime_error("cannot write " + tmp);
        });
    } catch (const std::exception& e) {
        throw InputError(path, where,
                         fmt::format("its embedded image cannot be written to {} ({}); set BOUNCE_IMAGE_CACHE to a folder bounce can write",
                                     folder.string(), e.what()));
    }
    return file.string();
}

}  // namespace bounce
