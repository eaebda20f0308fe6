#include "bounce/radiosity/radiosity.h"

#include <OpenImageIO/hash.h>
#include <OpenImageIO/imageio.h>
#include <fmt/format.h>

#include <bit>
#include <chrono>
#include <filesystem>
#include <optional>
#include <thread>

#include "bounce/core/atomic_file.h"
#include "bounce/core/error.h"
#include "bounce/core/image_input.h"
#include "bounce/core/parallel.h"
#include "bounce/core/random.h"

namespace bounce {

namespace fs = std::filesystem;

namespace {

constexpr int kRadiosityVersion = 2;  // 2: per-side "baked" flags (lazy bakes)

/// Index of lattice point (i, j) (i + j <= n) in a triangle's block.
inline uint32_t lattice_index(int i, int j, int n) { return static_cast<uint32_t>(j * (n + 1) - j * (j - 1) / 2 + i); }

float effective_texel(const Scene& scene, const RadiositySettings& s) { return s.texel > 0 ? s.texel : scene.size() / 128.0f; }

int effective_light_samples(const RadiositySettings& s, int lighting_samples) {
    return s.light_samples > 0 ? s.light_samples : lighting_samples;
}

std::string file_name(size_t id, const std::string& name) {
    std::string safe;
    for (char c : name) safe += std::isalnum(static_cast<unsigned char>(c)) || c == '_' || c == '-' ? c : '_';
    return fmt::format("radiosity.{:04}.{}.exr", id, safe);
}

/// An upper bound on how much `t` lengthens any vector: its linear part's Frobenius norm (at
/// least its largest singular value; Transform::largest_scale, the longest image of an axis,
/// is not a bound under shear); 1 for no transform.
float stretch_bound(const Transform* t) {
    if (!t) return 1;
    const Vec3 x = t->vector({1, 0, 0}), y = t->vector({0, 1, 0}), z = t->vector({0, 0, 1});
    return std::sqrt(dot(x, x) + dot(y, y) + dot(z, z));
}

/// Triangle t's longest edge, placed by `to_world` (null: in the mesh's own space).
float longest_edge(const TriangleMesh& m, const Transform* to_world, uint32_t t) {
    const auto [a, b, c] = triangle_vertices(m, to_world, t);
    return std::max({length(b - a), length(c - b), length(a - c)});
}

/// Object `o`'s lattice levels (an instance's each its own: texels follow its placement's
/// scale; a prototype, never placed, has none), triangle by triangle.
std::vector<uint8_t> lattice_levels(const Object& o, float texel, int max_level) {
    std::vector<uint8_t> level;
    if (!o.placed()) return level;
    const TriangleMesh& m = o.coarse_mesh();
    level.resize(m.triangle_count());
    for (uint32_t t = 0; t < m.triangle_count(); ++t)
        level[t] = static_cast<uint8_t>(radiosity_level(longest_edge(m, o.to_world(), t), texel, max_level));
    return level;
}

}  // namespace

int radiosity_level(float edge, float texel, int max_level) {
    // An edge a whole number of texels long (authored sizes often are) sat on ceil's step: a
    // placement that rounds it one ulp longer got a finer lattice and 4 % other bounce light
    // (a glTF GPU instance against the same node). A step only past 1e-4 above it.
    return std::clamp(static_cast<int>(std::ceil(edge / texel * (1 - 1e-4f))), 1, max_level);
}

namespace {

/// The three lattice points (within the triangle's run) whose values are interpolated at (u, v) of triangle `prim`, and their weights.
struct LatticeBlend {
    uint32_t k[3];
    float w[3];
};

LatticeBlend lattice_blend(const RadiosityMap& m, uint32_t prim, float u, float v) {
    const int n = m.level[prim];
    float fu = std::clamp(u, 0.0f, 1.0f) * static_cast<float>(n), fv = std::clamp(v, 0.0f, 1.0f) * static_cast<float>(n);
    int i = std::min(static_cast<int>(fu), n - 1), j = std::min(static_cast<int>(fv), n - 1);
    if (i + j > n - 1) {  // on the far edge of the triangle
        int over = i + j - (n - 1);
        (i >= over ? i : j) -= over;
    }
    float a = fu - static_cast<float>(i), b = fv - static_cast<float>(j);
    if (a + b <= 1 || i + j >= n - 1)  // lower sub-triangle (i,j) (i+1,j) (i,j+1)
        return {{lattice_index(i, j, n), lattice_index(i + 1, j, n), lattice_index(i, j + 1, n)}, {1 - a - b, a, b}};
    // upper sub-triangle (i+1,j+1) (i,j+1) (i+1,j)
    return {{lattice_index(i + 1, j + 1, n), lattice_index(i, j + 1, n), lattice_index(i + 1, j, n)}, {a + b - 1, 1 - a, 1 - b}};
}

}  // namespace

Color RadiosityMap::lookup(uint32_t prim, float u, float v, bool front_side) const {
    const Color* vals = (front_side ? front : back).run(prim, offset[prim]);
    if (!vals) return Color(0);  // (never baked: lookups bake first)
    const LatticeBlend b = lattice_blend(*this, prim, u, v);
    return vals[b.k[0]] * b.w[0] + vals[b.k[1]] * b.w[1] + vals[b.k[2]] * b.w[2];
}

void RadiosityMap::lookup_parts(uint32_t prim, float u, float v, bool front_side, std::span<Color> out) const {
    const Color* vals = (front_side ? front_parts : back_parts).run(prim, offset[prim]);
    if (!vals) return std::fill(out.begin(), out.end(), Color(0));
    const LatticeBlend b = lattice_blend(*this, prim, u, v);
    for (size_t l = 0; l < lights; ++l)
        out[l] = vals[b.k[0] * lights + l] * b.w[0] + vals[b.k[1] * lights + l] * b.w[1] + vals[b.k[2] * lights + l] * b.w[2];
}

/// Bumped when the bake's values change for the same scene (a saved folder of another is stale):
/// 2, its lattice levels off ceil's step; 3, a glTF file's diffuse transmission read.
constexpr uint64_t kBakeVersion = 3;

uint64_t RadiosityTextures::fingerprint(const Scene& scene, const RadiositySettings& s, int light_samples) {
    uint64_t h =
        hash_combine(scene.fingerprint({"objects", "materials", "lights"}, true), kBakeVersion);  // gloss, bumps, baked AO: not in the bake
    h = hash_combine(h, std::bit_cast<uint32_t>(effective_texel(scene, s)));
    h = hash_combine(h, static_cast<uint64_t>(effective_light_samples(s, light_samples)));
    return hash_combine(h, static_cast<uint64_t>(s.max_level));
}

size_t RadiosityTextures::lattice_points() const {
    size_t n = 0;
    for (const auto& m : maps_) n += m.front.points();
    return n;
}

size_t RadiosityTextures::allocated_bytes() const {
    size_t n = 0;
    for (const auto& m : maps_)
        n += m.front.allocated_bytes() + m.back.allocated_bytes() + m.front_parts.allocated_bytes() + m.back_parts.allocated_bytes();
    return n;
}

RadiosityTextures::RadiosityTextures() = default;
RadiosityTextures::~RadiosityTextures() = default;
RadiosityTextures::RadiosityTextures(RadiosityTextures&&) noexcept = default;
RadiosityTextures& RadiosityTextures::operator=(RadiosityTextures&&) noexcept = default;

RadiosityTextures::Layout RadiosityTextures::shared_layout(std::vector<uint8_t> level) {
    auto& alike = layouts_[OIIO::xxhash::XXH64(level.data(), level.size(), level.size())];
    for (const Layout& known : alike)
        if (known.first.vec() == level) return known;
    std::vector<uint32_t> offset(level.size());
    uint32_t off = 0;
    for (size_t t = 0; t < level.size(); ++t) offset[t] = off, off += lattice_count(level[t]);
    alike.emplace_back(SharedArray<uint8_t>(std::make_shared<const std::vector<uint8_t>>(std::move(level))),
                       SharedArray<uint32_t>(std::make_shared<const std::vector<uint32_t>>(std::move(offset))));
    return alike.back();
}

bool RadiosityTextures::lit_at_hit(const Scene& scene, size_t id, const RadiositySettings& settings, const HitProbe* probe) const {
    switch (settings.small_instances) {
        case SmallInstanceLight::Hit:
            return true;
        case SmallInstanceLight::Lattice:
            return false;
        case SmallInstanceLight::Auto:
            break;
    }
    if (!probe) return false;  // no gathers to weigh
    // A lattice costs its 3 points' light samples on every side a gather hits, the hit one
    // sample: the hit wins below 3 x samples hits per side. Counted per triangle (a closed
    // mesh shows a ray one side of it), so a near, often hit placement keeps its lattice.
    const double expected = probe->hits_at_most(id, settings.pixel_gather_rays);
    return expected < 3.0 * sources_->light_samples * static_cast<double>(scene.objects[id].coarse_mesh().triangle_count());
}

RadiosityMap RadiosityTextures::laid_out(const Scene& scene, size_t id, const RadiositySettings& settings, const HitProbe* probe) {
    const Object& o = scene.objects[id];
    const TriangleMesh& mesh = o.coarse_mesh();
    auto [known, added] = longest_edges_.emplace(&mesh, 0.0f);
    if (added)
        for (uint32_t t = 0; t < mesh.triangle_count(); ++t) known->second = std::max(known->second, longest_edge(mesh, nullptr, t));
    RadiosityMap m;
    bool ones = false;  // level 1 throughout
    if (o.placed() && known->second * stretch_bound(o.to_world()) < 0.99f * texel_size_) {
        // A placement that cannot stretch any edge to a texel is level 1 throughout, as each
        // triangle would compute (the 1 % margin is far beyond rounding), and shares the one
        // such layout of its triangle count: most of an instanced forest, whose levels took
        // 17.6 s of the big scene's layout one by one, and 3.7 s as arrays filled and compared.
        ones = true;
        Layout& one = ones_[mesh.triangle_count()];
        if (one.first.size() != mesh.triangle_count()) one = shared_layout(std::vector<uint8_t>(mesh.triangle_count(), 1));
        std::tie(m.level, m.offset) = one;
    } else {
        std::vector<uint8_t> level = lattice_levels(o, texel_size_, settings.max_level);
        ones = !level.empty() && std::all_of(level.begin(), level.end(), [](uint8_t l) { return l == 1; });
        std::tie(m.level, m.offset) = shared_layout(std::move(level));
    }
    m.lit_at_hit = o.instance && ones && lit_at_hit(scene, id, settings, probe);
    if (m.lit_at_hit) return m;  // no values, not even a pointer per page
    const uint32_t points = m.level.size() ? m.offset[m.level.size() - 1] + lattice_count(m.level[m.level.size() - 1]) : 0;
    m.front.lay_out(m.offset.shared(), points, 1);
    m.back.lay_out(m.offset.shared(), points, 1);
    if (has_parts()) {
        m.lights = static_cast<uint32_t>(scene.lights.size());
        m.front_parts.lay_out(m.offset.shared(), points, m.lights);
        m.back_parts.lay_out(m.offset.shared(), points, m.lights);
    }
    return m;
}

RadiosityTextures RadiosityTextures::lazy(const Scene& scene, const Materials& materials, const DirectLighting& lighting,
                                          const RadiositySettings& settings) {
    RadiosityTextures rt;
    rt.texel_size_ = effective_texel(scene, settings);
    const int samples = lighting.settings().light_samples;
    rt.fingerprint_ = fingerprint(scene, settings, samples);
    rt.sources_ = std::make_unique<Sources>(Sources{&scene, &materials, &lighting, effective_light_samples(settings, samples), {}});
    if (settings.light_parts) rt.sources_->scales = light_scales(scene);
    // Small instances in auto weigh a probe of the frame's gathers (only where there are any).
    std::optional<HitProbe> probe;
    if (settings.small_instances == SmallInstanceLight::Auto && settings.pixel_gather_rays > 0 &&
        std::any_of(scene.objects.begin(), scene.objects.end(), [](const Object& o) { return o.instance; }))
        probe = probe_gather_hits(scene, lighting.accel());
    for (size_t id = 0; id < scene.objects.size(); ++id) {
        rt.maps_.push_back(rt.laid_out(scene, id, settings, probe ? &*probe : nullptr));
        rt.state_.emplace_back(rt.maps_.back().sides_baked_apart());
        rt.names_.push_back(scene.objects[id].name);
    }
    return rt;
}

void RadiosityTextures::bake_side(uint32_t id, uint32_t t, bool front, Counters& counters) const {
    const Sources& src = *sources_;
    const Object& o = src.scene->objects[id];
    RadiosityMap& map = maps_[id];
    const int n = map.level[t];
    Color* values = (front ? map.front : map.back).writable_run(t, map.offset[t]);
    Color* part_values = map.lights ? (front ? map.front_parts : map.back_parts).writable_run(t, map.offset[t]) : nullptr;
    for (int j = 0; j <= n; ++j)
        for (int i = 0; i + j <= n; ++i) {
            float u = static_cast<float>(i) / static_cast<float>(n), v = static_cast<float>(j) / static_cast<float>(n);
            uint32_t k = map.offset[t] + lattice_index(i, j, n);
            // Random numbers keyed by (object, triangle, point): the textures depend on the
            // scene alone (renders with other seeds share them) and not on the bake order.
            // Geometric normal: the value must not depend on which side's shading normal a hit
            // happens to use.
            const RandomStream rng = front ? RandomStream(0, (static_cast<uint64_t>(id) << 40) | (static_cast<uint64_t>(t) << 12), k)
                                           : RandomStream(1, (static_cast<uint64_t>(id) << 40) | t, k);
            const std::span<Color> parts =
                part_values ? std::span<Color>(part_values + size_t{k - map.offset[t]} * map.lights, map.lights) : std::span<Color>();
            values[k - map.offset[t]] = side_radiance(id, o.coarse_point(t, u, v), front, rng, src.light_samples, counters, parts);
        }
}

Color RadiosityTextures::side_radiance(uint32_t id, const SurfacePoint& sp, bool front, const RandomStream& rng, int samples,
                                       Counters& counters, std::span<Color> parts) const {
    const Sources& src = *sources_;
    const Color albedo = src.materials->secondary_albedo(sp) * kInvPi, through = src.materials->secondary_translucency(sp) * kInvPi;
    const Vec3 ng = front ? sp.ng : -sp.ng;
    if (src.scales.empty()) return src.lighting->diffuse_radiance(sp.p, ng, id, albedo, through, rng, samples, counters);
    // Per light, scales factored out; the value is their scaled sum (as records' are).
    src.lighting->diffuse_radiance(sp.p, ng, id, albedo, through, rng, samples, counters, parts);
    Color value(0);
    for (size_t l = 0; l < parts.size(); ++l) value += parts[l] * src.scales[l];
    return value;
}

void RadiosityTextures::ensure_baked(uint32_t id, uint32_t tri, bool front, Counters& counters) const {
    std::atomic<uint8_t>& st = state_[id].at(2 * tri + (front ? 0 : 1));
    if (st.load(std::memory_order_acquire) == 2) return;
    uint8_t expected = 0;
    if (st.compare_exchange_strong(expected, 1, std::memory_order_acq_rel)) {
        const auto t0 = std::chrono::steady_clock::now();
        bake_side(id, tri, front, counters);
        st.store(2, std::memory_order_release);
        counters.radiosity_bake_ns +=
            static_cast<uint64_t>(std::chrono::duration_cast<std::chrono::nanoseconds>(std::chrono::steady_clock::now() - t0).count());
        return;
    }
    while (st.load(std::memory_order_acquire) != 2) std::this_thread::yield();  // another thread bakes it
}

Color RadiosityTextures::light_at_hit(uint32_t id, uint32_t prim, float u, float v, bool front, Counters& counters,
                                      std::span<Color> parts) const {
    const auto t0 = std::chrono::steady_clock::now();
    // Keyed by the hit (object, triangle, side, where on it), as the bake keys its points: a
    // re-shade of kept hits, another process or the lighting tool finds the same value.
    const RandomStream rng(front ? 2 : 3, (static_cast<uint64_t>(id) << 32) | prim,
                           (static_cast<uint64_t>(std::bit_cast<uint32_t>(u)) << 32) | std::bit_cast<uint32_t>(v));
    thread_local std::vector<Color> own;  // textures with parts read whole: the parts their sum is made of
    if (parts.empty() && !sources_->scales.empty()) own.assign(sources_->scales.size(), Color(0)), parts = own;
    const Color value = side_radiance(id, sources_->scene->objects[id].coarse_point(prim, u, v), front, rng, 1, counters, parts);
    counters.hits_lit += 1;
    counters.hits_lit_ns +=
        static_cast<uint64_t>(std::chrono::duration_cast<std::chrono::nanoseconds>(std::chrono::steady_clock::now() - t0).count());
    return value;
}

Color RadiosityTextures::lookup(uint32_t id, uint32_t prim, float u, float v, bool front, Counters& counters) const {
    if (maps_[id].lit_at_hit) return light_at_hit(id, prim, u, v, front, counters, {});
    ensure_baked(id, prim, front, counters);
    return maps_[id].lookup(prim, u, v, front);
}

void RadiosityTextures::lookup_parts(uint32_t id, uint32_t prim, float u, float v, bool front, Counters& counters,
                                     std::span<Color> out) const {
    if (maps_[id].lit_at_hit) {
        light_at_hit(id, prim, u, v, front, counters, out);
        return;
    }
    ensure_baked(id, prim, front, counters);
    maps_[id].lookup_parts(prim, u, v, front, out);
}

size_t RadiosityTextures::baked_sides() const {
    size_t n = 0;
    for (size_t id = 0; id < state_.size(); ++id)
        for (size_t i = 0; i < 2 * maps_[id].level.size(); ++i) n += state_[id].load(i, std::memory_order_relaxed) == 2;
    return n;
}

size_t RadiosityTextures::objects_lit_at_hit() const {
    return static_cast<size_t>(std::count_if(maps_.begin(), maps_.end(), [](const RadiosityMap& m) { return m.lit_at_hit; }));
}

size_t RadiosityTextures::sides() const {
    size_t n = 0;
    for (const auto& m : maps_) n += 2 * m.level.size();
    return n;
}

void RadiosityTextures::bake_all(Stats& stats, ProgressSink* sink, int share, int shares) {
    size_t total_tris = 0;
    for (const auto& m : maps_) total_tris += m.level.size();
    Progress progress(sink, "radiosity", total_tris);
    const auto count = static_cast<size_t>(std::max(shares, 1));
    size_t first = 0;  // the object's first triangle, counted over all objects
    for (size_t id = 0; id < maps_.size(); first += maps_[id].level.size(), ++id) {
        parallel_ranges(size_t{0}, maps_[id].level.size(), size_t{64}, [&](size_t lo, size_t hi) {
            Counters& counters = stats.local();
            for (size_t t = lo; t < hi; ++t) {
                if ((first + t) % count != static_cast<size_t>(share) || maps_[id].lit_at_hit) continue;
                ensure_baked(static_cast<uint32_t>(id), static_cast<uint32_t>(t), true, counters);
                ensure_baked(static_cast<uint32_t>(id), static_cast<uint32_t>(t), false, counters);
            }
            progress.add(hi - lo);
        });
    }
}

RadiosityTextures RadiosityTextures::bake(const Scene& scene, const Materials& materials, const DirectLighting& lighting,
                                          const RadiositySettings& settings, Stats& stats, ProgressSink* sink) {
    RadiosityTextures rt = lazy(scene, materials, lighting, settings);
    rt.bake_all(stats, sink);
    stats.set("radiosity_points", static_cast<double>(rt.lattice_points()));
    return rt;
}

void RadiosityTextures::save(const std::string& dir) const {
    std::error_code ec;
    fs::create_directories(dir, ec);
    if (ec) throw InputError(dir, "", "cannot create radiosity texture folder: " + ec.message());
    for (size_t id = 0; id < maps_.size(); ++id) {
        const RadiosityMap& m = maps_[id];
        // Texels in lattice order, 1024 wide: RGB front, RGB back, and whether each side of
        // the point's triangle is baked (A = 1) or left for whoever loads the file.
        const int width = 1024;
        size_t count = m.front.points();
        int height = static_cast<int>((count + width - 1) / width);
        OIIO::ImageSpec spec(width, std::max(1, height), 8, OIIO::TypeDesc::FLOAT);
        spec.channelnames = {"front.R", "front.G", "front.B", "back.R", "back.G", "back.B", "front.A", "back.A"};
        spec.attribute("compression", "zip");
        spec.attribute("bounce:radiosity_version", kRadiosityVersion);
        spec.attribute("bounce:fingerprint", fmt::format("{:016x}", fingerprint_));
        spec.attribute("bounce:object", names_[id]);
        spec.attribute("bounce:triangles", static_cast<int>(m.level.size()));
        spec.attribute("bounce:points", static_cast<int>(count));
        spec.attribute("bounce:texel_size", texel_size_);
        spec.attribute("bounce:lit_at_hit", m.lit_at_hit ? 1 : 0);  // no points: another render may bake them
        std::vector<float> px(static_cast<size_t>(width) * std::max(1, height) * 8, 0.0f);
        for (size_t t = 0; t < m.level.size() && !m.lit_at_hit; ++t) {
            const bool f = state_[id].load(2 * t, std::memory_order_acquire) == 2;
            const bool b = state_[id].load(2 * t + 1, std::memory_order_acquire) == 2;
            const uint32_t first = m.offset[t];
            const Color *fv = f ? m.front.run(static_cast<uint32_t>(t), first) : nullptr,
                        *bv = b ? m.back.run(static_cast<uint32_t>(t), first) : nullptr;
            for (uint32_t k = first; k < first + lattice_count(m.level[t]); ++k) {
                for (int c = 0; c < 3; ++c) px[8 * k + c] = fv ? fv[k - first][c] : 0, px[8 * k + 3 + c] = bv ? bv[k - first][c] : 0;
                px[8 * k + 6] = f, px[8 * k + 7] = b;
            }
        }
        std::string path = (fs::path(dir) / file_name(id, names_[id])).string();
        write_atomically(path, [&](const std::string& tmp) {
            auto out = OIIO::ImageOutput::create("openexr");
            if (!out || !out->open(tmp, spec) || !out->write_image(OIIO::TypeDesc::FLOAT, px.data()) || !out->close())
                throw InputError(path, "", "cannot write radiosity texture: " + (out ? out->geterror() : OIIO::geterror()));
        });
    }
}

bool RadiosityTextures::load(const std::string& dir, const Scene& scene, const RadiositySettings& settings, const Materials& materials,
                             const DirectLighting& lighting, RadiosityTextures& out, std::string& why) {
    RadiosityTextures rt = lazy(scene, materials, lighting, settings);
    for (size_t id = 0; id < scene.objects.size(); ++id) {
        std::string path = (fs::path(dir) / file_name(id, scene.objects[id].name)).string();
        std::error_code ec;
        if (!fs::is_regular_file(path, ec)) {
            why = "no texture for object \"" + scene.objects[id].name + "\"";
            return false;
        }
        std::string unreadable;
        auto in = open_image(path, unreadable);
        if (!in) throw InputError(path, "", "cannot read radiosity texture: " + unreadable);
        const OIIO::ImageSpec& spec = in->spec();
        if (spec.get_int_attribute("bounce:radiosity_version", -1) != kRadiosityVersion) {
            why = "textures were written by another version of bounce";
            return false;
        }
        if (spec.get_string_attribute("bounce:fingerprint") != fmt::format("{:016x}", rt.fingerprint_)) {
            why = "textures were baked for other geometry, materials, lights or settings";
            return false;
        }
        RadiosityMap& map = rt.maps_[id];
        // A small instance lit at the hit here reads nothing; one lit at the hit when saved
        // (another camera's probe) holds nothing, and its sides bake here as gathers need them.
        if (map.lit_at_hit) continue;
        if (spec.get_int_attribute("bounce:lit_at_hit", 0) == 1) {
            if (spec.get_int_attribute("bounce:points", -1) != 0)
                throw InputError(path, "bounce:points", "a small instance lit at the hit holds no points");
            continue;
        }
        const auto off = static_cast<uint32_t>(map.front.points());
        if (spec.nchannels != 8 || spec.get_int_attribute("bounce:points", -1) != static_cast<int>(off) ||
            static_cast<size_t>(spec.width) * spec.height < off)
            throw InputError(path, "bounce:points", "texture size does not match the scene's triangles");
        std::vector<float> px(static_cast<size_t>(spec.width) * spec.height * 8);
        if (!in->read_image(0, 0, 0, 8, OIIO::TypeDesc::FLOAT, px.data()))
            throw InputError(path, "", "cannot read radiosity texture: " + in->geterror());
        // OpenEXR sorts channels by name: find ours.
        int ch[8];
        const char* names[8] = {"front.R", "front.G", "front.B", "back.R", "back.G", "back.B", "front.A", "back.A"};
        for (int c = 0; c < 8; ++c) {
            ch[c] = spec.channelindex(names[c]);
            if (ch[c] < 0) throw InputError(path, "channels", std::string("missing channel ") + names[c]);
        }
        for (size_t k = 0; k < off; ++k)
            for (int c = 0; c < 6; ++c)
                if (!std::isfinite(px[8 * k + static_cast<size_t>(ch[c])]))
                    throw InputError(path, fmt::format("texel {}", k), "non-finite radiosity value");
        // A side is baked when its first point says so; only baked sides take values (and pages).
        for (uint32_t t = 0; t < map.level.size(); ++t)
            for (int side = 0; side < 2; ++side) {
                const uint32_t first = map.offset[t];
                if (px[8 * first + static_cast<size_t>(ch[6 + side])] != 1) continue;
                Color* v = (side == 0 ? map.front : map.back).writable_run(t, first);
                for (uint32_t k = first; k < first + lattice_count(map.level[t]); ++k)
                    v[k - first] = {px[8 * k + static_cast<size_t>(ch[3 * side])], px[8 * k + static_cast<size_t>(ch[3 * side + 1])],
                                    px[8 * k + static_cast<size_t>(ch[3 * side + 2])]};
                rt.state_[id].store(2 * t + static_cast<size_t>(side), 2, std::memory_order_relaxed);
            }
    }
    out = std::move(rt);
    return true;
}

}  // namespace bounce
