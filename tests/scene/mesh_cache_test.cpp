// The mesh cache (scene/mesh_cache.h): a hit loads exactly what parsing loads, an edited input
// or a damaged entry is parsed again, and a crafted entry never crashes the loader.
#include <OpenImageIO/hash.h>
#include <gtest/gtest.h>
#include <sys/stat.h>

#include <algorithm>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <fstream>

#include "bounce/core/files.h"
#include "bounce/scene/mesh_cache.h"
#include "bounce/scene/mesh_import.h"
#include "test_util.h"

namespace bounce {
namespace {

namespace fs = std::filesystem;

void expect_same_mesh(const TriangleMesh& a, const TriangleMesh& b) {
    ASSERT_EQ(a.positions.size(), b.positions.size());
    EXPECT_EQ(std::memcmp(a.positions.data(), b.positions.data(), a.positions.size() * sizeof(Vec3)), 0);
    ASSERT_EQ(a.normals.size(), b.normals.size());
    EXPECT_EQ(std::memcmp(a.normals.data(), b.normals.data(), a.normals.size() * sizeof(Vec3)), 0);
    ASSERT_EQ(a.uvs.size(), b.uvs.size());
    EXPECT_EQ(std::memcmp(a.uvs.data(), b.uvs.data(), a.uvs.size() * sizeof(Vec2)), 0);
    EXPECT_EQ(a.indices, b.indices);
    EXPECT_EQ(a.face_materials, b.face_materials);
}

void expect_same_materials(const std::vector<Material>& a, const std::vector<Material>& b) {
    ASSERT_EQ(a.size(), b.size());
    for (size_t i = 0; i < a.size(); ++i) {
        EXPECT_EQ(a[i].name, b[i].name);
        for (int c = 0; c < 3; ++c) {
            EXPECT_EQ(a[i].color[c], b[i].color[c]) << a[i].name;
            EXPECT_EQ(a[i].emission[c], b[i].emission[c]) << a[i].name;
            EXPECT_EQ(a[i].specular[c], b[i].specular[c]) << a[i].name;
        }
        EXPECT_EQ(a[i].roughness, b[i].roughness);
        EXPECT_EQ(a[i].color_texture, b[i].color_texture);
    }
}

/// The Cornell box OBJ and its MTL copied where a test may edit them, and a cache folder.
class MeshCache : public ::testing::Test {
  protected:
    test::TempDir dir, cache;
    std::string obj;
    void SetUp() override {
        const std::string src = test::source_dir() + "/tests/data/cornell_box/";
        fs::copy_file(src + "CornellBox-Original.obj", dir.file("box.obj"));
        fs::copy_file(src + "CornellBox-Original.mtl", dir.file("CornellBox-Original.mtl"));
        obj = dir.file("box.obj");
        setenv("BOUNCE_MESH_CACHE", cache.path().c_str(), 1);
    }
    void TearDown() override { unsetenv("BOUNCE_MESH_CACHE"); }

