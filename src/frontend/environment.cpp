#include "frontend/environment.h"

#include <fmt/format.h>
#include <unistd.h>

#include <cstdlib>
#include <filesystem>
#include <map>
#include <memory>
#include <mutex>

namespace bounce {

namespace {

std::string variable(const char* name) {
    const char* v = std::getenv(name);
    return v && *v ? v : "";
}

/// What this process's loads share (a front end's to keep; the library keeps nothing between
/// loads): the files' content hashes, and one mesh cache per folder the environment named, so a
/// cache says what it says once and counts every load of the process.
struct ProcessResources {
    std::mutex mutex;
    std::shared_ptr<FileHashes> hashes = std::make_shared<FileHashes>();
    std::map<std::string, std::shared_ptr<MeshCache>> mesh_caches;
};
ProcessResources& process_resources() {
    static ProcessResources r;
    return r;
}

}  // namespace

LoadResources load_resources_from_environment() {
    namespace fs = std::filesystem;
    LoadResources f;
    ProcessResources& process = process_resources();
    f.hashes = process.hashes;
    if (const std::string folder = variable("BOUNCE_MESH_CACHE"); !folder.empty()) {
        const std::lock_guard lock(process.mutex);
        std::shared_ptr<MeshCache>& cache = process.mesh_caches[folder];
        if (!cache) cache = std::make_shared<MeshCache>(folder, process.hashes);
        f.mesh_cache = cache;
    }
    if (std::string d = variable("BOUNCE_IMAGE_CACHE"); !d.empty())
        f.images = d;
    else if (std::string x = variable("XDG_CACHE_HOME"); !x.empty())
        f.images = (fs::path(x) / "bounce" / "images").string();
    else if (std::string h = variable("HOME"); !h.empty())
        f.images = (fs::path(h) / ".cache" / "bounce" / "images").string();
    else
        f.images = fmt::format("/tmp/bounce-images-{}", ::getuid());
    return f;
}

LoadOptions load_options_from_environment() {
    LoadOptions o;
    o.resources = load_resources_from_environment();
    return o;
}

MeshCacheCounts mesh_cache_counts() {
    ProcessResources& process = process_resources();
    const std::lock_guard lock(process.mutex);
    MeshCacheCounts sum;
    for (const auto& [folder, cache] : process.mesh_caches) sum.hits += cache->counts().hits, sum.writes += cache->counts().writes;
    return sum;
}

bool launched_by_mpi() {
    return !variable("OMPI_COMM_WORLD_SIZE").empty() || !variable("PMIX_RANK").empty() || !variable("PMI_RANK").empty();
}

}  // namespace bounce
