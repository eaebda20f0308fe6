#include "bounce/gather/gather.h"
#include "bounce/gather/gather_terms.h"

#include "bounce/gather/ao_cutoff.h"
#include "bounce/gather/gather_cells.h"
#include "bounce/gather/guide.h"
#include "bounce/gather/hessian.h"

#include <mutex>
#include <vector>

#include "bounce/core/sampling.h"

namespace bounce {

Gatherer::Gatherer(const Scene& scene, const SceneAccel& accel, const Materials& materials, const DirectLighting& lighting,
                   const RadiosityTextures* radiosity, GatherSettings settings)
    : scene_(scene),
      accel_(accel),
      materials_(materials),
      lighting_(lighting),
      radiosity_(radiosity),
      settings_(settings),
      grid_(gather_grid(settings.rays)),
      cos_concave_(std::cos(settings.concave_angle * kPi / 180.0f)),
      packet_order_(gather_packet_order(grid_)),
      far_(10 * std::max(1e-6f, length(scene.bounds().diagonal()))),
      lights_(settings.light_parts && !settings.ao ? scene.lights.size() : 0),
      unit_scales_(lights_, Color(1)),
      scratch_(std::make_shared<Scratch>()) {
    if (lights_ && radiosity_ && !radiosity_->has_parts())
        throw std::logic_error("gather: light parts need radiosity textures baked with parts");
}

namespace {
/// The sum of a cell's per-light parts, in light order (the signal: every light at scale 1).
Color part_sum(std::span<const Color> parts) {
    Color sum(0);
    for (const Color& x : parts) sum += x;
    return sum;
}
}  // namespace

Color Gatherer::hit_radiance(const Hit& h, const SurfacePoint& sp, const Vec3& d, const RandomStream& rng, uint64_t ray, Counters& counters,
                             std::span<Color> parts) const {
    bool front = dot(sp.ng, d) < 0;
    if (radiosity_ && !parts.empty()) {
        radiosity_->lookup_parts(h.object, h.prim, h.u, h.v, front, counters, parts);
        return part_sum(parts);
    }
    if (radiosity_) return radiosity_->lookup(h.object, h.prim, h.u, h.v, front, counters);
    const Vec3 n = front ? sp.ng : -sp.ng;
    const RandomStream hit_rng(rng.bits(ray, kDimGather + 3), ray);
    return lighting_.diffuse_radiance(sp.p, n, h.object, materials_.secondary_albedo(sp) * kInvPi,
                                      materials_.secondary_translucency(sp) * kInvPi, hit_rng, settings_.hit_light_samples, counters,
                                      parts);
}

Color Gatherer::hair_radiance(const Hit& h, const Vec3& at, const Vec3& d, const RandomStream& rng, uint64_t ray, Counters& counters,
                              std::span<Color> parts) const {
    const RandomStream hit_rng(rng.bits(ray, kDimGather + 3), ray);
    return lighting_.strand_radiance(h, at, d, hit_rng, settings_.hit_light_samples, counters, parts);
}

float Gatherer::unoccluded(float t) const {
    if (settings_.ao_distance > 0 && t >= settings_.ao_distance) return 1;
    return settings_.ao_falloff > 0 && settings_.ao_distance > 0 ? 1 - std::pow(1 - t / settings_.ao_distance, settings_.ao_falloff) : 0;
}

Color Gatherer::escaped_radiance(const Vec3& d, std::span<Color> parts) const {
    if (parts.empty()) return lighting_.background(d);
    lighting_.background_parts(d, parts);
    return part_sum(parts);
}

struct Gatherer::Scratch {
    PerThread<detail::Cells> per_thread;
    /// Reprojection's cells about each cell (detail::cell_margins): made once, on first use.
    std::once_flag margins_once;
    std::vector<std::vector<uint32_t>> margins;
};

detail::Cells& Gatherer::scratch() const { return scratch_->per_thread.local(); }

const std::vector<std::vector<uint32_t>>& Gatherer::reprojection_margins() const {
    std::call_once(scratch_->margins_once, [&] { scratch_->margins = detail::cell_margins(grid_, 1.5f / kReprojectNear); });
    return scratch_->margins;
}

void Gatherer::cell_directions(detail::Cells& cells, const Vec3& n, const RandomStream& rng) const {
    const int M = grid_.m, N = grid_.n;
    cells.resize(static_cast<size_t>(M * N));
    const Frame frame(n);
    for (int j = 0; j < M; ++j)
        for (int k = 0; k < N; ++k) {
            const auto c = static_cast<size_t>(j * N + k);
            const Vec3 local = gather_cell_direction(grid_, j, k, rng);
            cells.cos_theta[c] = local.z;
            cells.D[c] = frame.to_world(local);
        }
}

GatherResult Gatherer::gather(const Vec3& p, const Vec3& n, const RandomStream& rng, Counters& counters, float near,
                              GatherHits* keep) const {
    if (settings_.cancel) settings_.cancel->check();
    detail::Cells& cells = scratch();
    // Directions first (stratified, cosine-weighted), then one packet trace of all of them:
    // neighbouring cells of a row are coherent, so Embree traverses them together.
    cell_directions(cells, n, rng);
    const size_t S = cells.D.size();
    for (size_t i = 0; i < packet_order_.size(); ++i) cells.packet_dirs[i] = cells.D[packet_order_[i]];
    accel_.trace_many(p, cells.packet_dirs, cells.packet_hits);
    for (size_t i = 0; i < packet_order_.size(); ++i) cells.hits[packet_order_[i]] = cells.packet_hits[i];
    counters.gather_rays += static_cast<uint64_t>(S);
    if (keep) {
        keep->m = grid_.m, keep->n = grid_.n;
        keep->t.resize(S), keep->u.resize(S), keep->v.resize(S), keep->object.resize(S), keep->prim.resize(S);
        for (size_t c = 0; c < S; ++c) {
            const Hit& h = cells.hits[c];
            keep->t[c] = h.t, keep->u[c] = h.u, keep->v[c] = h.v, keep->prim[c] = h.prim;
            keep->object[c] = h.valid() && h.hair ? h.object | GatherHits::kHairBit : h.object;
        }
    }
    return finish(cells, p, n, rng, counters, near);
}

GatherResult Gatherer::reshade(const Vec3& p, const Vec3& n, const RandomStream& rng, const GatherHits& kept, Counters& counters,
                               float near) const {
    if (settings_.cancel) settings_.cancel->check();
    detail::Cells& cells = scratch();
    cell_directions(cells, n, rng);
    const size_t S = cells.D.size();
    if (kept.t.size() != S) return gather(p, n, rng, counters, near);  // made with other settings: trace again
    for (size_t c = 0; c < S; ++c) {
        Hit& h = cells.hits[c];
        h.t = kept.t[c], h.u = kept.u[c], h.v = kept.v[c], h.prim = kept.prim[c];
        h.hair = kept.object[c] != kNoHit && (kept.object[c] & GatherHits::kHairBit);
        h.object = kept.object[c] == kNoHit ? kNoHit : kept.object[c] & ~GatherHits::kHairBit;
    }
    return finish(cells, p, n, rng, counters, near);
}

GatherResult Gatherer::update(const Vec3& p, const Vec3& n, const RandomStream& rng, GatherHits& kept, std::span<const uint32_t> redo,
                              Counters& counters, float near) const {
    if (settings_.cancel) settings_.cancel->check();
    detail::Cells& cells = scratch();
    cell_directions(cells, n, rng);
    const size_t S = cells.D.size();
    if (kept.t.size() != S) return gather(p, n, rng, counters, near, &kept);
    std::vector<Vec3> dirs;
    for (uint32_t c : redo) dirs.push_back(cells.D[c]);
    std::vector<Hit> traced(dirs.size());
    accel_.trace_many(p, dirs, traced);
    counters.gather_rays += dirs.size();
    for (size_t i = 0; i < redo.size(); ++i) {
        const Hit& h = traced[i];
        const uint32_t c = redo[i];
        kept.t[c] = h.t, kept.u[c] = h.u, kept.v[c] = h.v, kept.prim[c] = h.prim;
        kept.object[c] = h.valid() && h.hair ? h.object | GatherHits::kHairBit : h.object;
    }
    return reshade(p, n, rng, kept, counters, near);
}

LightPart Gatherer::light_part(const detail::Cells& cells, const Color* L, size_t stride, const Frame& frame, float near,
                               bool gradients) const {
    const size_t S = static_cast<size_t>(grid_.rays());
    Color sum(0);
    std::array<Vec3, 3> dir{};
    for (size_t c = 0; c < S; ++c) {
        const Color& l = L[c * stride];
        sum += l;
        for (int ch = 0; ch < 3; ++ch) dir[static_cast<size_t>(ch)] += cells.D[c] * l[ch];
    }
    const float w = kPi / static_cast<float>(S);
    LightPart out;
    out.E = sum * w;
    for (size_t ch = 0; ch < 3; ++ch) out.dir[ch] = dir[ch] * w;
    if (!gradients) return out;
    gradient_sums(grid_, frame, near, cells.R.data(), L, stride, out.grad_r, out.grad_t);
    for (size_t ch = 0; ch < 3; ++ch) out.grad_r[ch] = out.grad_r[ch] * w;
    return out;
}

Color Gatherer::cell_radiance(detail::Cells& cells, const Vec3& p, size_t c, const RandomStream& rng, Counters& counters,
                              std::span<Color> parts) const {
    const Vec3& d = cells.D[c];
    const Hit& h = cells.hits[c];
    cells.NH[c] = Vec3(0);
    if (!h.valid()) return settings_.ao ? Color(0) : escaped_radiance(d, parts);
    if (h.hair) return settings_.ao ? Color(0) : hair_radiance(h, p + d * h.t, d, rng, c, counters, parts);
    if (!settings_.record_terms && settings_.ao) return Color(0);
    const Object& hit = scene_.objects[h.object];
    // AO needs only the plane, on either side: the face's normal, not a shading point.
    const SurfacePoint sp = settings_.ao ? SurfacePoint{} : hit.coarse_point(h.prim, h.u, h.v);
    cells.NH[c] = settings_.ao ? face_normal(hit.coarse_mesh(), hit.to_world(), h.prim) : sp.ng;
    return settings_.ao ? Color(0) : hit_radiance(h, sp, d, rng, c, counters, parts);
}

namespace {
/// What a record keeps beyond its value: the view summary (per direction bin, the farthest the
/// rays went; INFINITY: one escaped), the prediction's bins and cells, the Hessian.
void add_record_terms(const GatherSettings& settings, const GatherGrid& grid, float far, detail::Cells& cells, const Vec3& p, const Vec3& n,
                      const Frame& frame, GatherResult& res) {
    const int M = grid.m, N = grid.n, S = M * N;
    const std::vector<Color>& L = cells.L;
    const std::vector<float>&R = cells.R, &U = cells.U;
    const std::vector<Vec3>& D = cells.D;
    for (int j = 0; j < M; ++j)
        for (int k = 0; k < N; ++k) {
            const size_t bin = static_cast<size_t>((j * kReachBands / M) * kReachSectors + k * kReachSectors / N);
            res.reach[bin] = std::max(res.reach[bin], R[static_cast<size_t>(j * N + k)]);
        }
    if (settings.prediction) {
        set_bins(res, frame, settings.ao ? std::span<const float>(U) : std::span<const float>(), L, D);
        auto all = std::make_shared<std::vector<Color>>(L);
        if (settings.ao)
            for (size_t c = 0; c < all->size(); ++c) (*all)[c] = Color(U[c]);
        res.cells = std::move(all), res.grid = grid;
        if (settings.prediction_hits) {
            auto at = std::make_shared<std::vector<Vec3>>(static_cast<size_t>(S));
            for (size_t c = 0; c < at->size(); ++c) (*at)[c] = p + D[c] * std::min(R[c], kEscapedHit);
            res.cell_hits = std::move(at);
        }
    }
    if (settings.hessian) {
        const TangentHessian th = cells_hessian(grid, p, n, far, settings.ao, L, U, R, D, cells.scratch);
        res.hess_axis = th.axis, res.hess_slow = th.slow, res.hess_fast = th.fast;
    }
}

/// AO's gradients: a mean (1/S), not pi/S times a sum; where the cutoff distance cuts a
/// surface, the boundary moves with its distance (ao_cutoff.h).
void add_ao_gradients(const GatherGrid& grid, const Frame& frame, float near, const detail::Cells& cells, float ao_distance,
                      GatherResult& res) {
    std::array<Vec3, 1> agr{}, agt{};
    if (ao_distance > 0) {
        const detail::CutoffCells cut{cells.D, cells.R, cells.U, cells.NH};
        const detail::SurfacePairs pairs(grid, cut);
        gradient_sums(grid, frame, near, cells.R.data(), cells.U.data(), 1, agr, agt, pairs);
        res.ao_grad_trans = agt[0] * kInvPi + pairs.gradient();
    } else {
        gradient_sums(grid, frame, near, cells.R.data(), cells.U.data(), 1, agr, agt);
        res.ao_grad_trans = agt[0] * kInvPi;
    }
    res.ao_grad_rot = agr[0] / static_cast<float>(grid.m * grid.n);
}
}  // namespace

GatherResult Gatherer::finish(detail::Cells& cells, const Vec3& p, const Vec3& n, const RandomStream& rng, Counters& counters,
                              float near) const {
    const int M = grid_.m, N = grid_.n, S = M * N;
    std::vector<Color>& L = cells.L;
    std::vector<float>&R = cells.R, &U = cells.U, &cos_theta = cells.cos_theta;
    const std::vector<Vec3>& D = cells.D;
    const std::vector<Hit>& hits = cells.hits;
    const Frame frame(n);
    GatherResult res;
    res.rays = S;
    Vec3 sum_u_dir(0);
    double inv_r_sum = 0;
    float sum_u = 0;
    if (lights_) cells.P.assign(static_cast<size_t>(S) * lights_, Color(0));
    for (size_t c = 0; c < static_cast<size_t>(S); ++c) {
        const Vec3& d = D[c];
        const Hit& h = hits[c];
        const std::span<Color> parts = lights_ ? std::span<Color>(cells.P.data() + c * lights_, lights_) : std::span<Color>();
        const Color l = cell_radiance(cells, p, c, rng, counters, parts);
        float u = 1;
        if (h.valid()) {
            R[c] = h.t;
            inv_r_sum += 1.0 / std::max(h.t, 1e-20f);
            u = unoccluded(h.t);
            // Distance for the record radius: leave out rays that are grazing both where
            // they leave and where they land (slightly concave surfaces). Fur (that gathers
            // see: its visible_to.indirect) always counts.
            const bool grazing = !h.hair && cos_theta[c] < cos_concave_ && std::abs(dot(cells.NH[c], d)) < cos_concave_;
            if (settings_.record_terms && !grazing && h.t >= near) res.min_distance = std::min(res.min_distance, h.t);
        }
        L[c] = l;
        U[c] = u;
        sum_u += u;
        sum_u_dir += d * u;
    }
    // With light parts the values are the signal: the parts' sum (one pass over the cells per
    // light, none more), a function of the parts alone.
    std::shared_ptr<LightParts> parts;
    if (lights_) {
        parts = std::make_shared<LightParts>();
        for (size_t i = 0; i < lights_; ++i)
            parts->light.push_back(light_part(cells, cells.P.data() + i, lights_, frame, near, settings_.record_terms));
        parts->signal = combine_parts(*parts, unit_scales_);
    }
    // AO mode's radiance is all 0: nothing to sum.
    const LightPart sums = parts          ? parts->signal
                           : settings_.ao ? LightPart{}
                                          : light_part(cells, L.data(), 1, frame, near, settings_.record_terms);
    res.irradiance = sums.E, res.light_dir = sums.dir;
    res.parts = std::move(parts);
    res.ao = sum_u / static_cast<float>(S);
    res.bent_normal = dot(sum_u_dir, sum_u_dir) > 0 ? normalize(sum_u_dir) : n;
    res.harmonic_distance = inv_r_sum > 0 ? static_cast<float>(S / inv_r_sum) : INFINITY;
    // Only records use it (adaptive rays); brute force skips it.
    if (settings_.record_terms)
        res.rel_stderr = relative_stderr(grid_, settings_.ao, L, U, settings_.ao ? res.ao : luminance(res.irradiance));
    if (!settings_.record_terms) return res;
    add_record_terms(settings_, grid_, far_, cells, p, n, frame, res);
    if (settings_.guided > 0) res.guide = std::make_shared<const DirectionGuide>(cells_guide(cells, n));
    res.grad_rot = sums.grad_r, res.grad_trans = sums.grad_t;
    add_ao_gradients(grid_, frame, near, cells, settings_.ao_distance, res);
    return res;
}

}  // namespace bounce

namespace bounce {

HairSite hair_site(const Scene& scene, const Fragment& f) {
    const bool at_root = scene.objects[f.object].fur->params.indirect_at == FurIndirectAt::Root;
    return {at_root ? f.p_base : f.p, f.n_base};
}

bool needs_bounce_light(const Scene& scene, const Fragment& f) {
    if (scene.objects[f.object].matte) return false;
    if (f.is_hair()) return true;
    const Material& m = scene.materials[f.material];
    for (int c = 0; c < 3; ++c)
        if (m.mirror[c] < 1 && m.transmission[c] < 1) return true;
    return false;
}

bool takes_back_light(const Scene& scene, const Fragment& f, bool ao) {
    return !f.is_hair() && !ao && scene.materials[f.material].is_translucent() && needs_bounce_light(scene, f);
}

}  // namespace bounce
