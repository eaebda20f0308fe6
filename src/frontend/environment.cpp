#include "frontend/environment.h"

#include <fmt/format.h>
#include <unistd.h>

#include <cstdlib>
#include <filesystem>

namespace bounce {

namespace {

std::string variable(const char* name) {
    const char* v = std::getenv(name);
    return v && *v ? v : "";
}

}  // namespace

LoadFolders load_folders_from_environment() {
    namespace fs = std::filesystem;
    LoadFolders f;
    f.mesh_cache = variable("BOUNCE_MESH_CACHE");
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
    o.folders = load_folders_from_environment();
    return o;
}

bool launched_by_mpi() {
    return !variable("OMPI_COMM_WORLD_SIZE").empty() || !variable("PMIX_RANK").empty() || !variable("PMI_RANK").empty();
}

}  // namespace bounce
