// What loading a scene writes to and reads back on this machine, shared by a front end's loads:
// the folders it names (the command line from the environment: docs/scene-format.md), the mesh
// cache in one of them, and the files' content hashes it remembers. The library reads no
// environment variable and keeps nothing between loads of its own, so a render depends on its
// arguments alone.
#pragma once

#include <memory>
#include <string>

#include "bounce/core/files.h"

namespace bounce {

class MeshCache;  // mesh_cache.h

struct LoadResources {
    /// Parsed mesh files are kept here and reused while their inputs are unchanged; null: every
    /// mesh file is parsed.
    std::shared_ptr<MeshCache> mesh_cache;
    /// Images embedded in glTF files are written here, named by their content
    /// (embedded_images.h); empty: a file that embeds one is refused, saying so.
    std::string images;
    /// Content hashes of the files loads read (identities, mesh cache keys); null: each file is
    /// read again whenever its hash is needed.
    std::shared_ptr<FileHashes> hashes;
};

}  // namespace bounce
