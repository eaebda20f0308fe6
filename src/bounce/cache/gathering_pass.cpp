// The gathering pass (passes.h): hierarchical sub-passes that make records where lookups miss,
// and, in a frame of a shot, redo the earlier frames' stale records that cover a fragment.
#include <tbb/enumerable_thread_specific.h>

#include <algorithm>
#include <cstring>
#include <mutex>
#include <shared_mutex>

#include "bounce/cache/cache_file.h"
#include "bounce/cache/passes.h"
#include "bounce/cache/sites.h"
#include "bounce/cache/temporal.h"

namespace bounce {

namespace {

/// A fragment whose lookup missed, in a sub-pass.
struct Candidate {
    int wx, wy;
    uint32_t k;
    Side side = Side::Front;
};

/// What one sub-pass collected, per tile.
struct TileWork {
    std::vector<Record> made;         ///< new records
    std::vector<uint32_t> requests;   ///< stale records that cover a fragment
    std::vector<Candidate> deferred;  ///< misses waiting for those to be redone
};

class Gathering {
  public:
    Gathering(const Scene& scene, const DeepBuffer& deep, const Gatherer& gatherer, IrradianceCache& cache, Stats& stats,
              const GatheringOptions& o)
        : scene_(scene),
          deep_(deep),
          gatherer_(gatherer),
          cache_(cache),
          stats_(stats),
          o_(o),
          per_tile_(o.sharing == CacheSharing::PerThread),
          tiles_(make_tiles(deep.width, deep.height, gatherer.settings().tiling.tile_size, gatherer.settings().tiling.tile_order)),
          mine_(owned(tiles_, o.comm)),
          work_(tiles_.size()) {}

    void subpass(const SubPass& sp);
    size_t gathered = 0, dropped = 0;
    tbb::enumerable_thread_specific<size_t> full_gathers{0};

  private:
    Record gather_at(const Candidate& c, Counters& counters);
    void judge_tile(const SubPass& sp, const Tile& t);
    /// One side of one fragment of a tile: a record where the cache misses (`covering`: scratch).
    void judge(const Candidate& c, TileWork& w, std::vector<uint32_t>& covering, Counters& counters);
    void insert_new(std::vector<Record> records);
    void exchange_work();
    void share_late(const std::vector<Candidate>& deferred, std::vector<uint8_t>& still, std::vector<Record>& late);
    /// The tiles this process judges: it holds only their fragments (render/distributed.h).
    static std::vector<Tile> owned(const std::vector<Tile>& tiles, const Communicator* comm) {
        std::vector<Tile> out;
        for (const Tile& t : tiles)
            if (!comm || comm->owns(static_cast<size_t>(t.index))) out.push_back(t);
        return out;
    }
    /// The process that owns the tile of window pixel (wx, wy).
    size_t owner_of(const Candidate& c) const {
        return static_cast<size_t>(tile_index_of(c.wx, c.wy, deep_.width, gatherer_.settings().tiling.tile_size)) %
               static_cast<size_t>(o_.comm->size());
    }

