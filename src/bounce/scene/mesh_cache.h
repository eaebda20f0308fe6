// A cache of loaded mesh files (issue 49, docs/instancing.md "Mesh cache"): a text mesh file is
// parsed once, and later loads read what it loaded to at memory speed. Opt-in: the folder named
// by BOUNCE_MESH_CACHE holds one entry per (mesh file content, load), valid while the file and
// every file it read (MTL, glTF buffers, textures) hold the same bytes. An entry that is damaged
// or stale is a miss: the file is parsed again and the entry rewritten, never an error.
#pragma once

#include <atomic>
#include <cstdint>
#include <memory>
#include <optional>
#include <string>
#include <utility>
#include <vector>

#include "bounce/core/files.h"
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

/// Loads served from a cache, and loads that parsed the file and wrote an entry.
struct MeshCacheCounts {
    uint64_t hits = 0, writes = 0;
};

/// The opt-in cache of loaded mesh files in one folder (docs/instancing.md, "Mesh cache"): made by
/// a front end for its loads (LoadResources::mesh_cache) and safe to use from many threads. What
/// it says once on stderr and what it counts are its own.
class MeshCache {
  public:
    /// `folder` is made if missing; `hashes` (may be null) remembers the files' content hashes.
    MeshCache(std::string folder, std::shared_ptr<FileHashes> hashes);
    /// False when the folder could not be made (said once on stderr: meshes are then parsed).
    bool usable() const { return usable_; }
    const std::string& folder() const { return folder_; }
    /// The entry for `key` when it is sound and the file and its inputs are unchanged. A damaged
    /// entry is said once on stderr; a missing or stale one silently; both are misses.
    std::optional<LoadedMeshFile> read(const MeshCacheKey& key);
    /// Writes the entry for `key` (atomically: concurrent ranks may write the same one). A folder
    /// that cannot take it is said once on stderr, and the load goes on.
    void write(const MeshCacheKey& key, const LoadedMeshFile& loaded);
    /// The entry's file name in the folder (for tests and tools).
    std::string entry(const MeshCacheKey& key) const;
    MeshCacheCounts counts() const { return {hits_.load(), writes_.load()}; }
    /// A content hash as the cache takes it (remembered when it has `hashes`).
    uint64_t hash(const std::string& path) const { return file_content_hash(path, hashes_.get()); }

  private:
    std::string folder_;
    std::shared_ptr<FileHashes> hashes_;
    bool usable_ = false;
    std::atomic<bool> said_damaged_{false}, said_unwritable_{false};
    std::atomic<uint64_t> hits_{0}, writes_{0};
};

}  // namespace bounce
