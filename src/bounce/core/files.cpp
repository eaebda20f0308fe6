#include "bounce/core/files.h"

#include <signal.h>

#include <algorithm>
#include <cerrno>
#include <filesystem>

#include "bounce/core/error.h"

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

void check_output_file(const std::string& path, const std::vector<std::string>& inputs) {
    std::error_code ec;
    fs::file_status st = fs::status(path, ec);
    if (!ec && st.type() == fs::file_type::directory) throw InputError(path, "", "output is a directory");
    if (!ec && st.type() != fs::file_type::not_found && st.type() != fs::file_type::regular)
        throw InputError(path, "", "output is not a regular file (a device, FIFO or socket would be replaced)");
    for (const auto& in : inputs) {
        if (in.empty()) continue;
        std::error_code e1;
        bool same = fs::equivalent(path, in, e1) ||
                    fs::weakly_canonical(path, e1) == fs::weakly_canonical(in, e1);
        if (same) throw InputError(path, "", "output names an input (" + in + "); it would be overwritten");
    }
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
