// The folders of this machine that loading a scene writes to and reads back. The front end names
// them (the command line from the environment: docs/scene-format.md); the library reads no
// environment variable, so a render depends on its arguments alone.
#pragma once

#include <string>

namespace bounce {

struct LoadFolders {
    /// Parsed mesh files are kept here and reused while their inputs are unchanged (mesh_cache.h);
    /// empty: every mesh file is parsed.
    std::string mesh_cache;
    /// Images embedded in glTF files are written here, named by their content
    /// (embedded_images.h); empty: a file that embeds one is refused, saying so.
    std::string images;
};

}  // namespace bounce
