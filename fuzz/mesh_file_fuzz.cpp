// libFuzzer target: a mesh file (issue 50) must become triangles or an InputError. The first
// byte chooses what the rest is written as — an ASCII or binary PLY (bodies read against their
// header before Assimp: counts, list lengths, indices), a glTF (skins, morph targets and their
// counts, animation samplers with NaN or unordered times) or an OBJ — and, for a glTF, a clip
// and a time to pose it at, so skinning and morphing run on what the checks let through; or, with
// bit 1 of the second byte, loaded for instancing (meshes shared by nodes, EXT_mesh_gpu_instancing
// accessors read by bounce itself).
#include <unistd.h>

#include <cstddef>
#include <cstdint>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <string>
#include <vector>

#include "bounce/core/error.h"
#include "bounce/scene/mesh_import.h"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
    if (size < 2 || size > 1 << 20) return 0;
    static const char* const kinds[] = {".ply", ".gltf", ".obj"};
    const char* ext = kinds[data[0] % 3];
    // A file of this process's own in the working directory (the fuzzer runs in an empty one).
    const std::string path = "fuzz-" + std::to_string(getpid()) + ext;
    std::ofstream(path, std::ios::binary).write(reinterpret_cast<const char*>(data + 2), static_cast<std::streamsize>(size - 2));
    // Embedded images go to a folder of the working directory, not the user's cache.
    bounce::MeshInputs read;
    read.resources.images = "images";
    std::vector<bounce::Material> materials;
    bounce::MeshPose pose;
    if (data[0] % 3 == 1 && data[1] & 1) pose.clip = "0", pose.seconds = (data[1] >> 1) / 64.0;
    try {
        if (pose.clip.empty() && (data[1] & 2))
            (void)bounce::load_mesh_parts(path, "m", materials, -1, &read);
        else
            (void)bounce::load_mesh_file(path, "m", materials, -1, &read, pose);
    } catch (const bounce::InputError&) {}
    std::remove(path.c_str());
    std::error_code ec;
    std::filesystem::remove_all("images", ec);  // embedded images written by the load (below)
    return 0;
}
