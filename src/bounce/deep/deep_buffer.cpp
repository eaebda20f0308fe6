#include "bounce/deep/deep_buffer.h"

#include <OpenImageIO/deepdata.h>
#include <OpenImageIO/imageio.h>
#include <fmt/format.h>

#include "bounce/core/atomic_file.h"
#include "bounce/core/error.h"
#include "bounce/core/files.h"
#include "bounce/core/parallel.h"
#include "bounce/core/random.h"
#include "bounce/core/sampling.h"

namespace bounce {

// ------------------------------------------------------------------------------------------
// Camera

CameraRays::CameraRays(const Camera& cam) : pos_(cam.position), width_(cam.width), height_(cam.height) {
    forward_ = normalize(cam.look_at - cam.position);
    right_ = normalize(cross(forward_, cam.up));
    up_ = cross(right_, forward_);
    scale_ = std::tan(cam.fov * kPi / 360.0f);
    aspect_ = static_cast<float>(cam.width) / static_cast<float>(cam.height);
}

Vec3 CameraRays::direction(float px, float py) const {
    float sx = (2 * px / static_cast<float>(width_) - 1) * aspect_ * scale_;
    float sy = (1 - 2 * py / static_cast<float>(height_)) * scale_;
    return forward_ + right_ * sx + up_ * sy;
}

float CameraRays::footprint(const Vec3& d, float t, const Vec3& n) const {
    float s = 2 * scale_ / static_cast<float>(height_);
    Vec3 dx = right_ * s, dy = up_ * -s;
    float nd = dot(n, d);
    nd = std::copysign(std::max(std::abs(nd), 0.05f * length(d)), nd);
    float tau = t / length(d);
    Vec3 px = (dx - d * (dot(n, dx) / nd)) * tau, py = (dy - d * (dot(n, dy) / nd)) * tau;
    // The pixel's narrowest world extent (parallelogram area over its longer side), not
    // sqrt(area): on surfaces seen at grazing angles a record's reach in pixels along the
    // foreshortened direction would otherwise be far beyond max_spacing.
    return length(cross(px, py)) / std::max(length(px), length(py));
}

bool CameraRays::project(const Vec3& p, float& px, float& py) const {
    Vec3 v = p - pos_;
    float z = dot(v, forward_);
    if (z <= 0) return false;
    float sx = dot(v, right_) / z, sy = dot(v, up_) / z;
    px = (sx / (aspect_ * scale_) + 1) * 0.5f * static_cast<float>(width_);
    py = (1 - sy / scale_) * 0.5f * static_cast<float>(height_);
    return true;
}

// ------------------------------------------------------------------------------------------
// Visibility

namespace {

struct Accum {
    Vec3 p, n, ng;
    Vec3 p0, ng0;  ///< the first subsample's point and geometric normal: the group's plane
    float off_plane = 0;  ///< largest distance of a merged subsample from that plane
    Vec2 uv;
    uint32_t material, object, prim;
    float depth, footprint;
    int count;
};

}  // namespace

DeepBuffer render_visibility(const Scene& scene, const SceneAccel& accel, Stats& stats, ProgressSink* sink) {
    return render_visibility(scene, accel, stats, sink, frame_window(scene));
}

std::array<int, 4> frame_window(const Scene& scene) {
    const VisibilitySettings& v = scene.render.visibility;
    return v.has_crop() ? v.crop : std::array<int, 4>{0, scene.camera.width, 0, scene.camera.height};
}

DeepBuffer sub_window(const DeepBuffer& deep, const std::array<int, 4>& w) {
    if (w[0] == deep.x0 && w[2] == deep.y0 && w[1] - w[0] == deep.width && w[3] - w[2] == deep.height) return deep;
    DeepBuffer out = deep;
    out.x0 = w[0], out.y0 = w[2], out.width = w[1] - w[0], out.height = w[3] - w[2];
    out.offsets.assign(1, 0);
    out.fragments.clear();
    for (int y = w[2]; y < w[3]; ++y)
        for (int x = w[0]; x < w[1]; ++x) {
            auto f = deep.pixel(x - deep.x0, y - deep.y0);
            out.fragments.insert(out.fragments.end(), f.begin(), f.end());
            out.offsets.push_back(static_cast<uint32_t>(out.fragments.size()));
        }
    return out;
}

DeepBuffer render_visibility(const Scene& scene, const SceneAccel& accel, Stats& stats, ProgressSink* sink,
                             const std::array<int, 4>& window) {
    const Camera& cam = scene.camera;
    const VisibilitySettings& rs = scene.render.visibility;
    DeepBuffer deep;
    deep.full_width = cam.width;
    deep.full_height = cam.height;
    deep.x0 = window[0], deep.y0 = window[2];
    deep.width = window[1] - window[0], deep.height = window[3] - window[2];
    deep.spp = rs.spp;
    deep.seed = rs.seed;
    deep.scene_fingerprint = scene.fingerprint({"camera", "objects"});

    CameraRays camera(cam);
    const int spp = rs.spp;
    std::vector<std::vector<Fragment>> per_pixel(deep.pixel_count());
    Progress progress(sink, "visibility", static_cast<uint64_t>(deep.height));

    parallel_ranges(0, deep.height, 1, [&](int row0, int row1) {
        Counters& counters = stats.local();
        std::vector<Accum> groups;
        std::vector<std::pair<Vec3, size_t>> subsamples;  // (point, group) of this pixel
        for (int wy = row0; wy < row1; ++wy) {
            for (int wx = 0; wx < deep.width; ++wx) {
                int x = wx + deep.x0, y = wy + deep.y0;
                RandomStream rng(rs.seed, static_cast<uint64_t>(y) * 65536u + static_cast<uint64_t>(x));
                groups.clear();
                subsamples.clear();
                for (int s = 0; s < spp; ++s) {
                    Vec2 j = stratified_2d(s, spp, rng.get(static_cast<uint64_t>(s), kDimPixelX),
                                             rng.get(static_cast<uint64_t>(s), kDimPixelY));
                    Vec3 d = camera.direction(static_cast<float>(x) + j.x, static_cast<float>(y) + j.y);
                    Vec3 dn = normalize(d);
                    ++counters.camera_rays;
                    Hit h = accel.fine().intersect(camera.origin(), dn, 0, INFINITY);
                    if (!h.valid()) continue;
                    const Object& obj = scene.objects[h.object];
                    SurfacePoint sp = surface_point(obj.visible(), h.prim, h.u, h.v);
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
                        const float off = std::abs(dot(sp.p - a.p0, a.ng0));
                        if (a.object == h.object && a.material == sp.material &&
                            dot(normalize(a.ng), sp.ng) > 0.9f &&
                            std::abs(a.depth / static_cast<float>(a.count) - h.t) < 0.05f * h.t + 4 * fp && off < fp) {
                            g = &a;
                            g->off_plane = std::max(g->off_plane, off / fp);
                            break;
                        }
                    }
                    if (!g) {
                        groups.push_back({Vec3(0), Vec3(0), Vec3(0), sp.p, sp.ng, 0, {}, sp.material, h.object, h.prim,
                                          0, 0, 0});
                        g = &groups.back();
                    }
                    subsamples.emplace_back(sp.p, static_cast<size_t>(g - groups.data()));
                    g->p += sp.p, g->n += sp.n, g->ng += sp.ng;
                    g->uv.x += sp.uv.x, g->uv.y += sp.uv.y;
                    g->depth += h.t, g->footprint += fp;
                    ++g->count;
                }
                auto& out = per_pixel[static_cast<size_t>(wy) * deep.width + wx];
                for (size_t gi = 0; gi < groups.size(); ++gi) {
                    const Accum& a = groups[gi];
                    auto c = static_cast<float>(a.count);
                    Fragment f;
                    // A planar group sits at its centroid. Otherwise the centroid can lie off
                    // every surface (inside a convex ridge, between offset faces), where a
                    // gather sees only the inside of the model: take the subsample nearest it.
                    const Vec3 centroid = a.p / c;
                    f.p = centroid;
                    if (a.off_plane > 1e-3f) {
                        float best = INFINITY;
                        for (const auto& [q, group] : subsamples) {
                            const float dist = length(q - centroid);
                            if (group == gi && dist < best) best = dist, f.p = q;
                        }
                    }
                    f.n = normalize(a.n);
                    f.ng = normalize(a.ng);
                    f.p_base = f.p;
                    f.n_base = f.n;
                    f.uv = {a.uv.x / c, a.uv.y / c};
                    f.material = a.material, f.object = a.object, f.prim = a.prim;
                    f.depth = a.depth / c;
                    f.weight = c / static_cast<float>(spp);
                    f.footprint = a.footprint / c;
                    out.push_back(f);
                }
                // Front to back, as deep compositing expects.
                std::stable_sort(out.begin(), out.end(), [](const Fragment& a, const Fragment& b) { return a.depth < b.depth; });
            }
            progress.add();
        }
    });

