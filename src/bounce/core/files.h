// Checks on the files a command reads and writes, made before any work starts: inputs must be
// regular files (a FIFO would block, a directory cannot be read), and an output must not name
// an input, a device or a directory (the atomic rename would replace it).
#pragma once

#include <string>
#include <vector>

namespace bounce {

/// Why `path` cannot be read as a file ("file not found", "is a directory", "not a regular
/// file"), or empty when it can.
std::string not_a_regular_file(const std::string& path);
/// Throws InputError(path) unless `path` is a regular file.
void check_input_file(const std::string& path);
/// Throws InputError(path) when `path` is a directory, a device, a FIFO or anything else
/// but a regular file or a new name, or when it is the same file as one of `inputs`.
void check_output_file(const std::string& path, const std::vector<std::string>& inputs);
/// Removes temporary files of dead processes that write_atomically left beside `path`
/// (a SIGKILL cannot be caught).
void remove_stale_temporaries(const std::string& path);

}  // namespace bounce
