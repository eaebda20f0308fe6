// Checks on the files a command reads and writes, made before any work starts: inputs must be
// regular files (a FIFO would block, a directory cannot be read), and an output must not name
// an input, a device or a directory (the atomic rename would replace it).
#pragma once

#include <filesystem>
#include <map>
#include <mutex>
#include <string>
#include <vector>

namespace bounce {

/// Why `path` cannot be read as a file ("file not found", "is a directory", "not a regular
/// file"), or empty when it can.
std::string not_a_regular_file(const std::string& path);
/// Throws InputError(path) unless `path` is a regular file.
void check_input_file(const std::string& path);
/// Throws InputError(path) when `path` is a directory, a device, a FIFO or anything else
/// but a regular file or a new name, when it is the same file as one of `inputs` or lies
/// inside one of `input_folders`, or when its folder does not exist or cannot take a new file
/// (a read-only or pseudo file system such as /proc: a file is created there and removed).
void check_output_file(const std::string& path, const std::vector<std::string>& inputs, const std::vector<std::string>& input_folders = {});
/// The extension of `path`, lower case (".PLY" -> ".ply"; "" for none).
std::string lower_extension(const std::string& path);
/// `s` with its ASCII letters in lower case (extensions, HTTP header values).
std::string ascii_lower(std::string s);
/// True when `path` is `folder` or lies under it, symlinks that exist resolved.
bool inside(const std::filesystem::path& path, const std::filesystem::path& folder);
/// Files' content hashes remembered per (path, size, mtime), so a file unchanged since it was
/// last hashed is not read again (the lighting tool reloads its scene at every edit). Its owner
/// (a front end, for all its loads) hands it down; safe to use from many threads.
class FileHashes {
  public:
    uint64_t hash(const std::string& path);

  private:
    struct Seen {
        uintmax_t size;
        int64_t mtime;
        uint64_t hash;
    };
    std::mutex mutex_;
    std::map<std::string, Seen> seen_;
};
/// A 64-bit hash of the file's whole content (xxHash; 0 when it cannot be read): identities
/// cover what a file holds, not only its name. With `remembered`, taken from there.
uint64_t file_content_hash(const std::string& path, FileHashes* remembered = nullptr);
/// Removes temporary files of dead processes that write_atomically left beside `path`
/// (a SIGKILL cannot be caught).
void remove_stale_temporaries(const std::string& path);

}  // namespace bounce
