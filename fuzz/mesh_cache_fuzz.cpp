// libFuzzer target (issue 49): mesh cache entries (scene/mesh_cache.h). The input is the body of
// an entry after its key, written with a valid header, key and checksum, so that the fuzzer
// reaches what a crafted entry would: counts, indices, materials, placements. A read must end
// in a hit whose faces name vertices and materials it has, or a miss; never a crash, a hang or
// a huge allocation.
#include <OpenImageIO/hash.h>
#include <unistd.h>

#include <cstddef>
#include <cstdint>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <memory>
#include <string>

#include "bounce/scene/mesh_cache.h"

namespace {

namespace fs = std::filesystem;

struct Folder {
    std::string dir, entry;
    bounce::MeshCacheKey key;
    std::unique_ptr<bounce::MeshCache> cache;
    std::string prefix;  ///< an entry's header and key, as written for an empty load
    Folder() {
        dir = (fs::temp_directory_path() / ("bounce-mesh-cache-fuzz-" + std::to_string(getpid()))).string();
        fs::create_directories(dir);
        std::ofstream(dir + "/m.obj") << "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n";
        key = {dir + "/m.obj", "m", false, false, true};
        cache = std::make_unique<bounce::MeshCache>(dir, nullptr);
        cache->write(key, {});
        entry = cache->entry(key);
        std::ifstream in(entry, std::ios::binary);
        const std::string bytes((std::istreambuf_iterator<char>(in)), {});
        prefix = bytes.substr(0, bytes.size() - 52);  // an empty load's body after its key: 52 bytes
    }
};

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
    static const Folder folder;
    std::string bytes = folder.prefix + std::string(reinterpret_cast<const char*>(data), size);
    uint32_t version = 0;  // the body's hash is seeded with the entry's version
    std::memcpy(&version, bytes.data() + 8, 4);
    const uint64_t body = bytes.size() - 32, hash = OIIO::xxhash::XXH64(bytes.data() + 32, body, version);
    std::memcpy(bytes.data() + 16, &body, 8);
    std::memcpy(bytes.data() + 24, &hash, 8);
    std::ofstream(folder.entry, std::ios::binary | std::ios::trunc) << bytes;
    if (const auto hit = folder.cache->read(folder.key)) {
        const bounce::TriangleMesh& m = hit->parts.once;
        for (uint32_t i : m.indices)
            if (i >= m.positions.size()) std::abort();
        for (uint32_t f : m.face_materials)
            if (f >= hit->materials.size()) std::abort();
    }
    return 0;
}
