#include "bounce/core/stats.h"

#include <fmt/format.h>

#include <algorithm>
#include <sys/resource.h>

namespace bounce {

Counters& Counters::operator+=(const Counters& o) {
    camera_rays += o.camera_rays;
    shadow_rays += o.shadow_rays;
    gather_rays += o.gather_rays;
    specular_rays += o.specular_rays;
    fragments_shaded += o.fragments_shaded;
    lock_wait_ns += o.lock_wait_ns;
    radiosity_bake_ns += o.radiosity_bake_ns;
    hits_lit += o.hits_lit;
    hits_lit_ns += o.hits_lit_ns;
    return *this;
}

Counters Stats::total() const {
    Counters t;
    for (const auto& c : per_thread_) t += c;
    return t;
}

void Stats::add_phase(const std::string& name, double seconds) {
    for (auto& [n, s] : phases_)
        if (n == name) {
            s += seconds;
            return;
        }
    phases_.emplace_back(name, seconds);
}

nlohmann::json Stats::to_json() const {
    Counters t = total();
    nlohmann::json j;
    nlohmann::json phases = nlohmann::json::object();
    double total_time = 0;
    for (const auto& [n, s] : phases_) {
        phases[n] = s;
        total_time += s;
    }
    j["phases_s"] = phases;
    j["total_s"] = total_time;
    uint64_t rays = t.camera_rays + t.shadow_rays + t.gather_rays + t.specular_rays;
    j["rays"] = {
        {"camera", t.camera_rays}, {"shadow", t.shadow_rays}, {"gather", t.gather_rays}, {"specular", t.specular_rays}, {"total", rays}};
    j["rays_per_s"] = total_time > 0 ? static_cast<double>(rays) / total_time : 0.0;
    j["fragments_shaded"] = t.fragments_shaded;
    j["lock_wait_s"] = static_cast<double>(t.lock_wait_ns) * 1e-9;
    j["radiosity_bake_cpu_s"] = static_cast<double>(t.radiosity_bake_ns) * 1e-9;
    j["hits_lit"] = t.hits_lit;
    j["hits_lit_cpu_s"] = static_cast<double>(t.hits_lit_ns) * 1e-9;
    j["peak_rss_bytes"] = peak_rss_bytes();
    for (auto it = extra_.begin(); it != extra_.end(); ++it) j[it.key()] = it.value();
    return j;
}

std::string Stats::to_text() const {
    nlohmann::json j = to_json();
    std::string s = "bounce statistics\n";
    for (const auto& [n, t] : phases_) s += fmt::format("  {:<24} {:>10.3f} s\n", n, t);
    s += fmt::format("  {:<24} {:>10.3f} s\n", "total", j["total_s"].get<double>());
    s += fmt::format("  {:<24} {:>10}\n", "camera rays", j["rays"]["camera"].get<uint64_t>());
    s += fmt::format("  {:<24} {:>10}\n", "shadow rays", j["rays"]["shadow"].get<uint64_t>());
    s += fmt::format("  {:<24} {:>10}\n", "gather rays", j["rays"]["gather"].get<uint64_t>());
    s += fmt::format("  {:<24} {:>10.3f} M/s\n", "rays/s", j["rays_per_s"].get<double>() * 1e-6);
    s += fmt::format("  {:<24} {:>10.6f} s\n", "cache lock wait", j["lock_wait_s"].get<double>());
    s += fmt::format("  {:<24} {:>10.6f} s (CPU, inside gathering)\n", "radiosity bake", j["radiosity_bake_cpu_s"].get<double>());
    if (const auto lit = j["hits_lit"].get<uint64_t>())
        s += fmt::format("  {:<24} {:>10.6f} s (CPU, {} hits on small instances)\n", "light at gather hits",
                         j["hits_lit_cpu_s"].get<double>(), lit);
    for (auto it = extra_.begin(); it != extra_.end(); ++it) s += fmt::format("  {:<24} {:>10}\n", it.key(), it.value().dump());
    s += fmt::format("  {:<24} {:>10.1f} MiB\n", "peak memory", static_cast<double>(peak_rss_bytes()) / (1024.0 * 1024.0));
    return s;
}

double PhaseTimer::stop() {
    double s = std::chrono::duration<double>(std::chrono::steady_clock::now() - start_).count();
    if (!stopped_) {
        stats_.add_phase(name_, s);
        stopped_ = true;
    }
    return s;
}

uint64_t peak_rss_bytes() {
    rusage u{};
    getrusage(RUSAGE_SELF, &u);
    return static_cast<uint64_t>(u.ru_maxrss) * 1024u;
}

std::string seed_table(const nlohmann::json& s) {
    auto clock = [](double secs) { return fmt::format("{}:{:06.3f}", static_cast<int>(secs) / 60, std::fmod(secs, 60.0)); };
    const auto& ph = s["phases_s"];
    auto phase = [&](const char* n) { return ph.contains(n) ? ph[n].get<double>() : 0.0; };
    // Radiosity textures bake lazily inside the gathers: their share of the gathering wall time
    // (bake CPU time over the threads) is reported as its own column.
    const double threads = std::max(1.0, s.value("threads", 1.0));
    const double bake = phase("radiosity bake") + s.value("radiosity_bake_cpu_s", 0.0) / threads;
    const double gathering = std::max(0.0, phase("gather") + phase("radiosity load") - s.value("radiosity_bake_cpu_s", 0.0) / threads);
    double shading = phase("shading");
    double total = s["total_s"].get<double>();
    double pixels = s.value("pixels", 0.0);
    double rays = static_cast<double>(s["rays"]["gather"].get<uint64_t>());
    std::string per_record = s.contains("records") ? fmt::format("{}", s.value("rays_per_gather", 0)) : "-";
    std::string records = s.contains("records") ? fmt::format("{}", s["records"].get<double>()) : "-";
    return fmt::format(
        "| radiosity bake | gathering | shading | total | rays/record | records | rays/MP |\n"
        "| {} | {} | {} | {} | {} | {} | {:.1f} M |\n",
        clock(bake), clock(gathering), clock(shading), clock(total), per_record, records, pixels > 0 ? rays / pixels : 0.0);
}

}  // namespace bounce
