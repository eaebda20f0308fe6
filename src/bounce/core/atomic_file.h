// Outputs are written to a temporary name beside the target and renamed into place, so a crash
// or an error never leaves a half-written file under the final name.
#pragma once

#include <filesystem>
#include <functional>
#include <string>

namespace bounce {

/// Calls `write(tmp_path)`; if it returns normally, renames tmp_path to `path`.
/// On exception the temporary file is removed and the exception propagates.
void write_atomically(const std::filesystem::path& path, const std::function<void(const std::string& tmp_path)>& write);

}  // namespace bounce
