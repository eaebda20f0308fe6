// Render statistics: cheap per-thread counters folded at the end, and wall time per phase.
// Printed by `--stats`, always written by `--stats-json`.
#pragma once

#include <tbb/enumerable_thread_specific.h>

#include <chrono>
#include <cstdint>
#include <nlohmann/json.hpp>
#include <string>
#include <vector>

namespace bounce {

/// Counters one thread increments without synchronisation.
struct Counters {
    uint64_t camera_rays = 0;
    uint64_t shadow_rays = 0;
    uint64_t gather_rays = 0;
    uint64_t specular_rays = 0;  ///< mirror and glass rays (reflection, refraction)
    uint64_t fragments_shaded = 0;
    uint64_t lock_wait_ns = 0;       ///< time spent waiting for the cache's reader-writer lock
    uint64_t radiosity_bake_ns = 0;  ///< time spent baking radiosity texture sides (lazily, inside gathers)
    uint64_t hits_lit = 0;           ///< gather hits on small instances lit where they landed (RadiositySettings::small_instances)
    uint64_t hits_lit_ns = 0;        ///< time spent lighting them
    Counters& operator+=(const Counters& o);
};

/// Per-render statistics. Threads call `local()` to get their own counters.
class Stats {
  public:
    Counters& local() { return per_thread_.local(); }
    Counters total() const;

    /// Records the wall time of a named phase (phases keep their first-seen order).
    void add_phase(const std::string& name, double seconds);
    const std::vector<std::pair<std::string, double>>& phases() const { return phases_; }

    /// Extra named values (pixels, fragments, records ...) shown in the stats block.
    void set(const std::string& key, double value) { extra_[key] = value; }
    void set(const std::string& key, nlohmann::json value) { extra_[key] = std::move(value); }
    const nlohmann::json& extra() const { return extra_; }

    nlohmann::json to_json() const;
    /// Human-readable block for `--stats`.
    std::string to_text() const;

  private:
    tbb::enumerable_thread_specific<Counters> per_thread_;
    std::vector<std::pair<std::string, double>> phases_;
    nlohmann::json extra_ = nlohmann::json::object();
};

/// Measures a phase from construction to destruction (or `stop()`), adding it to `stats`.
class PhaseTimer {
  public:
    PhaseTimer(Stats& stats, std::string name) : stats_(stats), name_(std::move(name)), start_(std::chrono::steady_clock::now()) {}
    ~PhaseTimer() { stop(); }
    double stop();
    PhaseTimer(const PhaseTimer&) = delete;
    PhaseTimer& operator=(const PhaseTimer&) = delete;

  private:
    Stats& stats_;
    std::string name_;
    std::chrono::steady_clock::time_point start_;
    bool stopped_ = false;
};

/// The seed's table (TL04 class notes): gathering, shading, total, rays per record, records,
/// rays per megapixel (millions) — a header line and one row, from Stats::to_json().
std::string seed_table(const nlohmann::json& stats);

/// Peak resident set size of this process, in bytes.
uint64_t peak_rss_bytes();

}  // namespace bounce
