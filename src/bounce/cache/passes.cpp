#include "bounce/cache/passes.h"

#include <tbb/enumerable_thread_specific.h>
#include <tbb/parallel_for.h>

#include <algorithm>

namespace bounce {

bool SubPass::contains(int x, int y) const {
    if (x % step || y % step) return false;
    int px = (x / step) & 1, py = (y / step) & 1;
    if (!all && (px | (py << 1)) != parity) return false;
    // Quarter classes on the lattice of twice the spacing (for the first level, of the step).
    int q = all ? step : 2 * step;
    return (((x / q) & 1) | (((y / q) & 1) << 1)) == quarter;
}

std::vector<SubPass> subpass_schedule(int first_step) {
    int s = 1;
    while (s * 2 <= first_step) s *= 2;
    std::vector<SubPass> out;
    for (int q = 0; q < 4; ++q) out.push_back({s, 0, true, q});
    for (s /= 2; s >= 1; s /= 2)
        for (int parity : {1, 2, 3})
            for (int q = 0; q < 4; ++q) out.push_back({s, parity, false, q});
    return out;
}

namespace {

struct Candidate {
    uint64_t key;   ///< (pixel index in the full image) << 8 | fragment
    int x, y;       ///< window coordinates
    uint32_t frag;  ///< index into deep.fragments
    uint32_t k;     ///< fragment index within the pixel
};

uint64_t candidate_key(const DeepBuffer& deep, int wx, int wy, uint32_t k) {
    uint64_t pix = static_cast<uint64_t>(wy + deep.y0) * static_cast<uint64_t>(deep.full_width) +
                   static_cast<uint64_t>(wx + deep.x0);
    return (pix << 8) | k;
}

}  // namespace

void gathering_pass(const Scene& scene, const DeepBuffer& deep, const Gatherer& gatherer, IrradianceCache& cache,
                    Stats& stats, ProgressSink* sink, const SubPassCallback& after_subpass, int frame) {
    const auto schedule = subpass_schedule(static_cast<int>(cache.settings().max_spacing));
    Progress progress(sink, "gathering", schedule.size());
    size_t dropped = 0, gathered = 0;
    for (size_t si = 0; si < schedule.size(); ++si) {
        const SubPass& sp = schedule[si];
        // 1. Lookups against the cache as it is now (read-only, parallel over rows).
        tbb::enumerable_thread_specific<std::vector<Candidate>> local;
        tbb::parallel_for(0, deep.height, [&](int wy) {
            auto& out = local.local();
            for (int wx = 0; wx < deep.width; ++wx) {
                if (!sp.contains(wx + deep.x0, wy + deep.y0)) continue;
                size_t first = deep.offsets[static_cast<size_t>(wy) * deep.width + wx];
                auto frags = deep.pixel(wx, wy);
                for (uint32_t k = 0; k < frags.size(); ++k)
                    if (cache.misses(frags[k].p_base, frags[k].n_base))
                        out.push_back({candidate_key(deep, wx, wy, k), wx, wy, static_cast<uint32_t>(first + k), k});
            }
        });
        std::vector<Candidate> misses;
        for (auto& v : local) misses.insert(misses.end(), v.begin(), v.end());
        std::sort(misses.begin(), misses.end(), [](const Candidate& a, const Candidate& b) { return a.key < b.key; });

        // 2. Gathers at the misses (parallel, each from its own fragment's random stream).
        std::vector<Record> records(misses.size());
        tbb::parallel_for(tbb::blocked_range<size_t>(0, misses.size(), 1), [&](const tbb::blocked_range<size_t>& r) {
            Counters& counters = stats.local();
            for (size_t i = r.begin(); i < r.end(); ++i) {
                const Candidate& c = misses[i];
                const Fragment& f = deep.fragments[c.frag];
                GatherResult g = gatherer.gather(f.p, f.n_base, fragment_stream(scene.render.seed, c.x + deep.x0, c.y + deep.y0, c.k),
                                                 counters);
                records[i] = cache.make_record(g, f.p_base, f.n_base, f.footprint, c.key);
                records[i].frame = frame;
            }
        });
        gathered += records.size();

        // 3. Insert in pixel order, dropping candidates the records inserted before them in
        //    this sub-pass already cover.
        if (cache.luminance_floor() < 0 && !records.empty()) {
            double mean = 0;
            for (const auto& r : records) mean += luminance(r.E);
            cache.set_luminance_floor(static_cast<float>(1e-3 * mean / static_cast<double>(records.size())));
        }
        size_t before = cache.size();
        for (auto& r : records) {
            if (cache.size() > before && !cache.misses(r.p, r.n)) {
                ++dropped;
                continue;
            }
            cache.insert(r);
        }
        progress.add();
        if (after_subpass) after_subpass(sp, si, schedule.size());
    }
    stats.set("records", static_cast<double>(cache.size()));
    stats.set("record_gathers", static_cast<double>(gathered));
    stats.set("records_dropped", static_cast<double>(dropped));
    stats.set("subpasses", static_cast<double>(schedule.size()));
    stats.set("rays_per_gather", gathered ? static_cast<double>(stats.total().gather_rays) / static_cast<double>(gathered) : 0.0);
    stats.set("cache_bytes", static_cast<double>(cache.memory_bytes()));
}

std::vector<Indirect> shading_pass(const Scene& scene, const DeepBuffer& deep, const IrradianceCache& cache,
                                   Stats& stats, ProgressSink* sink) {
    std::vector<Indirect> out(deep.fragments.size());
    tbb::enumerable_thread_specific<uint64_t> misses(0), lookups(0);
    for_each_pixel_in_tiles(deep, scene.render.tile_size, sink, "interpolate", [&](int wx, int wy, size_t first) {
        auto frags = deep.pixel(wx, wy);
        for (uint32_t k = 0; k < frags.size(); ++k) {
            Interpolated in = cache.lookup(frags[k].p_base, frags[k].n_base, true);
            ++lookups.local();
            if (in.weight <= 0) ++misses.local();
            out[first + k] = {in.E, in.ao, in.bent};
        }
    });
    uint64_t m = 0, l = 0;
    for (auto v : misses) m += v;
    for (auto v : lookups) l += v;
    stats.set("shading_misses", static_cast<double>(m));
    stats.set("lookups", static_cast<double>(l));
    return out;
}

}  // namespace bounce