    deep.offsets.resize(deep.pixel_count() + 1);
    deep.offsets[0] = 0;
    for (size_t i = 0; i < per_pixel.size(); ++i)
        deep.offsets[i + 1] = deep.offsets[i] + static_cast<uint32_t>(per_pixel[i].size());
    deep.fragments.reserve(deep.offsets.back());
    for (auto& v : per_pixel) deep.fragments.insert(deep.fragments.end(), v.begin(), v.end());
    stats.set("fragments", static_cast<double>(deep.fragments.size()));
    return deep;
}

void check_camera_sees_geometry(const Scene& scene, const SceneAccel& accel) {
    CameraRays camera(scene.camera);
    const int n = 48;
    for (int j = 0; j < n; ++j)
        for (int i = 0; i < n; ++i) {
            float px = (static_cast<float>(i) + 0.5f) / n * static_cast<float>(scene.camera.width);
            float py = (static_cast<float>(j) + 0.5f) / n * static_cast<float>(scene.camera.height);
            if (accel.fine().intersect(camera.origin(), normalize(camera.direction(px, py)), 0, INFINITY).valid())
                return;
        }
    const Vec3 &p = scene.camera.position, &l = scene.camera.look_at;
    throw InputError(scene.path, "/camera",
                     fmt::format("the camera at ({}, {}, {}) looking at ({}, {}, {}) sees no geometry", p.x, p.y,
                                 p.z, l.x, l.y, l.z));
}

