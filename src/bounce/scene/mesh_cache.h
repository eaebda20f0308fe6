// A cache of loaded mesh files (issue 49, docs/instancing.md "Mesh cache"): a text mesh file is
// parsed once, and later loads read what it loaded to at memory speed. Opt-in: the folder named
// by BOUNCE_MESH_CACHE holds one entry per (mesh file content, load), valid while the file and
// every file it read (MTL, glTF buffers, textures) hold the same bytes. An entry that is damaged
// or stale is a miss: the file is parsed again and the entry rewritten, never an error.
#pragma once

#include <cstdint>
#include <optional>
#include <string>
#include <utility>
#include <vector>

#include "bounce/scene/mesh_import.h"

namespace bounce {

/// Which load of which file an entry holds.
struct MeshCacheKey {
    std::string path;             ///< the mesh file, absolute
    std::string prefix;           ///< its materials' name prefix
    bool overridden = false;      ///< a scene material replaces the file's
    bool override_emits = false;  ///< ... and is emissive (emissive meshes are never shared)
    bool parts = false;           ///< load_mesh_parts (shared meshes kept apart), else load_mesh_file
};

/// What a mesh file loads to, apart from the scene: its triangles, their face materials indexing
/// `materials` (the file's own, in order; 0 when overridden), and the other files it read with
/// their content hashes (file_content_hash).
struct LoadedMeshFile {
    MeshFileParts parts;
    std::vector<Material> materials;
    std::vector<std::pair<std::string, uint64_t>> inputs;
};

/// `folder` (LoadFolders::mesh_cache) made if missing, or empty when it is empty or cannot be
/// made (said once on stderr: meshes are then parsed).
std::string usable_mesh_cache(const std::string& folder);

/// The entry for `key` in `folder` when it is sound and the file and its inputs are unchanged.
/// A damaged entry is said once on stderr; a missing or stale one silently; both are misses.
std::optional<LoadedMeshFile> read_mesh_cache(const std::string& folder, const MeshCacheKey& key);

/// Writes the entry for `key` (atomically: concurrent ranks may write the same one). A folder
/// that cannot take it is said once on stderr, and the load goes on.
void write_mesh_cache(const std::string& folder, const MeshCacheKey& key, const LoadedMeshFile& loaded);

/// The entry's file name in its folder (for tests and tools).
std::string mesh_cache_entry(const std::string& folder, const MeshCacheKey& key);

/// Loads the process served from the cache, and loads that parsed the file and wrote an entry.
struct MeshCacheCounts {
    uint64_t hits = 0, writes = 0;
};
MeshCacheCounts mesh_cache_counts();

}  // namespace bounce
