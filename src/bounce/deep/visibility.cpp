// Primary visibility: subsamples traced against the fine tessellation, merged into fragments.
#include "bounce/deep/deep_buffer.h"

#include <fmt/format.h>

#include <cstring>
#include <numeric>

#include "bounce/core/error.h"
#include "bounce/core/parallel.h"
#include "bounce/core/random.h"
#include "bounce/core/sampling.h"

namespace bounce {

namespace {

struct Accum {
    Vec3 p, n, ng;
    Vec3 p0, ng0;         ///< the first subsample's point and geometric normal: the group's plane
    float off_plane = 0;  ///< largest distance of a merged subsample from that plane
    Vec2 uv;
    uint32_t material, object, prim;
    float depth, footprint;
    int count;
    Vec3 p_base{0}, n_base{0};  ///< sums over the subsamples of a displaced surface
    Vec3 n_base0{0};            ///< the first subsample's (oriented) un-displaced normal
    int based = 0;              ///< subsamples that carried an un-displaced surface
    bool hair = false;          ///< subsamples of one strand (prim = the strand)
    float cover = 0;            ///< the subsamples' shares it covers (1 each but through blended cutouts)
    Vec3 tangent{0};
    float v = 0;
};

/// A camera subsample that hit fur: the strand's point as a (camera-facing) surface point.
/// The normal is the direction to the camera with the tangent's component removed.
SurfacePoint hair_point(const Fur& fur, const Hit& h, const Vec3& o, const Vec3& dn, const TriangleMesh& surface) {
    SurfacePoint sp;
    sp.p = o + dn * h.t;
    const Vec3 t = fur.tangent(h.prim);
    Vec3 n = -dn - t * dot(-dn, t);
    sp.n = sp.ng = dot(n, n) > 1e-12f ? normalize(n) : fur.root_n[fur.strand_of(h.prim)];
    sp.uv = fur.root_uv[fur.strand_of(h.prim)];
    sp.material = surface.face_materials.empty() ? 0 : surface.face_materials[0];
    return sp;
}

}  // namespace

DeepBuffer render_visibility(const Scene& scene, const SceneAccel& accel, const VisibilitySettings& settings, Stats& stats,
                             ProgressSink* sink) {
    return render_visibility(scene, accel, settings, stats, sink, frame_window(scene.camera, settings));
}

std::array<int, 4> frame_window(const Camera& camera, const VisibilitySettings& settings) {
    return settings.has_crop() ? settings.crop : std::array<int, 4>{0, camera.width, 0, camera.height};
}

DeepBuffer sub_window(const DeepBuffer& deep, const std::array<int, 4>& w) {
    if (w[0] == deep.x0 && w[2] == deep.y0 && w[1] - w[0] == deep.width && w[3] - w[2] == deep.height) return deep;
    DeepBuffer out;  // the header only: copying the fragments to clear them cost a frame's worth per tile
    out.full_width = deep.full_width, out.full_height = deep.full_height;
    out.spp = deep.spp, out.seed = deep.seed, out.scene_fingerprint = deep.scene_fingerprint;
    out.x0 = w[0], out.y0 = w[2], out.width = w[1] - w[0], out.height = w[3] - w[2];
    out.offsets.reserve(out.pixel_count() + 1);
    out.offsets.push_back(0);
    for (int y = w[2]; y < w[3]; ++y)
        for (int x = w[0]; x < w[1]; ++x) {
            auto f = deep.pixel(x - deep.x0, y - deep.y0);
            out.fragments.insert(out.fragments.end(), f.begin(), f.end());
            out.offsets.push_back(static_cast<uint32_t>(out.fragments.size()));
        }
    return out;
}

DeepBuffer empty_window(const Scene& scene, const VisibilitySettings& settings, const std::array<int, 4>& window) {
    DeepBuffer deep;
    deep.full_width = scene.camera.width;
    deep.full_height = scene.camera.height;
    deep.x0 = window[0], deep.y0 = window[2];
    deep.width = window[1] - window[0], deep.height = window[3] - window[2];
    deep.spp = settings.spp;
    deep.seed = settings.seed;
    deep.scene_fingerprint = scene.visibility_fingerprint();
    deep.offsets.assign(deep.pixel_count() + 1, 0);
    return deep;
}

namespace {

/// True when something the camera sees lies between its centre and `p` (at the frame's time).
bool hidden(const SceneAccel& accel, const CameraRays& camera, const Vec3& p) {
    const Vec3 o = camera.origin();
    const float dist = length(p - o);
    return dist > 0 && accel.fine().intersect(o, (p - o) / dist, 0, dist * (1 - 1e-5f), 0, kRayCamera).valid();
}

/// How many surfaces one camera subsample passes through (blended cutouts), and the share of
/// it below which what is behind is not looked for: past either the rest shows the background.
constexpr int kMaxLayers = 32;
constexpr float kLeastThrough = 1e-4f;

/// One pixel's camera subsamples grouped into fragments: subsamples of the same surface merge.
class PixelFragments {
  public:
    PixelFragments(const Scene& scene, const SceneAccel& accel, const CameraRays& camera) : scene_(scene), accel_(accel), camera_(camera) {}
    void clear() { groups_.clear(), subsamples_.clear(); }
    /// Hit `h` of the ray leaving `origin` along unit `dn` (pixel direction `d`), reached by
    /// `through` of its subsample: adds what the surface covers of it and returns the surface's
    /// opacity there (1 but for blended cutouts).
    float add(const Hit& h, const Vec3& origin, const Vec3& d, const Vec3& dn, float through);
    /// The pixel's fragments (`spp` subsamples), in the order their groups were made.
    void emit(int spp, std::vector<Fragment>& out) const;