    const Scene& scene_;
    const DeepBuffer& deep_;
    const Gatherer& gatherer_;
    IrradianceCache& cache_;
    Stats& stats_;
    const GatheringOptions& o_;
    const bool per_tile_;
    const std::vector<Tile> tiles_;
    const std::vector<Tile> mine_;  ///< the tiles this process judges (all of them without MPI)
    std::vector<TileWork> work_;
};

Record Gathering::gather_at(const Candidate& c, Counters& counters) {
    const Fragment& f = deep_.pixel(c.wx, c.wy)[c.k];
    const Site site = record_site(scene_, f, cache_.settings(), c.side);
    const RandomStream front = fragment_stream(gatherer_.settings().tiling.seed, c.wx + deep_.x0, c.wy + deep_.y0, c.k);
    const RandomStream rng = c.side == Side::Back ? back_side_stream(front) : front;
    auto hits = o_.keep_hits ? std::make_shared<GatherHits>() : nullptr;
    GatherResult g = o_.first ? o_.first->gather(site.origin, site.n, rng, counters, site.near, hits.get()) : GatherResult{};
    if (!o_.first || g.rel_stderr > cache_.settings().ray_noise) {
        g = gatherer_.gather(site.origin, site.n, rng, counters, site.near, hits.get());
        ++full_gathers.local();
    }
    Record r = cache_.make_record(g, site.p, site.n, f.footprint, candidate_key(deep_, c.wx, c.wy, c.k, c.side));
    r.frame = r.gathered = o_.frame;
    r.origin = site.origin;
    r.near = site.near;
    r.hits = std::move(hits);
    const Object& obj = scene_.objects[f.object];
    if (obj.moves && !f.is_hair()) anchor_record(r, obj, f.object, f.prim);  // it travels with its object (temporal.h)
    return r;
}

void Gathering::judge_tile(const SubPass& sp, const Tile& t) {
    Counters& counters = stats_.local();
    auto lock = lock_cache<std::shared_lock<std::shared_mutex>>(cache_, counters);
    TileWork& w = work_[static_cast<size_t>(t.index)];
    w.made.clear(), w.requests.clear(), w.deferred.clear();
    std::vector<uint32_t> covering;
    // Only the sub-pass's lattice (a sixteenth of the pixels or fewer), not every pixel tested.
    const int period = sp.period();
    for (int wy = sp.first(t.y0 + deep_.y0, 1) - deep_.y0; wy < t.y1; wy += period)
        for (int wx = sp.first(t.x0 + deep_.x0, 0) - deep_.x0; wx < t.x1; wx += period) {
            auto frags = deep_.pixel(wx, wy);
            for (uint32_t k = 0; k < frags.size(); ++k) {
                if (!needs_bounce_light(scene_, frags[k])) continue;
                judge({wx, wy, k, Side::Front}, w, covering, counters);
                if (takes_back_light(scene_, frags[k], cache_.ao_only())) judge({wx, wy, k, Side::Back}, w, covering, counters);
            }
        }
}

void Gathering::judge(const Candidate& c, TileWork& w, std::vector<uint32_t>& covering, Counters& counters) {
    const Site site = record_site(scene_, deep_.pixel(c.wx, c.wy)[c.k], cache_.settings(), c.side);
    covering.clear();
    if (o_.stale) {
        // Every earlier frame's record that covers the point is redone, not only those that would
        // fill a miss: which records cover a miss depends on the order of the misses, so the point
        // would blend another subset of them each frame.
        o_.stale->covering(site.p, site.n, covering);
        w.requests.insert(w.requests.end(), covering.begin(), covering.end());
    }
    if (!cache_.misses(site.p, site.n, per_tile_ ? std::span<const Record>(w.made) : std::span<const Record>(), o_.own_weight,
                       o_.min_weight))
        return;
    if (!covering.empty()) {  // a miss that redone records may fill: judged again after them
        w.deferred.push_back(c);
        return;
    }
    Record r = gather_at(c, counters);
    if (per_tile_) {
        cache_.clamp_to_neighbours(r, w.made);
        r.support = cache_.support(r);
    }
    w.made.push_back(std::move(r));
}

/// New records, merged in an order that does not depend on scheduling. Shared: by pixel,
/// dropping those that records inserted before them in this sub-pass already cover.
/// Per-thread: the tile caches in tile order, all kept (each came from one tile's cache).
void Gathering::insert_new(std::vector<Record> records) {
    gathered += records.size();
    if (!per_tile_) std::sort(records.begin(), records.end(), [](const Record& a, const Record& b) { return a.key < b.key; });
    auto lock = lock_cache<std::unique_lock<std::shared_mutex>>(cache_, stats_.local());
    if (cache_.luminance_floor() < 0 && !records.empty()) {
        double mean = 0;
        for (const auto& r : records) mean += luminance(r.parts ? r.parts->signal.E : r.E);  // light parts: the signal's
        cache_.set_luminance_floor(static_cast<float>(1e-3 * mean / static_cast<double>(records.size())));
    }
    const size_t before = cache_.size();
    for (auto& r : records) {
        if (!per_tile_ && cache_.size() > before && !cache_.misses(r.p, r.n)) {
            ++dropped;
            continue;
        }
        cache_.insert(std::move(r));
    }
}

/// Every process sends the work of its tiles and takes the others': afterwards each holds
/// every tile's work, as one process that judged them all would.
void Gathering::exchange_work() {
    std::string mine;
    const auto put = [&mine](const void* p, size_t n) { mine.append(static_cast<const char*>(p), n); };
    for (const Tile& t : mine_) {
        const TileWork& w = work_[static_cast<size_t>(t.index)];
        const std::string made = serialize_records(w.made);
        const uint64_t head[4] = {static_cast<uint64_t>(t.index), made.size(), w.requests.size(), w.deferred.size()};
        put(head, sizeof(head));
        put(made.data(), made.size());
        put(w.requests.data(), w.requests.size() * sizeof(uint32_t));
        put(w.deferred.data(), w.deferred.size() * sizeof(Candidate));
    }
    const std::vector<std::string> all = o_.comm->allgather(mine);
    for (int r = 0; r < o_.comm->size(); ++r) {
        if (r == o_.comm->rank()) continue;
        const std::string& b = all[static_cast<size_t>(r)];
        for (size_t at = 0; at < b.size();) {
            uint64_t head[4];
            std::memcpy(head, b.data() + at, sizeof(head));
            at += sizeof(head);
            TileWork& w = work_.at(head[0]);
            w.made = parse_records(b.substr(at, head[1]));
            at += head[1];
            w.requests.resize(head[2]);
            std::memcpy(w.requests.data(), b.data() + at, head[2] * sizeof(uint32_t));
            at += head[2] * sizeof(uint32_t);
            w.deferred.resize(head[3]);
            std::memcpy(w.deferred.data(), b.data() + at, head[3] * sizeof(Candidate));
            at += head[3] * sizeof(Candidate);
        }
    }
}

/// Late gathers are judged and made by the process whose tile holds the candidate; each sends
/// its candidates' verdicts and records in index order.
void Gathering::share_late(const std::vector<Candidate>& deferred, std::vector<uint8_t>& still, std::vector<Record>& late) {
    const auto rank = static_cast<size_t>(o_.comm->rank());
    std::string flags;
    std::vector<Record> made;
    for (size_t i = 0; i < late.size(); ++i)
        if (owner_of(deferred[i]) == rank) {
            flags.push_back(static_cast<char>(still[i]));
            if (still[i]) made.push_back(late[i]);
        }
    const uint64_t n = flags.size();
    const std::vector<std::string> all =
        o_.comm->allgather(std::string(reinterpret_cast<const char*>(&n), sizeof(n)) + flags + serialize_records(made));
    for (size_t r = 0; r < all.size(); ++r) {
        if (r == rank) continue;
        uint64_t count = 0;
        std::memcpy(&count, all[r].data(), sizeof(count));
        std::vector<Record> theirs = parse_records(all[r].substr(sizeof(count) + count));
        size_t next_flag = sizeof(count), next = 0;
        for (size_t i = 0; i < late.size(); ++i)
            if (owner_of(deferred[i]) == r) {
                still[i] = static_cast<uint8_t>(all[r].at(next_flag++));
                if (still[i]) late[i] = std::move(theirs.at(next++));
            }
    }
}

void Gathering::subpass(const SubPass& sp) {
    // 1. Each tile judges its candidates against the cache as it was when the sub-pass began
    //    (shared lock; nobody writes until step 2) and gathers at the misses. Under MPI each
    //    process judges its own tiles and the tiles' work is exchanged.
    for_each_tile(mine_, [&](const Tile& t) { judge_tile(sp, t); });
    if (o_.comm && o_.comm->size() > 1) exchange_work();
    std::vector<Record> made;
    std::vector<uint32_t> requests;
    std::vector<Candidate> deferred;
    for (TileWork& w : work_) {
        made.insert(made.end(), w.made.begin(), w.made.end());
        requests.insert(requests.end(), w.requests.begin(), w.requests.end());
        deferred.insert(deferred.end(), w.deferred.begin(), w.deferred.end());
    }
    // 2. Stale records redone, in their order; then the new records.
    if (!requests.empty()) {
        std::sort(requests.begin(), requests.end());
        requests.erase(std::unique(requests.begin(), requests.end()), requests.end());
        std::vector<Record> redone = o_.stale->redo(requests, stats_);
        auto lock = lock_cache<std::unique_lock<std::shared_mutex>>(cache_, stats_.local());
        for (Record& r : redone) cache_.insert(std::move(r));
    }
    insert_new(std::move(made));
    // 3. The misses that waited for redone records: those still missing get records of their own.
    if (deferred.empty()) return;
    // Under MPI each process judges and gathers the candidates of its own tiles (it holds only
    // their fragments); share_late gives every process the others'.
    const bool shared = o_.comm && o_.comm->size() > 1;
    const auto mine = [&](size_t i) { return !shared || owner_of(deferred[i]) == static_cast<size_t>(o_.comm->rank()); };
    std::vector<uint8_t> still(deferred.size(), 0);
    std::vector<Record> late(deferred.size());
    parallel_for_each_index(0, static_cast<int>(deferred.size()), [&](int i) {
        const auto u = static_cast<size_t>(i);
        if (!mine(u)) return;
        const Candidate& c = deferred[u];
        const Site site = record_site(scene_, deep_.pixel(c.wx, c.wy)[c.k], cache_.settings(), c.side);
        still[u] = cache_.misses(site.p, site.n, {}, o_.own_weight, o_.min_weight);
        if (still[u]) late[u] = gather_at(c, stats_.local());
    });
    if (shared) share_late(deferred, still, late);
    std::vector<Record> kept;
    for (size_t i = 0; i < late.size(); ++i)
        if (still[i]) kept.push_back(std::move(late[i]));
    insert_new(std::move(kept));
}

}  // namespace

void gathering_pass(const Scene& scene, const DeepBuffer& deep, const Gatherer& gatherer, IrradianceCache& cache, Stats& stats,
                    ProgressSink* sink, const GatheringOptions& options) {
    const auto schedule = subpass_schedule(static_cast<int>(cache.settings().max_spacing));
    Progress progress(sink, "gathering", schedule.size());
    Gathering g(scene, deep, gatherer, cache, stats, options);
    for (size_t si = 0; si < schedule.size(); ++si) {
        g.subpass(schedule[si]);
        progress.add();
        if (options.after_subpass) options.after_subpass(schedule[si], si, schedule.size());
    }
    stats.set("records", static_cast<double>(cache.size()));
    stats.set("record_gathers", static_cast<double>(g.gathered));
    if (options.first) {
        size_t full = 0;
        for (size_t n : g.full_gathers) full += n;
        stats.set("record_gathers_full_rays", static_cast<double>(full));
        stats.set("record_first_rays", static_cast<double>(options.first->grid().rays()));
    }
    stats.set("records_dropped", static_cast<double>(g.dropped));
    stats.set("subpasses", static_cast<double>(schedule.size()));
    stats.set("rays_per_gather", g.gathered ? static_cast<double>(stats.total().gather_rays) / static_cast<double>(g.gathered) : 0.0);
    stats.set("cache_bytes", static_cast<double>(cache.memory_bytes()));
}

}  // namespace bounce