// ------------------------------------------------------------------------------------------
// Deep file I/O (OpenEXR deep scanlines through OpenImageIO)

namespace {

constexpr int kDeepVersion = 1;

struct Channel {
    const char* name;
    OIIO::TypeDesc type;
};

// Z and A first: the layout deep-aware compositors expect.
const std::vector<Channel>& deep_channels() {
    static const std::vector<Channel> ch = {
        {"Z", OIIO::TypeDesc::FLOAT},       {"A", OIIO::TypeDesc::FLOAT},
        {"P.X", OIIO::TypeDesc::FLOAT},     {"P.Y", OIIO::TypeDesc::FLOAT},     {"P.Z", OIIO::TypeDesc::FLOAT},
        {"N.X", OIIO::TypeDesc::FLOAT},     {"N.Y", OIIO::TypeDesc::FLOAT},     {"N.Z", OIIO::TypeDesc::FLOAT},
        {"Ng.X", OIIO::TypeDesc::FLOAT},    {"Ng.Y", OIIO::TypeDesc::FLOAT},    {"Ng.Z", OIIO::TypeDesc::FLOAT},
        {"Pref.X", OIIO::TypeDesc::FLOAT},  {"Pref.Y", OIIO::TypeDesc::FLOAT},  {"Pref.Z", OIIO::TypeDesc::FLOAT},
        {"Nref.X", OIIO::TypeDesc::FLOAT},  {"Nref.Y", OIIO::TypeDesc::FLOAT},  {"Nref.Z", OIIO::TypeDesc::FLOAT},
        {"uv.U", OIIO::TypeDesc::FLOAT},    {"uv.V", OIIO::TypeDesc::FLOAT},
        {"id.material", OIIO::TypeDesc::UINT}, {"id.object", OIIO::TypeDesc::UINT}, {"id.prim", OIIO::TypeDesc::UINT},
        {"footprint", OIIO::TypeDesc::FLOAT},
    };
    return ch;
}

/// Float channel values of a fragment in deep_channels() order (ids handled separately).
std::array<float, 23> float_values(const Fragment& f) {
    return {f.depth, f.weight, f.p.x, f.p.y, f.p.z, f.n.x, f.n.y, f.n.z, f.ng.x, f.ng.y, f.ng.z,
            f.p_base.x, f.p_base.y, f.p_base.z, f.n_base.x, f.n_base.y, f.n_base.z, f.uv.x, f.uv.y,
            0, 0, 0, f.footprint};
}

}  // namespace

