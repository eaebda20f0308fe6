#include "bounce/core/atomic_file.h"

#include <unistd.h>

#include "bounce/core/error.h"

namespace bounce {

void write_atomically(const std::filesystem::path& path, const std::function<void(const std::string& tmp_path)>& write) {
    namespace fs = std::filesystem;
    if (path.has_parent_path()) {
        std::error_code ec;
        fs::create_directories(path.parent_path(), ec);
        if (ec) throw InputError(path.string(), "", "cannot create directory: " + ec.message());
    }
    // Keep the extension last: image writers choose the format from it.
    fs::path tmp = path;
    tmp.replace_filename(path.stem().string() + ".tmp" + std::to_string(::getpid()) + path.extension().string());
    try {
        write(tmp.string());
    } catch (...) {
        std::error_code ec;
        fs::remove(tmp, ec);
        throw;
    }
    std::error_code ec;
    fs::rename(tmp, path, ec);
    if (ec) {
        std::error_code removed;  // the rename's reason is the one to give (it said "Success")
        fs::remove(tmp, removed);
        const std::string why = fs::is_directory(path, removed) ? "a folder of that name is in the way" : ec.message();
        throw InputError(path.string(), "", "cannot write output: " + why);
    }
}

}  // namespace bounce
