#include "bounce/scene/mesh_cache.h"
#include "bounce/scene/opacity.h"
#include "bounce/scene/surface_textures.h"

#include <OpenImageIO/hash.h>
#include <assimp/version.h>
#include <fmt/format.h>

#include <algorithm>
#include <atomic>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <type_traits>

#include "bounce/core/atomic_file.h"
#include "bounce/core/files.h"
#include "bounce/core/image.h"
#include "bounce/core/memory.h"
#include "bounce/core/random.h"

namespace bounce {

namespace fs = std::filesystem;

namespace {

// Bump when what a load makes of a mesh file changes (mesh_import.cpp), or the layout below.
/// 2: inputs and textures by absolute path (1 named them relative to the working directory of
/// the run that wrote the entry, so another folder's copy of an MTL could stand in for it).
constexpr uint32_t kVersion = 5;  // 3: materials' cutouts and occlusion textures; 4: the whole glTF material; 5: diffuse transmission
constexpr char kMagic[8] = {'B', 'N', 'C', 'M', 'E', 'S', 'H', '\n'};
constexpr size_t kHeaderBytes = 8 + 4 + 4 + 8 + 8;  // magic, version, 0, body bytes, body hash
constexpr size_t kMaxString = 1 << 16;

/// Says `message` on stderr the first time one of its kind comes (each kind has its flag).
void say_once(std::atomic<bool>& said, const std::string& message) {
    if (!said.exchange(true)) std::fprintf(stderr, "bounce: %s\n", message.c_str());
}

/// Bytes appended in the machine's own layout (a cache is the machine's, not an exchange format).
struct Out {
    std::string bytes;
    template <typename T>
    void pod(const T& v) {
        static_assert(std::is_trivially_copyable_v<T>);
        bytes.append(reinterpret_cast<const char*>(&v), sizeof(T));
    }
    void str(const std::string& s) {
        pod(static_cast<uint32_t>(s.size()));
        bytes += s;
    }
    template <typename T>
    void array(const std::vector<T>& v) {
        pod(static_cast<uint64_t>(v.size()));
        bytes.append(reinterpret_cast<const char*>(v.data()), v.size() * sizeof(T));
    }
};

struct Damaged {
    std::string why;
};

/// Reads what Out wrote, every count checked against the bytes left before anything is allocated.
struct In {
    const char* p;
    const char* end;
    size_t left() const { return static_cast<size_t>(end - p); }
    template <typename T>
    T pod() {
        T v;
        if (left() < sizeof(T)) throw Damaged{"it ends early"};
        std::memcpy(&v, p, sizeof(T));
        p += sizeof(T);
        return v;
    }
    std::string str() {
        const auto n = pod<uint32_t>();
        if (n > kMaxString || n > left()) throw Damaged{"a string is longer than the entry"};
        std::string s(p, n);
        p += n;
        return s;
    }
    template <typename T>
    std::vector<T> array() {
        const auto n = pod<uint64_t>();
        if (n > left() / sizeof(T)) throw Damaged{"an array is longer than the entry"};
        std::vector<T> v(n);
        std::memcpy(v.data(), p, n * sizeof(T));
        p += n * sizeof(T);
        return v;
    }
};

void write_key(Out& out, const MeshCacheKey& key, uint64_t content) {
    out.str(key.path);
    out.str(key.prefix);
    out.pod(static_cast<uint8_t>(key.overridden));
    out.pod(static_cast<uint8_t>(key.override_emits));
    out.pod(static_cast<uint8_t>(key.parts));
    out.pod(content);
    out.pod(static_cast<uint32_t>(aiGetVersionMajor() * 10000 + aiGetVersionMinor() * 100 + aiGetVersionPatch()));
}

void write_mesh(Out& out, const TriangleMesh& m) {
    out.array(m.positions);
    out.array(m.normals);
    out.array(m.uvs);
    out.array(m.colors);
    out.array(m.indices);
    out.array(m.face_materials);
}

bool finite_in(float v, float lo, float hi) { return v >= lo && v <= hi; }  // (NaN fails)

template <typename T>
void check_finite(const std::vector<T>& v, const char* what) {
    const auto* f = reinterpret_cast<const float*>(v.data());
    for (size_t i = 0; i < v.size() * sizeof(T) / sizeof(float); ++i)
        if (!finite_in(f[i], -kMaxCoordinate, kMaxCoordinate)) throw Damaged{fmt::format("{} are not finite", what)};
}

TriangleMesh read_mesh(In& in, size_t materials, bool overridden) {
    TriangleMesh m;
    m.positions = in.array<Vec3>();
    m.normals = in.array<Vec3>();
    m.uvs = in.array<Vec2>();
    m.colors = in.array<Color>();
    m.indices = in.array<uint32_t>();
    m.face_materials = in.array<uint32_t>();
    const size_t n = m.positions.size();
    if ((!m.normals.empty() && m.normals.size() != n) || (!m.uvs.empty() && m.uvs.size() != n) ||
        (!m.colors.empty() && m.colors.size() != n))
        throw Damaged{"normals, uvs or colours do not match the vertices"};
    for (const Color& c : m.colors)
        if (!(finite_in(c.x, 0, 1) && finite_in(c.y, 0, 1) && finite_in(c.z, 0, 1))) throw Damaged{"a vertex colour is out of range"};
    if (m.indices.size() % 3 != 0 || m.face_materials.size() != m.indices.size() / 3) throw Damaged{"faces do not match their materials"};
    for (uint32_t i : m.indices)
        if (i >= n) throw Damaged{"a face names a vertex it does not have"};
    for (uint32_t f : m.face_materials)
        if (overridden ? f != 0 : f >= materials) throw Damaged{"a face names a material it does not have"};
    check_finite(m.positions, "positions");
    check_finite(m.normals, "normals");
    check_finite(m.uvs, "uvs");
    return m;
}

void write_material(Out& out, const Material& m) {
    out.str(m.name);
    out.pod(m.color), out.pod(m.emission), out.pod(m.specular), out.pod(m.roughness);
    out.str(m.color_texture), out.str(m.bump_texture), out.str(m.normal_texture), out.str(m.ao_texture);
    out.pod(static_cast<uint8_t>(m.alpha_mode)), out.pod(m.opacity), out.pod(m.alpha_cutoff), out.str(m.opacity_texture);
    out.str(m.emission_texture), out.str(m.metallic_roughness_texture), out.pod(m.metallic);
    out.pod(m.uv_transform.offset), out.pod(m.uv_transform.rotation), out.pod(m.uv_transform.scale), out.pod(m.uv_set);
    out.pod(m.transmission), out.pod(m.ior), out.pod(m.diffuse_transmission), out.pod(m.diffuse_transmission_color);
}

/// A material as mesh_import makes one, in the ranges it allows.
Material read_material(In& in) {
    Material m;
    m.name = in.str();
    m.color = in.pod<Color>(), m.emission = in.pod<Color>(), m.specular = in.pod<Color>();
    m.roughness = in.pod<float>();
    m.color_texture = in.str(), m.bump_texture = in.str(), m.normal_texture = in.str(), m.ao_texture = in.str();
    const auto mode = in.pod<uint8_t>();
    m.opacity = in.pod<float>(), m.alpha_cutoff = in.pod<float>();
    m.opacity_texture = in.str();
    if (mode > static_cast<uint8_t>(AlphaMode::Blend) || !finite_in(m.opacity, 0, 1) || !finite_in(m.alpha_cutoff, 0, 1))
        throw Damaged{"a material's cutout is out of range"};
    m.alpha_mode = static_cast<AlphaMode>(mode);
    m.emission_texture = in.str(), m.metallic_roughness_texture = in.str(), m.metallic = in.pod<float>();
    const Vec2 offset = in.pod<Vec2>();
    const float rotation = in.pod<float>();
    const Vec2 scale = in.pod<Vec2>();
    std::string why;
    if (!make_uv_transform(offset, rotation, scale, m.uv_transform, why)) throw Damaged{"a material's uv transform is out of range"};
    m.uv_set = in.pod<uint8_t>();
    m.transmission = in.pod<Color>(), m.ior = in.pod<float>();
    m.diffuse_transmission = in.pod<float>(), m.diffuse_transmission_color = in.pod<Color>();
    if (m.uv_set > 1 || !finite_in(m.metallic, 0, 1) || !finite_in(m.ior, 1, 3) || !finite_in(m.diffuse_transmission, 0, 1))
        throw Damaged{"a material is out of range"};
    for (int c = 0; c < 3; ++c)
        if (!finite_in(m.color[c], 0, 1) || !finite_in(m.specular[c], 0, 1) || !finite_in(m.emission[c], 0, kMaxRadiometric) ||
            !finite_in(m.transmission[c], 0, 1) || !finite_in(m.diffuse_transmission_color[c], 0, 1))
            throw Damaged{"a material is out of range"};
    if (!finite_in(m.roughness, 0.01f, 1)) throw Damaged{"a material is out of range"};
    return m;
}

void write_entry(Out& out, const LoadedMeshFile& loaded) {
    out.pod(static_cast<uint32_t>(loaded.inputs.size()));
    for (const auto& [path, hash] : loaded.inputs) out.str(path), out.pod(hash);
    out.pod(static_cast<uint32_t>(loaded.materials.size()));
    for (const Material& m : loaded.materials) write_material(out, m);
    write_mesh(out, loaded.parts.once);
    out.pod(static_cast<uint32_t>(loaded.parts.shared.size()));
    for (const MeshFileParts::Shared& s : loaded.parts.shared) {
        write_mesh(out, s.mesh);
        out.pod(static_cast<uint32_t>(s.uses.size()));
        for (const MeshFileParts::Use& u : s.uses) out.str(u.node), out.pod(u.world.m);
    }
}

/// Every count read is bounded by the bytes left, so a loop over it cannot outrun the entry.
LoadedMeshFile read_entry(In& in, bool overridden) {
    LoadedMeshFile loaded;
    for (uint32_t n = in.pod<uint32_t>(), i = 0; i < n; ++i) {
        std::string path = in.str();
        loaded.inputs.emplace_back(std::move(path), in.pod<uint64_t>());
    }
    for (uint32_t n = in.pod<uint32_t>(), i = 0; i < n; ++i) loaded.materials.push_back(read_material(in));
    if (overridden && !loaded.materials.empty()) throw Damaged{"an overridden file keeps materials"};
    loaded.parts.once = read_mesh(in, loaded.materials.size(), overridden);
    for (uint32_t n = in.pod<uint32_t>(), i = 0; i < n; ++i) {
        MeshFileParts::Shared s{read_mesh(in, loaded.materials.size(), overridden), {}};
        for (uint32_t k = in.pod<uint32_t>(), j = 0; j < k; ++j) {
            MeshFileParts::Use u;
            u.node = in.str();
            u.world.m = in.pod<decltype(u.world.m)>();
            for (float v : u.world.m)
                if (!std::isfinite(v)) throw Damaged{"a placement is not finite"};
            s.uses.push_back(std::move(u));
        }
        loaded.parts.shared.push_back(std::move(s));
    }
    if (in.left() != 0) throw Damaged{"bytes follow its end"};
    return loaded;
}

/// A material's textures are files the parse read (so their content is checked with the
/// entry's inputs, and they pass the same confinement on a hit) and still textures a parse
/// would take: a name that is neither is damage, and the file is parsed again.
/// An opacity texture is read again (the entry keeps its name, not its texels).
void check_textures(LoadedMeshFile& loaded) {
    for (Material& m : loaded.materials) {
        for (const std::string* t : m.texture_files()) {
            if (t->empty()) continue;
            if (std::none_of(loaded.inputs.begin(), loaded.inputs.end(), [&](const auto& in) { return in.first == *t; }))
                throw Damaged{"a material names a texture the parse did not read"};
            if (t != &m.opacity_texture && t != &m.emission_texture && !texture_problem(*t).empty())
                throw Damaged{"a material's texture is not one a parse would take"};
        }
        std::string why;
        if (!m.emission_texture.empty() && !(m.emission_map = load_emission_map(m.emission_texture, why)))
            throw Damaged{"a material's emission texture is not one a parse would take"};
        if (m.opacity_texture.empty()) continue;
        // glTF's base colour alpha (AlphaOnly) or a grey map: whichever the parse read.
        m.opacity_map = load_opacity_map(
            m.opacity_texture, m.opacity_texture == m.color_texture ? OpacityChannel::AlphaOnly : OpacityChannel::AlphaOrFirst, why);
        if (!m.opacity_map) throw Damaged{"a material's opacity texture is not one a parse would take"};
    }
}

uint64_t body_hash(const std::string& bytes, size_t from) {
    return OIIO::xxhash::XXH64(bytes.data() + from, bytes.size() - from, kVersion);
}

}  // namespace

MeshCache::MeshCache(std::string folder, std::shared_ptr<FileHashes> hashes) : folder_(std::move(folder)), hashes_(std::move(hashes)) {
    std::error_code ec;
    fs::create_directories(folder_, ec);
    usable_ = !folder_.empty() && fs::is_directory(folder_, ec);
    if (!usable_ && !folder_.empty())
        std::fprintf(stderr, "bounce: the mesh cache %s is not a folder bounce can make (BOUNCE_MESH_CACHE); meshes are parsed\n",
                     folder_.c_str());
}

std::string MeshCache::entry(const MeshCacheKey& key) const {
    Out k;
    write_key(k, key, hash(key.path));
    return (fs::path(folder_) / fmt::format("{:016x}.bmc", OIIO::xxhash::XXH64(k.bytes.data(), k.bytes.size(), kVersion))).string();
}

std::optional<LoadedMeshFile> MeshCache::read(const MeshCacheKey& key) {
    const std::string entry = this->entry(key);
    std::error_code ec;
    if (!fs::exists(fs::symlink_status(entry, ec))) return std::nullopt;
    try {
        if (const std::string why = not_a_regular_file(entry); !why.empty()) throw Damaged{why};
        std::ifstream f(entry, std::ios::binary | std::ios::ate);
        const auto size = static_cast<size_t>(std::max<std::streamoff>(0, f.tellg()));
        if (!memory_shortfall(static_cast<double>(size), "").empty()) throw Damaged{"it is larger than memory"};
        std::string bytes(size, '\0');
        f.seekg(0);
        if (!f.read(bytes.data(), static_cast<std::streamsize>(bytes.size()))) throw Damaged{"it cannot be read"};
        if (bytes.size() < kHeaderBytes || std::memcmp(bytes.data(), kMagic, 8) != 0) throw Damaged{"not a mesh cache entry"};
        In in{bytes.data() + 8, bytes.data() + bytes.size()};
        if (in.pod<uint32_t>() != kVersion) return std::nullopt;  // another version's: rewritten
        in.pod<uint32_t>();
        const auto body = in.pod<uint64_t>(), hash = in.pod<uint64_t>();
        if (body != in.left() || hash != body_hash(bytes, kHeaderBytes)) throw Damaged{"its checksum does not match"};
        Out k;
        write_key(k, key, this->hash(key.path));
        if (in.left() < k.bytes.size() || std::memcmp(in.p, k.bytes.data(), k.bytes.size()) != 0) return std::nullopt;
        in.p += k.bytes.size();
        LoadedMeshFile loaded = read_entry(in, key.overridden);
        for (const auto& [path, hash_then] : loaded.inputs)
            if (this->hash(path) != hash_then) return std::nullopt;  // an MTL or texture changed
        check_textures(loaded);
        ++hits_;
        return loaded;
    } catch (const Damaged& d) {
        say_once(said_damaged_, fmt::format("mesh cache entry {} is damaged ({}); {} is parsed again", entry, d.why, key.path));
        return std::nullopt;
    }
}

void MeshCache::write(const MeshCacheKey& key, const LoadedMeshFile& loaded) {
    const std::string entry = this->entry(key);
    Out out;
    out.bytes.append(kMagic, 8);
    out.pod(kVersion);
    out.pod(uint32_t{0});
    out.pod(uint64_t{0}), out.pod(uint64_t{0});  // body bytes and hash, filled below
    write_key(out, key, hash(key.path));
    write_entry(out, loaded);
    const uint64_t size = out.bytes.size() - kHeaderBytes, hash = body_hash(out.bytes, kHeaderBytes);
    std::memcpy(out.bytes.data() + 16, &size, 8);
    std::memcpy(out.bytes.data() + 24, &hash, 8);
    try {
        remove_stale_temporaries(entry);
        write_atomically(entry, [&](const std::string& tmp) {
            std::ofstream f(tmp, std::ios::binary);
            f.write(out.bytes.data(), static_cast<std::streamsize>(out.bytes.size()));
            if (!f.flush()) throw std::runtime_error("cannot write " + tmp);
        });
        ++writes_;
    } catch (const std::exception& e) {
        say_once(said_unwritable_,
                 fmt::format("mesh cache folder {} cannot take an entry ({}); loads go on without it", folder_, e.what()));
    }
}

}  // namespace bounce
