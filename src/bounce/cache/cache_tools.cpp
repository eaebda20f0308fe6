#include "bounce/cache/cache_tools.h"

#include <fmt/format.h>

#include <algorithm>
#include <array>
#include <cstring>
#include <fstream>
#include <map>
#include <regex>

#include "bounce/cache/irradiance_cache.h"
#include "bounce/core/atomic_file.h"
#include "bounce/core/error.h"
#include "bounce/core/files.h"
#include "bounce/config/params.h"
#include "bounce/core/image.h"

namespace bounce {

nlohmann::json cache_info(const CacheFile& f, size_t file_bytes) {
    nlohmann::json j;
    j["records"] = f.records.size();
    j["fragment_records"] = f.fragment_records.size();
    j["frame"] = f.info.frame;
    j["scene_fingerprint"] = fmt::format("{:016x}", f.info.scene_fingerprint);
    j["camera_fingerprint"] = fmt::format("{:016x}", f.info.camera_fingerprint);
    j["parameters"] = f.info.parameters;
    Bounds b;
    double rays = 0, mean_e = 0;
    std::map<int, size_t> frames;
    const std::vector<float> edges = {1, 2, 4, 8, 16, 32, 64};
    std::vector<size_t> hist(edges.size() + 1, 0);
    for (const Record& r : f.records) {
        b.extend(r.p);
        rays += r.rays;
        mean_e += luminance(r.E);
        ++frames[r.frame];
        float px = r.radius / r.footprint;
        size_t k = static_cast<size_t>(std::upper_bound(edges.begin(), edges.end(), px) - edges.begin());
        ++hist[k];
    }
    if (!f.records.empty()) {
        j["bounds"] = {{b.lo.x, b.lo.y, b.lo.z}, {b.hi.x, b.hi.y, b.hi.z}};
        j["mean_rays_per_record"] = rays / static_cast<double>(f.records.size());
        j["mean_irradiance_luminance"] = mean_e / static_cast<double>(f.records.size());
    }
    nlohmann::json h = nlohmann::json::array();
    for (size_t k = 0; k < hist.size(); ++k) {
        std::string label = k == 0              ? fmt::format("<{}", edges[0])
                            : k == edges.size() ? fmt::format(">={}", edges.back())
                                                : fmt::format("{}-{}", edges[k - 1], edges[k]);
        h.push_back({{"pixels", label}, {"records", hist[k]}});
    }
    j["radius_pixels_histogram"] = h;
    nlohmann::json fr = nlohmann::json::object();
    for (const auto& [frame, n] : frames) fr[std::to_string(frame)] = n;
    j["records_by_frame"] = fr;
    j["file_bytes"] = file_bytes;
    j["memory_bytes"] = (f.records.size() + f.fragment_records.size()) * sizeof(Record);
    return j;
}

std::string cache_info_text(const nlohmann::json& j, const std::string& path) {
    std::string s = fmt::format("{}: {} records, {} fragment records (frame {})\n", path, j["records"].get<size_t>(),
                                j["fragment_records"].get<size_t>(), j["frame"].get<int>());
    if (j.contains("bounds")) s += fmt::format("  bounds       {} .. {}\n", j["bounds"][0].dump(), j["bounds"][1].dump());
    if (j.contains("mean_rays_per_record"))
        s += fmt::format("  rays/record  {:.0f}\n  mean E (Y)   {:.4g}\n", j["mean_rays_per_record"].get<double>(),
                         j["mean_irradiance_luminance"].get<double>());
    s += fmt::format("  scene        {}  camera {}\n", j["scene_fingerprint"].get<std::string>(),
                     j["camera_fingerprint"].get<std::string>());
    s += "  parameters  ";
    for (auto it = j["parameters"].begin(); it != j["parameters"].end(); ++it) s += " " + it.key() + "=" + it.value().dump();
    s += "\n  radius in pixels:\n";
    size_t most = 1;
    for (const auto& h : j["radius_pixels_histogram"]) most = std::max(most, h["records"].get<size_t>());
    for (const auto& h : j["radius_pixels_histogram"]) {
        size_t n = h["records"].get<size_t>();
        s += fmt::format("    {:>6} {:>8} {}\n", h["pixels"].get<std::string>(), n, std::string(40 * n / most, '#'));
    }
    s += "  records by frame:";
    for (auto it = j["records_by_frame"].begin(); it != j["records_by_frame"].end(); ++it)
        s += fmt::format(" {}:{}", it.key(), it.value().get<size_t>());
    s += fmt::format("\n  memory       {:.2f} MiB in memory, {:.2f} MiB on disk\n",
                     static_cast<double>(j["memory_bytes"].get<size_t>()) / 1048576.0,
                     static_cast<double>(j["file_bytes"].get<size_t>()) / 1048576.0);
    return s;
}

namespace {

/// The cache settings a file's parameters name (through the parameter table); the defaults
/// for parameters it does not record or records with values out of range.
CacheSettings settings_from(const nlohmann::json& parameters) {
    Camera camera;
    RenderSettings render;
    for (const Param& p : scene_params()) {
        if (!parameters.contains(p.key)) continue;
        try {
            set_param_value(ParamsOut(camera, render), p.key, parameters[p.key]);
        } catch (const std::invalid_argument&) {}
    }
    return render.cache;
}

std::string record_bytes(const Record& r) {
    CacheFile one;
    one.records = {r};
    return serialize_cache_file(one);  // deterministic bytes: a canonical sort key
}

}  // namespace

CacheFile merge_caches(const CacheFile& a, const CacheFile& b, const std::string& name_a, const std::string& name_b, bool force) {
    if (!force && (a.info.scene_fingerprint != b.info.scene_fingerprint || a.info.camera_fingerprint != b.info.camera_fingerprint))
        throw InputError(name_b, "fingerprint", "cache belongs to another scene or camera than " + name_a + " (--force merges anyway)");
    const bool ao_a = a.info.parameters.value("render.ao", false), ao_b = b.info.parameters.value("render.ao", false);
    if (!force && ao_a != ao_b)
        throw InputError(name_b, "parameters/render.ao",
                         fmt::format("cache holds {} but {} holds {} (--force merges anyway)", ao_b ? "AO" : "irradiance", name_a,
                                     ao_a ? "AO" : "irradiance"));
    // Records made under other settings (metric, spacings, rays ...) would be judged by the
    // first file's settings and the result accepted by --cache-in as if made with them.
    if (const std::vector<std::string> differ = param_differences(a.info.parameters, b.info.parameters); !force && !differ.empty())
        throw InputError(name_b, "parameters",
                         fmt::format("gathered with other settings than {} ({}); --force merges anyway", name_a, fmt::join(differ, "; ")));
    struct Item {
        std::string bytes;
        const Record* r;
        int source;
    };
    std::vector<Item> items;
    for (const Record& r : a.records) items.push_back({record_bytes(r), &r, 0});
    for (const Record& r : b.records) items.push_back({record_bytes(r), &r, 1});
    std::stable_sort(items.begin(), items.end(), [](const Item& x, const Item& y) {
        if (x.r->key != y.r->key) return x.r->key < y.r->key;
        return x.bytes < y.bytes;
    });
    Bounds bounds;
    for (const Item& it : items) bounds.extend(it.r->p);
    CacheSettings s = settings_from(a.info.parameters);
    // One index per source: a record is dropped only when the other source covers it.
    IrradianceCache kept[2] = {IrradianceCache(bounds, s, false), IrradianceCache(bounds, s, false)};
    CacheFile out;
    out.info = a.info;
    for (const Item& it : items) {
        if (!kept[1 - it.source].misses(it.r->p, it.r->n)) continue;
        kept[it.source].insert_loaded(*it.r);
        out.records.push_back(*it.r);
    }
    // Fragment records: one per fragment key; of two for the same key, the one with the
    // smaller bytes, so the merge is commutative.
    std::map<uint64_t, std::pair<std::string, const Record*>> own;
    for (const auto* list : {&a.fragment_records, &b.fragment_records})
        for (const Record& r : *list) {
            std::string bytes = record_bytes(r);
            auto [it, fresh] = own.try_emplace(r.key, bytes, &r);
            if (!fresh && bytes < it->second.first) it->second = {std::move(bytes), &r};
        }
    for (const auto& [key, kept_one] : own) out.fragment_records.push_back(*kept_one.second);
    return out;
}

namespace {

/// The --where fields, by the names the CLI takes.
constexpr std::array<std::pair<std::string_view, WhereTerm::Field>, 15> kWhereFields{{{"p.x", WhereTerm::Field::PX},
                                                                                      {"p.y", WhereTerm::Field::PY},
                                                                                      {"p.z", WhereTerm::Field::PZ},
                                                                                      {"n.x", WhereTerm::Field::NX},
                                                                                      {"n.y", WhereTerm::Field::NY},
                                                                                      {"n.z", WhereTerm::Field::NZ},
                                                                                      {"E.r", WhereTerm::Field::ER},
                                                                                      {"E.g", WhereTerm::Field::EG},
                                                                                      {"E.b", WhereTerm::Field::EB},
                                                                                      {"E.y", WhereTerm::Field::EY},
                                                                                      {"ao", WhereTerm::Field::Ao},
                                                                                      {"radius", WhereTerm::Field::Radius},
                                                                                      {"pixels", WhereTerm::Field::Pixels},
                                                                                      {"rays", WhereTerm::Field::Rays},
                                                                                      {"frame", WhereTerm::Field::Frame}}};
constexpr std::array<std::pair<std::string_view, WhereTerm::Op>, 6> kWhereOps{{{"<", WhereTerm::Op::Less},
                                                                               {"<=", WhereTerm::Op::LessEqual},
                                                                               {">", WhereTerm::Op::Greater},
                                                                               {">=", WhereTerm::Op::GreaterEqual},
                                                                               {"==", WhereTerm::Op::Equal},
                                                                               {"!=", WhereTerm::Op::NotEqual}}};

double field_value(const Record& r, WhereTerm::Field f) {
    using F = WhereTerm::Field;
    switch (f) {
        case F::PX:
            return r.p.x;
        case F::PY:
            return r.p.y;
        case F::PZ:
            return r.p.z;
        case F::NX:
            return r.n.x;
        case F::NY:
            return r.n.y;
        case F::NZ:
            return r.n.z;
        case F::ER:
            return r.E.x;
        case F::EG:
            return r.E.y;
        case F::EB:
            return r.E.z;
        case F::EY:
            return luminance(r.E);
        case F::Ao:
            return r.ao;
        case F::Radius:
            return r.radius;
        case F::Pixels:
            return r.radius / r.footprint;
        case F::Rays:
            return r.rays;
        case F::Frame:
            return r.frame;
    }
    return 0;
}

}  // namespace

WhereTerm WhereTerm::parse(const std::string& term) {
    static const std::regex re(R"(\s*([A-Za-z_]+(?:\.[A-Za-z])?)\s*(<=|>=|==|!=|<|>)\s*(-?[0-9.eE+-]+)\s*)");
    std::smatch m;
    if (!std::regex_match(term, m, re))
        throw InputError("command line", "--where " + term, "expected FIELD OP NUMBER, e.g. \"radius<0.5\" or \"E.y>=0.1\"");
    const std::string name = m[1], op = m[2];
    auto field = std::find_if(kWhereFields.begin(), kWhereFields.end(), [&](const auto& f) { return f.first == name; });
    if (field == kWhereFields.end()) {
        std::vector<std::string_view> names;
        for (const auto& f : kWhereFields) names.push_back(f.first);
        throw InputError("command line", "--where " + term, fmt::format("unknown field \"{}\" (valid: {})", name, fmt::join(names, ", ")));
    }
    WhereTerm w;
    w.field = field->second;
    w.op = std::find_if(kWhereOps.begin(), kWhereOps.end(), [&](const auto& o) { return o.first == op; })->second;
    try {
        w.value = std::stod(m[3]);
    } catch (...) {
        throw InputError("command line", "--where " + term, "bad number");
    }
    return w;
}

bool WhereTerm::holds(const Record& r) const {
    const double v = field_value(r, field);
    switch (op) {
        case Op::Less:
            return v < value;
        case Op::LessEqual:
            return v <= value;
        case Op::Greater:
            return v > value;
        case Op::GreaterEqual:
            return v >= value;
        case Op::Equal:
            return v == value;
        case Op::NotEqual:
            return v != value;
    }
    return false;
}

bool RecordFilter::matches(const Record& r) const {
    if (has_box && (r.p.x < box_lo.x || r.p.y < box_lo.y || r.p.z < box_lo.z || r.p.x > box_hi.x || r.p.y > box_hi.y || r.p.z > box_hi.z))
        return false;
    if (has_sphere && length(r.p - center) > radius) return false;
    return std::all_of(where.begin(), where.end(), [&](const WhereTerm& w) { return w.holds(r); });
}

CacheFile filter_cache(const CacheFile& in, const RecordFilter& filter, bool remove) {
    CacheFile out;
    out.info = in.info;
    for (const Record& r : in.records)
        if (filter.matches(r) != remove) out.records.push_back(r);
    for (const Record& r : in.fragment_records)
        if (filter.matches(r) != remove) out.fragment_records.push_back(r);
    return out;
}

void export_ply(const CacheFile& f, const std::string& path) {
    std::string header = fmt::format(
        "ply\nformat binary_little_endian 1.0\ncomment bounce irradiance cache: {} records\nelement vertex {}\n"
        "property float x\nproperty float y\nproperty float z\nproperty float nx\nproperty float ny\nproperty float nz\n"
        "property uchar red\nproperty uchar green\nproperty uchar blue\nproperty float irradiance_r\n"
        "property float irradiance_g\nproperty float irradiance_b\nproperty float ao\nproperty float radius\nend_header\n",
        f.records.size(), f.records.size());
    // Colours: irradiance scaled so the 99th percentile luminance maps to white, sRGB-encoded.
    std::vector<float> ys;
    for (const Record& r : f.records) ys.push_back(luminance(r.E));
    std::sort(ys.begin(), ys.end());
    float top = ys.empty() ? 1.0f : std::max(1e-12f, ys[static_cast<size_t>(0.99 * static_cast<double>(ys.size() - 1))]);
    std::string body;
    auto putf = [&](float v) { body.append(reinterpret_cast<const char*>(&v), 4); };
    for (const Record& r : f.records) {
        putf(r.p.x), putf(r.p.y), putf(r.p.z), putf(r.n.x), putf(r.n.y), putf(r.n.z);
        for (int c = 0; c < 3; ++c) body.push_back(static_cast<char>(std::lround(255 * srgb_encode(r.E[c] / top))));
        putf(r.E.x), putf(r.E.y), putf(r.E.z), putf(r.ao), putf(r.radius);
    }
    write_atomically(path, [&](const std::string& tmp) {
        std::ofstream out(tmp, std::ios::binary);
        out << header << body;
        if (!out) throw InputError(path, "", "cannot write PLY file");
    });
}

void check_tool_output(const ToolCall& call, const std::string& output, const char* extension, const char* what,
                       const std::vector<std::string>& inputs) {
    if (lower_extension(output) != extension)
        throw InputError(call.source, call.output_place, fmt::format("{} is written as a {} file", what, extension));
    check_output_file(output, inputs);
}

CacheFile merge_cache_files(const ToolCall& call, const std::vector<std::string>& inputs, const std::string& output, bool force) {
    check_tool_output(call, output, ".bic", "the merged cache", inputs);
    if (inputs.size() < 2) throw InputError(call.source, call.command, "give at least two caches to merge");
    CacheFile out = read_cache_file(inputs[0]);
    for (size_t i = 1; i < inputs.size(); ++i) out = merge_caches(out, read_cache_file(inputs[i]), inputs[0], inputs[i], force);
    write_cache_file(output, out);
    return out;
}

std::pair<CacheFile, CacheFile> filter_cache_file(const ToolCall& call, const std::string& input, const std::string& output,
                                                  const RecordFilter& filter, bool remove) {
    check_tool_output(call, output, ".bic", "the filtered cache", {input});
    if (!filter.has_box && !filter.has_sphere && filter.where.empty())
        throw InputError(call.source, call.command, "give a box, a sphere or a where term");
    CacheFile in = read_cache_file(input);
    CacheFile out = filter_cache(in, filter, remove);
    write_cache_file(output, out);
    return {std::move(in), std::move(out)};
}

}  // namespace bounce