  private:
    const Scene& scene_;
    const SceneAccel& accel_;
    const CameraRays& camera_;
    std::vector<Accum> groups_;
    std::vector<std::pair<Vec3, size_t>> subsamples_;  // (point, group)
};

float PixelFragments::add(const Hit& h, const Vec3& origin, const Vec3& d, const Vec3& dn, float through) {
    const CameraRays& camera = camera_;
    std::vector<Accum>& groups = groups_;
    const Object& obj = scene_.objects[h.object];
    const uint32_t prim = h.hair ? obj.fur->strand_of(h.prim) : h.prim;
    SurfacePoint sp = h.hair ? hair_point(*obj.fur, h, origin, dn, obj.visible()) : obj.visible_point(h.prim, h.u, h.v);
    const Material& material = scene_.materials[sp.material];
    const float alpha = h.hair || material.alpha_mode != AlphaMode::Blend ? 1.0f : material.opacity_at(sp.uv);
    if (!(alpha > 0)) return 0;
    // Face the camera (all surfaces are two-sided).
    if (dot(sp.ng, dn) > 0) sp.ng = -sp.ng, sp.n = -sp.n;
    if (dot(sp.n, dn) > 0) sp.n = normalize(sp.n - dn * (2 * dot(sp.n, dn)));
    float fp = camera.footprint(d, h.t, sp.ng);
    // Merge with a subsample of the same surface: same object and material,
    // similar orientation and depth (so silhouettes of one object stay apart),
    // and within a pixel's width of the group's plane (a step between parallel
    // faces is two surfaces, however close their depths).
    Accum* g = nullptr;
    for (auto& a : groups) {
        if (a.hair != h.hair || (h.hair && (a.object != h.object || a.prim != prim))) continue;
        const float off = std::abs(dot(sp.p - a.p0, a.ng0));
        if (h.hair ||  // subsamples of one strand are one fragment
            (a.object == h.object && a.material == sp.material && dot(normalize(a.ng), sp.ng) > 0.9f &&
             std::abs(a.depth / static_cast<float>(a.count) - h.t) < 0.05f * h.t + 4 * fp && off < fp)) {
            g = &a;
            g->off_plane = std::max(g->off_plane, off / fp);
            break;
        }
    }
    if (!g) {
        groups.push_back({Vec3(0), Vec3(0), Vec3(0), sp.p, sp.ng, 0, {}, sp.material, h.object, prim, 0, 0, 0});
        g = &groups.back();
        g->hair = h.hair;
    }
    subsamples_.emplace_back(sp.p, static_cast<size_t>(g - groups.data()));
    g->p += sp.p, g->n += sp.n, g->ng += sp.ng;
    g->uv.x += sp.uv.x, g->uv.y += sp.uv.y;
    g->depth += h.t;
    ++g->count;
    float spacing_fp = fp;  // the fragment's footprint: where records are spaced
    if (h.hair) {
        g->tangent += obj.fur->tangent(h.prim);
        g->v += obj.fur->v_of(h.prim, h.u);
        g->p_base = obj.fur->root_p[prim], g->n_base = obj.fur->root_n[prim];
    } else if (obj.visible().displaced()) {
        auto [pb, nb] = base_point(obj.visible(), h.prim, h.u, h.v);
        // On the side of the displaced normal seen: at a silhouette a bump can face
        // the camera where the smooth surface under it does not, and flipping Nref
        // towards the camera there turned the records' hemisphere inside the
        // model (black blotches on a displaced ball's outline).
        const Vec3 o = dot(nb, sp.n) < 0 ? -nb : nb;
        if (g->based++ == 0) g->n_base0 = o;
        g->p_base += pb, g->n_base += o;
        // Records are spaced on the un-displaced surface: its footprint, not
        // the bump's (a bump seen edge-on would pack them).
        spacing_fp = camera.footprint(d, h.t, o);
    }
    g->footprint += spacing_fp;
    g->cover += through * alpha;
    return alpha;
}

void PixelFragments::emit(int spp, std::vector<Fragment>& out) const {
    const std::vector<Accum>& groups = groups_;
    for (size_t gi = 0; gi < groups.size(); ++gi) {
        const Accum& a = groups[gi];
        auto c = static_cast<float>(a.count);
        Fragment f;
        // A planar group sits at its centroid. Otherwise the centroid can lie off
        // every surface (inside a convex ridge, between offset faces), or on its
        // plane but behind another surface of the pixel (what is seen of a ceiling
        // around a light's corner is not convex), where a gather sees only the back
        // of what hides it: take the subsample nearest it. (Not at every edge: the
        // subsample taken changes from frame to frame where the centroid does not.)
        const Vec3 centroid = a.p / c;
        f.p = centroid;
        if (a.off_plane > 1e-3f || (groups.size() > 1 && !a.hair && hidden(accel_, camera_, centroid))) {
            float best = INFINITY;
            for (const auto& [q, group] : subsamples_) {
                const float dist = length(q - centroid);
                if (group == gi && dist < best) best = dist, f.p = q;
            }
        }
        f.n = normalize(a.n);
        f.ng = normalize(a.ng);
        // Cache records live on the un-displaced surface when there is one.
        // (Across a fold the subsamples' orientations can cancel: keep the first's.)
        f.p_base = a.based ? a.p_base / static_cast<float>(a.based) : f.p;
        f.n_base = !a.based ? f.n : dot(a.n_base, a.n_base) > 1e-12f ? normalize(a.n_base) : a.n_base0;
        if (a.hair) {
            f.p_base = a.p_base, f.n_base = a.n_base;
            f.tangent = dot(a.tangent, a.tangent) > 0 ? normalize(a.tangent) : a.n_base;
            f.strand_v = a.v / c;
        }
        f.uv = {a.uv.x / c, a.uv.y / c};
        f.material = a.material, f.object = a.object, f.prim = a.prim;
        f.depth = a.depth / c;
        f.weight = a.cover / static_cast<float>(spp);
        f.footprint = a.footprint / c;
        out.push_back(f);
    }
}

}  // namespace

DeepBuffer render_visibility(const Scene& scene, const SceneAccel& accel, const VisibilitySettings& rs, Stats& stats, ProgressSink* sink,
                             const std::array<int, 4>& window) {
    const Camera& cam = scene.camera;
    DeepBuffer deep = empty_window(scene, rs, window);

    CameraRays camera(cam);
    const int spp = rs.spp;
    const bool blur = cam.has_motion_blur();
    std::vector<std::vector<Fragment>> per_pixel(deep.pixel_count());
    Progress progress(sink, "visibility", static_cast<uint64_t>(deep.height));

    parallel_ranges(0, deep.height, 1, [&](int row0, int row1) {
        Counters& counters = stats.local();
        PixelFragments pixel(scene, accel, camera);
        std::vector<int> time_strata(static_cast<size_t>(spp));
        for (int wy = row0; wy < row1; ++wy) {
            for (int wx = 0; wx < deep.width; ++wx) {
                int x = wx + deep.x0, y = wy + deep.y0;
                RandomStream rng(rs.seed, static_cast<uint64_t>(y) * 65536u + static_cast<uint64_t>(x));
                pixel.clear();
                // Motion blur: every time stratum once, in an order shuffled per pixel, so a
                // subsample's time says nothing of where in the pixel it lies.
                if (blur) {
                    std::iota(time_strata.begin(), time_strata.end(), 0);
                    for (size_t i = time_strata.size(); i-- > 1;)
                        std::swap(time_strata[i], time_strata[rng.bits(i, kDimTimeStratum) % (i + 1)]);
                }
                for (int s = 0; s < spp; ++s) {
                    const auto su = static_cast<uint64_t>(s);
                    Vec2 j = stratified_2d(s, spp, rng.get(su, kDimPixelX), rng.get(su, kDimPixelY));
                    const float px = static_cast<float>(x) + j.x, py = static_cast<float>(y) + j.y;
                    Vec3 d = camera.direction(px, py), dn;
                    // Depth of field: the ray leaves a point of the lens; motion blur: it sees the
                    // scene at its time in the shutter. Shading stays at the frame's time.
                    const float time =
                        blur ? (static_cast<float>(time_strata[su]) + rng.get(su, kDimTime)) / static_cast<float>(spp) : 0.0f;
                    const Vec3 origin = camera.lens_ray(px, py, rng.get(su, kDimLensU), rng.get(su, kDimLensV), dn, time);
                    // Blended cutouts cover their share of the subsample and let the rest on.
                    float through = 1, tnear = 0;
                    for (int layer = 0; layer < kMaxLayers && through > kLeastThrough; ++layer) {
                        ++counters.camera_rays;
                        const Hit h = accel.fine().intersect(origin, dn, tnear, INFINITY, time, kRayCamera);
                        if (!h.valid()) break;
                        through *= 1 - pixel.add(h, origin, d, dn, through);
                        tnear = h.t + std::max(1e-4f, 1e-5f * h.t);
                    }
                }
                auto& out = per_pixel[static_cast<size_t>(wy) * deep.width + wx];
                pixel.emit(spp, out);
                // Front to back, as deep compositing expects.
                std::stable_sort(out.begin(), out.end(), [](const Fragment& a, const Fragment& b) { return a.depth < b.depth; });
            }
            progress.add();
        }
    });

    deep.offsets.resize(deep.pixel_count() + 1);
    deep.offsets[0] = 0;
    for (size_t i = 0; i < per_pixel.size(); ++i) deep.offsets[i + 1] = deep.offsets[i] + static_cast<uint32_t>(per_pixel[i].size());
    deep.fragments.reserve(deep.offsets.back());
    for (auto& v : per_pixel) deep.fragments.insert(deep.fragments.end(), v.begin(), v.end());
    stats.set("fragments", static_cast<double>(deep.fragments.size()));
    return deep;
}

std::string serialize_window(const DeepBuffer& d) {
    std::string out;
    const auto put = [&out](const void* p, size_t n) { out.append(static_cast<const char*>(p), n); };
    const int64_t head[8] = {d.full_width, d.full_height, d.x0, d.y0, d.width, d.height, d.spp, static_cast<int64_t>(d.fragments.size())};
    put(head, sizeof(head));
    put(&d.seed, sizeof(d.seed)), put(&d.scene_fingerprint, sizeof(d.scene_fingerprint));
    put(d.offsets.data(), d.offsets.size() * sizeof(uint32_t));
    put(d.fragments.data(), d.fragments.size() * sizeof(Fragment));  // a trivially copyable struct, same build
    return out;
}

DeepBuffer parse_window(const std::string& bytes) {
    DeepBuffer d;
    int64_t head[8];
    size_t at = 0;
    const auto get = [&](void* p, size_t n) {
        if (at + n > bytes.size()) throw std::runtime_error("truncated deep window from another process");
        std::memcpy(p, bytes.data() + at, n);
        at += n;
    };
    get(head, sizeof(head));
    d.full_width = static_cast<int>(head[0]), d.full_height = static_cast<int>(head[1]), d.x0 = static_cast<int>(head[2]);
    d.y0 = static_cast<int>(head[3]), d.width = static_cast<int>(head[4]), d.height = static_cast<int>(head[5]),
    d.spp = static_cast<int>(head[6]);
    get(&d.seed, sizeof(d.seed)), get(&d.scene_fingerprint, sizeof(d.scene_fingerprint));
    d.offsets.resize(d.pixel_count() + 1);
    get(d.offsets.data(), d.offsets.size() * sizeof(uint32_t));
    d.fragments.resize(static_cast<size_t>(head[7]));
    get(d.fragments.data(), d.fragments.size() * sizeof(Fragment));
    return d;
}

DeepBuffer assemble_tiles(const Scene& scene, const VisibilitySettings& settings, const std::array<int, 4>& w,
                          const std::vector<DeepBuffer>& tiles) {
    DeepBuffer out = empty_window(scene, settings, w);
    std::vector<uint32_t> count(out.pixel_count(), 0);
    const auto at = [&](const DeepBuffer& t, int x, int y) {
        return static_cast<size_t>(t.y0 + y - out.y0) * out.width + static_cast<size_t>(t.x0 + x - out.x0);
    };
    for (const DeepBuffer& t : tiles)
        for (int y = 0; y < t.height; ++y)
            for (int x = 0; x < t.width; ++x) count[at(t, x, y)] = static_cast<uint32_t>(t.pixel(x, y).size());
    for (size_t i = 0; i < count.size(); ++i) out.offsets[i + 1] = out.offsets[i] + count[i];
    out.fragments.resize(out.offsets.back());
    for (const DeepBuffer& t : tiles)
        for (int y = 0; y < t.height; ++y)
            for (int x = 0; x < t.width; ++x) {
                const auto f = t.pixel(x, y);
                std::copy(f.begin(), f.end(), out.fragments.begin() + out.offsets[at(t, x, y)]);
            }
    return out;
}

void check_camera_sees_geometry(const Scene& scene, const SceneAccel& accel) {
    CameraRays camera(scene.camera);
    const int n = 48;
    for (int j = 0; j < n; ++j)
        for (int i = 0; i < n; ++i) {
            float px = (static_cast<float>(i) + 0.5f) / n * static_cast<float>(scene.camera.width);
            float py = (static_cast<float>(j) + 0.5f) / n * static_cast<float>(scene.camera.height);
            if (accel.fine().intersect(camera.origin(), normalize(camera.direction(px, py)), 0, INFINITY).valid()) return;
        }
    const Vec3 &p = scene.camera.position, &l = scene.camera.look_at;
    throw InputError(scene.path, "/camera",
                     fmt::format("the camera at ({}, {}, {}) looking at ({}, {}, {}) sees no geometry", p.x, p.y, p.z, l.x, l.y, l.z));
}

}  // namespace bounce