void write_deep(const std::string& path, const DeepBuffer& deep) {
    const auto& chans = deep_channels();
    OIIO::ImageSpec spec(deep.width, deep.height, static_cast<int>(chans.size()), OIIO::TypeDesc::FLOAT);
    spec.x = deep.x0, spec.y = deep.y0;
    spec.full_x = 0, spec.full_y = 0;
    spec.full_width = deep.full_width, spec.full_height = deep.full_height;
    spec.deep = true;
    spec.channelnames.clear();
    spec.channelformats.clear();
    for (const auto& c : chans) {
        spec.channelnames.emplace_back(c.name);
        spec.channelformats.push_back(c.type);
    }
    spec.z_channel = 0;
    spec.alpha_channel = 1;
    spec.attribute("compression", "zips");
    spec.attribute("bounce:deep_version", kDeepVersion);
    spec.attribute("bounce:spp", deep.spp);
    spec.attribute("bounce:seed", fmt::format("{}", deep.seed));
    spec.attribute("bounce:scene_fingerprint", fmt::format("{:016x}", deep.scene_fingerprint));
    spec.attribute("Software", "bounce " BOUNCE_VERSION);

    OIIO::DeepData dd;
    dd.init(static_cast<int64_t>(deep.pixel_count()), static_cast<int>(chans.size()),
            spec.channelformats, spec.channelnames);
    for (size_t i = 0; i < deep.pixel_count(); ++i)
        dd.set_samples(static_cast<int64_t>(i), static_cast<int>(deep.offsets[i + 1] - deep.offsets[i]));
    for (size_t i = 0; i < deep.pixel_count(); ++i) {
        for (uint32_t k = deep.offsets[i]; k < deep.offsets[i + 1]; ++k) {
            const Fragment& f = deep.fragments[k];
            auto vals = float_values(f);
            int s = static_cast<int>(k - deep.offsets[i]);
            auto pix = static_cast<int64_t>(i);
            for (int c = 0; c < static_cast<int>(chans.size()); ++c) {
                if (chans[static_cast<size_t>(c)].type == OIIO::TypeDesc::UINT) continue;
                dd.set_deep_value(pix, c, s, vals[static_cast<size_t>(c)]);
            }
            dd.set_deep_value(pix, 19, s, f.material);
            dd.set_deep_value(pix, 20, s, f.object);
            dd.set_deep_value(pix, 21, s, f.prim);
        }
    }
    write_atomically(path, [&](const std::string& tmp) {
        auto out = OIIO::ImageOutput::create("openexr");
        if (!out || !out->open(tmp, spec))
            throw InputError(path, "", "cannot write deep file: " + (out ? out->geterror() : OIIO::geterror()));
        if (!out->write_deep_image(dd)) throw InputError(path, "", "cannot write deep file: " + out->geterror());
        if (!out->close()) throw InputError(path, "", "cannot write deep file: " + out->geterror());
    });
}

