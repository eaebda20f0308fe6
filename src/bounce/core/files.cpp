#include "bounce/core/files.h"

#include <OpenImageIO/hash.h>
#include <signal.h>
#include <unistd.h>

#include <algorithm>
#include <cctype>
#include <cerrno>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <map>
#include <mutex>
#include <vector>

#include "bounce/core/error.h"
#include "bounce/core/random.h"

namespace bounce {

namespace fs = std::filesystem;

std::string not_a_regular_file(const std::string& path) {
    std::error_code ec;
    fs::file_status st = fs::status(path, ec);
    if (ec || st.type() == fs::file_type::not_found) return "file not found";
    if (st.type() == fs::file_type::directory) return "is a directory, not a file";
    if (st.type() != fs::file_type::regular) return "not a regular file";
    return "";
}

void check_input_file(const std::string& path) {
    if (std::string why = not_a_regular_file(path); !why.empty()) throw InputError(path, "", why);
}

namespace {

/// Throws unless `dir` is an existing folder in which a new file can be created (and removed).
void check_output_folder(const std::string& path, const fs::path& dir) {
    std::error_code ec;
    const fs::file_status st = fs::status(dir, ec);
    if (ec || st.type() == fs::file_type::not_found) throw InputError(path, "", "its folder " + dir.string() + " does not exist");
    if (st.type() != fs::file_type::directory) throw InputError(path, "", dir.string() + " is not a folder");
    std::string probe = (dir / ".bounce-probe-XXXXXX").string();
    const int fd = ::mkstemp(probe.data());
    if (fd < 0) throw InputError(path, "", "cannot create a file in " + dir.string() + ": " + std::strerror(errno));
    ::close(fd);
    ::unlink(probe.c_str());
}

}  // namespace

std::string ascii_lower(std::string s) {
    for (char& c : s) c = static_cast<char>(std::tolower(static_cast<unsigned char>(c)));
    return s;
}

std::string lower_extension(const std::string& path) { return ascii_lower(std::filesystem::path(path).extension().string()); }

bool inside(const std::filesystem::path& path, const std::filesystem::path& folder) {
    std::error_code ec;
    const fs::path p = fs::weakly_canonical(path, ec), f = fs::weakly_canonical(folder, ec);
    auto pi = p.begin();
    for (auto fi = f.begin(); fi != f.end(); ++fi, ++pi)
        if (fi->empty())
            continue;  // a trailing separator
        else if (pi == p.end() || *pi != *fi)
            return false;
    return true;
}

void check_output_file(const std::string& path, const std::vector<std::string>& inputs, const std::vector<std::string>& input_folders) {
    std::error_code ec;
    fs::file_status st = fs::status(path, ec);
    if (!ec && st.type() == fs::file_type::directory) throw InputError(path, "", "output is a directory");
    if (!ec && st.type() != fs::file_type::not_found && st.type() != fs::file_type::regular)
        throw InputError(path, "", "output is not a regular file (a device, FIFO or socket would be replaced)");
    for (const auto& in : inputs) {
        if (in.empty()) continue;
        std::error_code e1;
        bool same = fs::equivalent(path, in, e1) || fs::weakly_canonical(path, e1) == fs::weakly_canonical(in, e1);
        if (same) throw InputError(path, "", "output names an input (" + in + "); it would be overwritten");
    }
    for (const auto& folder : input_folders)
        if (!folder.empty() && inside(path, folder))
            throw InputError(path, "", "output lies inside " + folder + ", a folder the scene reads");
    const fs::path p(path);
    check_output_folder(path, p.has_parent_path() ? p.parent_path() : fs::path("."));
}

namespace {

/// The file's content hash as read now, with the size and mtime it was read at.
uint64_t hash_of_file(const std::string& path, uintmax_t size) {
    std::ifstream in(path, std::ios::binary);
    std::vector<char> chunk(1 << 20);
    uint64_t h = hash_combine(0x6a09e667f3bcc909ULL, size);
    while (in) {
        in.read(chunk.data(), static_cast<std::streamsize>(chunk.size()));
        const auto n = static_cast<size_t>(in.gcount());
        if (n == 0) break;
        h = hash_combine(h, OIIO::xxhash::XXH64(chunk.data(), n, 0));
    }
    return h;
}

}  // namespace

uint64_t FileHashes::hash(const std::string& path) {
    std::error_code ec;
    const uintmax_t size = fs::file_size(path, ec);
    if (ec) return 0;  // the loader reports a missing file itself
    const int64_t mtime = fs::last_write_time(path, ec).time_since_epoch().count();
    {
        std::lock_guard lock(mutex_);
        auto it = seen_.find(path);
        if (it != seen_.end() && it->second.size == size && it->second.mtime == mtime) return it->second.hash;
    }
    const uint64_t h = hash_of_file(path, size);
    std::lock_guard lock(mutex_);
    seen_[path] = {size, mtime, h};
    return h;
}

uint64_t file_content_hash(const std::string& path, FileHashes* remembered) {
    if (remembered) return remembered->hash(path);
    std::error_code ec;
    const uintmax_t size = fs::file_size(path, ec);
    return ec ? 0 : hash_of_file(path, size);
}

void remove_stale_temporaries(const std::string& path) {
    fs::path p(path);
    fs::path dir = p.has_parent_path() ? p.parent_path() : fs::path(".");
    std::error_code ec;
    if (!fs::is_directory(dir, ec)) return;
    // Names made by write_atomically: <stem>.tmp<PID><extension>.
    std::string stem = p.stem().string(), ext = p.extension().string();
    for (const auto& e : fs::directory_iterator(dir, ec)) {
        std::string name = e.path().filename().string();
        std::string prefix = stem + ".tmp";
        if (name.rfind(prefix, 0) != 0 || name.size() < prefix.size() + ext.size() + 1 ||
            name.compare(name.size() - ext.size(), ext.size(), ext) != 0)
            continue;
        std::string digits = name.substr(prefix.size(), name.size() - prefix.size() - ext.size());
        if (digits.empty() || digits.size() > 9 || !std::all_of(digits.begin(), digits.end(), ::isdigit)) continue;
        auto pid = static_cast<pid_t>(std::stol(digits));
        if (::kill(pid, 0) == 0 || errno != ESRCH) continue;  // alive, or not ours to judge
        fs::remove(e.path(), ec);
    }
}

}  // namespace bounce