    struct Loaded {
        MeshFileParts parts;
        std::vector<Material> materials;
        std::vector<std::string> files;
    };
    /// The box loaded after one scene material ("white"), overridden by material `override_material`.
    Loaded load(int override_material = -1) const {
        Loaded l;
        l.materials.resize(2);
        l.materials[0].name = "white";
        l.materials[1].name = "lamp", l.materials[1].emission = Color(4);
        MeshInputs read;
        read.resources = load_resources_from_environment();
        l.parts = load_mesh_parts(obj, "box", l.materials, override_material, &read);
        l.files = read.files;
        return l;
    }
    Loaded parsed(int override_material = -1) const {
        unsetenv("BOUNCE_MESH_CACHE");
        Loaded l = load(override_material);
        setenv("BOUNCE_MESH_CACHE", cache.path().c_str(), 1);
        return l;
    }
    std::string entry(bool overridden = false, bool emits = false) const {
        return bounce::MeshCache(cache.path().string(), nullptr)
            .entry({fs::absolute(obj).lexically_normal().string(), "box", overridden, emits, true});
    }
    static void expect_same(const Loaded& a, const Loaded& b) {
        expect_same_mesh(a.parts.once, b.parts.once);
        EXPECT_EQ(a.parts.shared.size(), b.parts.shared.size());
        expect_same_materials(a.materials, b.materials);
        EXPECT_EQ(a.files, b.files);
    }
};

TEST_F(MeshCache, AHitLoadsWhatParsingLoads) {
    const Loaded reference = parsed();
    ASSERT_GT(reference.parts.once.triangle_count(), 30u);
    ASSERT_EQ(reference.materials.size(), 2u + 9u);  // the scene's two, then Assimp's default and the MTL's eight
    EXPECT_EQ(reference.files.size(), 1u);           // the MTL
    const MeshCacheCounts before = mesh_cache_counts();
    expect_same(load(), reference);  // a miss: parsed, written
    EXPECT_EQ(mesh_cache_counts().writes, before.writes + 1);
    EXPECT_TRUE(fs::is_regular_file(entry()));
    expect_same(load(), reference);  // a hit
    EXPECT_EQ(mesh_cache_counts().hits, before.hits + 1);
    EXPECT_EQ(mesh_cache_counts().writes, before.writes + 1);
    // load_mesh_file's entries are apart from load_mesh_parts' and hold the same triangles.
    const std::vector<Material> scene_materials(reference.materials.begin(), reference.materials.begin() + 2);
    std::vector<Material> first = scene_materials, second = scene_materials;
    MeshInputs read;
    read.resources = load_resources_from_environment();
    const TriangleMesh flat = load_mesh_file(obj, "box", first, -1, &read);
    const TriangleMesh again = load_mesh_file(obj, "box", second, -1, &read);
    expect_same_materials(second, reference.materials);
    expect_same_mesh(flat, reference.parts.once);
    expect_same_mesh(again, reference.parts.once);
    EXPECT_EQ(mesh_cache_counts().hits, before.hits + 2);
}

TEST_F(MeshCache, AnOverrideReusesTheEntryOfAnyMaterialThatDoesNotEmit) {
    const Loaded white = load(0);
    for (uint32_t m : white.parts.once.face_materials) EXPECT_EQ(m, 0u);
    EXPECT_EQ(white.materials.size(), 2u);
    const MeshCacheCounts before = mesh_cache_counts();
    expect_same(load(0), parsed(0));
    EXPECT_EQ(mesh_cache_counts().hits, before.hits + 1);
    // An emissive override has an entry of its own (emissive meshes are never shared).
    const Loaded lamp = load(1);
    for (uint32_t m : lamp.parts.once.face_materials) EXPECT_EQ(m, 1u);
    EXPECT_EQ(mesh_cache_counts().writes, before.writes + 1);
    EXPECT_NE(entry(true, true), entry(true, false));
}

TEST_F(MeshCache, AnEditedFileOrMtlIsParsedAgain) {
    load();
    const MeshCacheCounts before = mesh_cache_counts();
    std::string mtl = test::bytes_of(dir.file("CornellBox-Original.mtl"));
    const size_t at = mtl.find("Kd 0.63 0.065 0.05");
    ASSERT_NE(at, std::string::npos);
    mtl.replace(at, 18, "Kd 0.5 0.25 0.125 ");
    dir.write("CornellBox-Original.mtl", mtl);
    const Loaded edited = load();
    EXPECT_EQ(mesh_cache_counts().hits, before.hits);
    EXPECT_EQ(mesh_cache_counts().writes, before.writes + 1);
    const auto left =
        std::find_if(edited.materials.begin(), edited.materials.end(), [](const Material& m) { return m.name == "box/leftWall"; });
    ASSERT_NE(left, edited.materials.end());
    EXPECT_EQ(left->color, Color(0.5f, 0.25f, 0.125f));
    std::ofstream(obj, std::ios::app) << "v 1 2 3\n";  // the OBJ itself: another key
    expect_same(load(), parsed());
    EXPECT_EQ(mesh_cache_counts().writes, before.writes + 2);
}

/// Bytes of an entry with its body's checksum made right again (mesh_cache.cpp's layout: 32
/// header bytes, the body's XXH64 at 24 seeded with the version).
std::string with_checksum(std::string bytes) {
    uint32_t version = 0;  // the body's hash is seeded with the entry's version
    std::memcpy(&version, bytes.data() + 8, 4);
    const uint64_t h = OIIO::xxhash::XXH64(bytes.data() + 32, bytes.size() - 32, version);
    std::memcpy(bytes.data() + 24, &h, 8);
    return bytes;
}

TEST_F(MeshCache, ADamagedEntryIsParsedAgainAndRewritten) {
    const Loaded reference = parsed();
    load();
    const std::string good = test::bytes_of(entry());
    ASSERT_GT(good.size(), 1000u);
    auto expect_reparsed = [&](const std::string& what) {
        const MeshCacheCounts before = mesh_cache_counts();
        expect_same(load(), reference);
        EXPECT_EQ(mesh_cache_counts().hits, before.hits) << what;
        EXPECT_EQ(test::bytes_of(entry()), good) << what << ": not rewritten";
    };
    for (size_t at : {size_t{0}, size_t{9}, size_t{20}, size_t{40}, good.size() / 2, good.size() - 1}) {
        std::string bad = good;
        bad[at] = static_cast<char>(bad[at] ^ 0x5a);
        std::ofstream(entry(), std::ios::binary) << bad;
        expect_reparsed("byte " + std::to_string(at));
    }
    std::ofstream(entry(), std::ios::binary | std::ios::trunc) << good.substr(0, good.size() / 3);
    expect_reparsed("truncated");
    std::ofstream(entry(), std::ios::binary | std::ios::trunc) << with_checksum(good + "tail");
    expect_reparsed("bytes after its end");
    fs::remove(entry());
    ASSERT_EQ(mkfifo(entry().c_str(), 0600), 0);  // would block a reader that opened it
    expect_reparsed("a FIFO");
}

TEST_F(MeshCache, ACraftedEntryNeverCrashesTheLoader) {
    const Loaded reference = parsed();
    load();
    const std::string good = test::bytes_of(entry());
    // Each byte of the body set to 0xff with the checksum made right: a hit of other values, or
    // a miss; never an out-of-range index, a huge allocation or a crash.
    size_t hits = 0, tries = 0;
    for (size_t at = 32; at < good.size(); at += 7, ++tries) {
        std::string bad = good;
        bad[at] = static_cast<char>(0xff);
        std::ofstream(entry(), std::ios::binary | std::ios::trunc) << with_checksum(bad);
        const MeshCacheCounts before = mesh_cache_counts();
        const Loaded l = load();
        hits += mesh_cache_counts().hits - before.hits;
        const size_t n = l.parts.once.positions.size();
        for (uint32_t i : l.parts.once.indices) ASSERT_LT(i, n) << "byte " << at;
        for (uint32_t m : l.parts.once.face_materials) ASSERT_LT(m, l.materials.size()) << "byte " << at;
    }
    EXPECT_GT(tries, 100u);
    EXPECT_GT(hits, 0u);     // a changed position or colour is still an entry
    EXPECT_LT(hits, tries);  // a changed count or index is not
    EXPECT_GT(reference.parts.once.triangle_count(), 0u);
}

TEST_F(MeshCache, AFolderThatCannotTakeEntriesLeavesLoadsAsTheyWere) {
    const Loaded reference = parsed();
    fs::create_directory(entry());  // the entry's name is taken by a folder
    expect_same(load(), reference);
    setenv("BOUNCE_MESH_CACHE", (dir.file("box.obj") + "/sub").c_str(), 1);  // under a file: no folder
    expect_same(load(), reference);
}

TEST_F(MeshCache, ARenderFromTheCacheIsTheRenderFromTheFile) {
    const std::string scene =
        dir.write("box.json", R"({"camera": {"position": [0, 1, 3.5], "look_at": [0, 1, 0], "fov": 40, "resolution": [24, 24]},
        "objects": [{"name": "box", "file": "box.obj"}]})");
    const std::string args = " --spp 1 --gi brute --rays 8 -q -o ";
    unsetenv("BOUNCE_MESH_CACHE");
    ASSERT_EQ(test::run_bounce("render " + scene + args + dir.file("parsed.exr")), 0);
    const std::string with = "BOUNCE_MESH_CACHE=" + cache.path().string() + " " + BOUNCE_BINARY + " render " + scene + args;
    ASSERT_EQ(test::run_bounce_shell(with + dir.file("miss.exr")), 0);
    ASSERT_FALSE(fs::is_empty(cache.path()));
    ASSERT_EQ(test::run_bounce_shell(with + dir.file("hit.exr")), 0);
    const Image parsed = read_exr(dir.file("parsed.exr"));
    EXPECT_EQ(test::differing_values(read_exr(dir.file("miss.exr")), parsed), 0u);
    EXPECT_EQ(test::differing_values(read_exr(dir.file("hit.exr")), parsed), 0u);
}

// Issue 65: an entry's MTL is checked where the mesh's folder has it, not by a name relative to
// the working directory of the run that wrote the entry (a copy of an old MTL there hid an edit).
TEST_F(MeshCache, AnEditedMtlIsSeenFromAnyWorkingDirectory) {
    const fs::path start = fs::current_path();
    fs::current_path(dir.path());
    obj = "box.obj";  // relative, as a scene in this folder names it
    load();           // the entry, written from the mesh's folder
    test::TempDir elsewhere;
    fs::copy_file(dir.file("CornellBox-Original.mtl"), elsewhere.file("CornellBox-Original.mtl"));  // the old MTL
    std::string mtl = test::bytes_of(dir.file("CornellBox-Original.mtl"));
    const size_t kd = mtl.find("Kd ");
    ASSERT_NE(kd, std::string::npos);
    mtl.replace(kd, mtl.find('\n', kd) - kd, "Kd 0.1 0.1 0.8");
    std::ofstream(dir.file("CornellBox-Original.mtl"), std::ios::trunc) << mtl;
    fs::current_path(elsewhere.path());
    obj = dir.file("box.obj");
    const MeshCacheCounts before = mesh_cache_counts();
    const Loaded l = load();
    EXPECT_EQ(mesh_cache_counts().hits, before.hits) << "the old entry was used";
    const Loaded reference = parsed();
    fs::current_path(start);
    expect_same_materials(l.materials, reference.materials);
    bool blue = false;
    for (const Material& m : l.materials) blue |= m.color[0] == 0.1f && m.color[2] == 0.8f;
    EXPECT_TRUE(blue);
}

// Issue 65: a material's texture in an entry is a file the parse read and a texture a parse
// would take; /etc/passwd or a missing file makes the entry damaged (parsed again).
TEST_F(MeshCache, AnEntrysTexturesAreCheckedAsAParseChecksThem) {
    const Loaded reference = parsed();
    load();
    const MeshCacheKey key{fs::absolute(obj).lexically_normal().string(), "box", false, false, true};
    bounce::MeshCache direct(cache.path().string(), nullptr);
    const std::optional<LoadedMeshFile> good = direct.read(key);
    ASSERT_TRUE(good);
    for (const std::string& texture : {std::string("/etc/passwd"), dir.file("nosuch.png")}) {
        for (const bool listed : {false, true}) {
            LoadedMeshFile bad = *good;
            bad.materials.back().color_texture = texture;
            if (listed) bad.inputs.emplace_back(texture, file_content_hash(texture));
            direct.write(key, bad);
            EXPECT_FALSE(direct.read(key)) << texture << (listed ? " (listed)" : "");
        }
    }
    // The load parses again and is the parse's.
    expect_same(load(), reference);
}

}  // namespace
}  // namespace bounce