DeepBuffer read_deep(const std::string& path) {
    check_input_file(path);
    auto in = OIIO::ImageInput::open(path);
    if (!in) throw InputError(path, "", "not a readable deep file: " + OIIO::geterror());
    const OIIO::ImageSpec& spec = in->spec();
    if (!spec.deep) throw InputError(path, "", "not a deep image (expected an OpenEXR deep file from --deep-out)");
    int version = spec.get_int_attribute("bounce:deep_version", -1);
    if (version != kDeepVersion)
        throw InputError(path, "bounce:deep_version",
                         version < 0 ? "not a bounce deep file (no bounce:deep_version attribute)"
                                     : fmt::format("unsupported version {} (this bounce reads {})", version, kDeepVersion));
    // OpenEXR stores channels sorted by name: find ours by name.
    const auto& chans = deep_channels();
    std::vector<int> index(chans.size(), -1);
    for (size_t c = 0; c < chans.size(); ++c) {
        for (int k = 0; k < spec.nchannels; ++k)
            if (spec.channelnames[static_cast<size_t>(k)] == chans[c].name) index[c] = k;
        if (index[c] < 0) throw InputError(path, "channels", fmt::format("missing channel \"{}\"", chans[c].name));
        if (spec.channelformat(index[c]) != chans[c].type)
            throw InputError(path, fmt::format("channel {}", chans[c].name),
                             fmt::format("expected type {}, found {}", chans[c].type.c_str(),
                                         spec.channelformat(index[c]).c_str()));
    }
    DeepBuffer deep;
    deep.x0 = spec.x, deep.y0 = spec.y, deep.width = spec.width, deep.height = spec.height;
    deep.full_width = spec.full_width, deep.full_height = spec.full_height;
    deep.spp = spec.get_int_attribute("bounce:spp", 0);
    try {
        deep.seed = std::stoull(spec.get_string_attribute("bounce:seed", "x"));
        deep.scene_fingerprint = std::stoull(spec.get_string_attribute("bounce:scene_fingerprint", "x"), nullptr, 16);
    } catch (const std::exception&) {
        throw InputError(path, "header", "missing or malformed bounce:seed / bounce:scene_fingerprint");
    }
    if (deep.spp <= 0 || deep.width <= 0 || deep.height <= 0 || deep.x0 < 0 || deep.y0 < 0 ||
        deep.x0 + deep.width > deep.full_width || deep.y0 + deep.height > deep.full_height)
        throw InputError(path, "header", "inconsistent image window or sample count");
    OIIO::DeepData dd;
    if (!in->read_native_deep_image(0, 0, dd))
        throw InputError(path, "", "cannot read deep data: " + in->geterror());
    deep.offsets.resize(deep.pixel_count() + 1);
    deep.offsets[0] = 0;
    for (size_t i = 0; i < deep.pixel_count(); ++i) {
        int n = dd.samples(static_cast<int64_t>(i));
        if (n < 0 || n > deep.spp)
            throw InputError(path, fmt::format("pixel {}", i), fmt::format("{} fragments exceed spp {}", n, deep.spp));
        deep.offsets[i + 1] = deep.offsets[i] + static_cast<uint32_t>(n);
    }
    deep.fragments.resize(deep.offsets.back());
    for (size_t i = 0; i < deep.pixel_count(); ++i) {
        auto pix = static_cast<int64_t>(i);
        for (uint32_t k = deep.offsets[i]; k < deep.offsets[i + 1]; ++k) {
            int s = static_cast<int>(k - deep.offsets[i]);
            auto v = [&](int c) { return dd.deep_value(pix, index[static_cast<size_t>(c)], s); };
            auto id = [&](int c) { return dd.deep_value_uint(pix, index[static_cast<size_t>(c)], s); };
            Fragment& f = deep.fragments[k];
            f.depth = v(0), f.weight = v(1);
            f.p = {v(2), v(3), v(4)}, f.n = {v(5), v(6), v(7)}, f.ng = {v(8), v(9), v(10)};
            f.p_base = {v(11), v(12), v(13)}, f.n_base = {v(14), v(15), v(16)};
            f.uv = {v(17), v(18)};
            f.material = id(19);
            f.object = id(20);
            f.prim = id(21);
            f.footprint = v(22);
            if (!isfinite(f.p) || !isfinite(f.n) || !std::isfinite(f.weight) || f.weight < 0 || f.weight > 1)
                throw InputError(path, fmt::format("pixel {} fragment {}", i, s), "non-finite or out-of-range values");
        }
    }
    return deep;
}

}  // namespace bounce
