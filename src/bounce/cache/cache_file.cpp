#include "bounce/cache/cache_file.h"

#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <cstring>
#include <filesystem>
#include <fstream>

#include "bounce/core/json_limits.h"
#include "bounce/core/atomic_file.h"
#include "bounce/core/error.h"
#include "bounce/core/files.h"
#include "bounce/scene/shot.h"
#include "bounce/core/version.h"

namespace bounce {

namespace {

constexpr char kMagic[8] = {'B', 'O', 'U', 'N', 'C', 'E', 'I', 'C'};
constexpr uint32_t kBlockRecords = 4096;
constexpr uint32_t kMaxHeader = 1u << 20;

/// Record fields in file order: name, type, count. Floats are IEEE-754 binary32 little-endian.
struct Field {
    const char* name;
    const char* type;
    int count;
};
const Field kFields[] = {
    {"p", "f32", 3},
    {"n", "f32", 3},
    {"E", "f32", 3},
    {"ao", "f32", 1},
    {"bent", "f32", 3},
    {"dir", "f32", 9},
    {"grad_r", "f32", 9},
    {"grad_t", "f32", 9},
    {"ao_grad_r", "f32", 3},
    {"ao_grad_t", "f32", 3},
    {"radius", "f32", 1},
    {"raw_radius", "f32", 1},
    {"footprint", "f32", 1},
    {"harmonic", "f32", 1},
    {"dmin", "f32", 1},
    {"weber", "f32", 1},
    {"radius_long", "f32", 1},
    {"axis", "f32", 3},
    {"key", "u64", 1},
    {"rays", "u32", 1},
    {"frame", "i32", 1},
    {"origin", "f32", 3},
    {"reach", "f32", kReachBins},
    {"anchor", "u32", 1},
    {"anchor_p", "f32", 3},
    {"anchor_n", "f32", 3},
    {"gathered", "i32", 1},
    {"drift", "f32", 1},
    {"near", "f32", 1},
    {"anchor_prim", "u32", 1},
    {"noise", "f32", 1},
    {"bins", "f32", 3 * kReachBins},
};
constexpr size_t kFloats = 3 + 3 + 3 + 1 + 3 + 9 + 9 + 9 + 3 + 3 + 6 + 4 + 3 + kReachBins + 3 + 3 + 1 + 1 + 1 + 3 * kReachBins;
constexpr size_t kRecordBytes = kFloats * 4 + 8 + 4 + 4 + 4 + 4 + 4;

uint64_t fnv1a(const char* data, size_t n) {
    uint64_t h = 0xcbf29ce484222325ULL;
    for (size_t i = 0; i < n; ++i) h = (h ^ static_cast<uint8_t>(data[i])) * 0x100000001b3ULL;
    return h;
}

template <typename T>
void put(std::string& out, T v) {
    char b[sizeof(T)];
    std::memcpy(b, &v, sizeof(T));  // the project targets little-endian x86-64 / arm64
    out.append(b, sizeof(T));
}

void put_vec(std::string& out, const Vec3& v) { put(out, v.x), put(out, v.y), put(out, v.z); }

void write_record(std::string& out, const Record& r) {
    put_vec(out, r.p), put_vec(out, r.n), put_vec(out, r.E), put(out, r.ao), put_vec(out, r.bent);
    for (const auto& v : r.dir) put_vec(out, v);
    for (const auto& v : r.grad_r) put_vec(out, v);
    for (const auto& v : r.grad_t) put_vec(out, v);
    put_vec(out, r.ao_grad_r), put_vec(out, r.ao_grad_t);
    put(out, r.radius), put(out, r.raw_radius), put(out, r.footprint), put(out, r.harmonic), put(out, r.dmin), put(out, r.weber);
    put(out, r.radius_long), put_vec(out, r.axis);
    put(out, r.key), put(out, r.rays), put(out, r.frame);
    put_vec(out, r.origin);
    for (float d : r.reach) put(out, d);
    put(out, r.anchor), put_vec(out, r.anchor_p), put_vec(out, r.anchor_n), put(out, r.gathered), put(out, r.drift);
    put(out, r.near), put(out, r.anchor_prim), put(out, r.noise);
    for (const Color& b : r.bin_values()) put_vec(out, b);
}

/// Sequential reader over the file's bytes with bounds checks.
class Cursor {
  public:
    Cursor(const std::string& b, const std::string& name) : b_(b), name_(name) {}
    template <typename T>
    T get(const char* what) {
        need(sizeof(T), what);
        T v;
        std::memcpy(&v, b_.data() + pos_, sizeof(T));
        pos_ += sizeof(T);
        return v;
    }
    Vec3 vec(const char* what) {
        float x = get<float>(what), y = get<float>(what), z = get<float>(what);
        return {x, y, z};
    }
    std::string bytes(size_t n, const char* what) {
        need(n, what);
        std::string s = b_.substr(pos_, n);
        pos_ += n;
        return s;
    }
    size_t remaining() const { return b_.size() - pos_; }
    size_t pos() const { return pos_; }
    [[noreturn]] void fail(const std::string& msg) const { throw InputError(name_, fmt::format("byte {}", pos_), msg); }

  private:
    void need(size_t n, const char* what) const {
        if (n > remaining()) fail(fmt::format("file is truncated (reading {})", what));
    }
    const std::string& b_;
    const std::string& name_;
    size_t pos_ = 0;
};

Record read_record(Cursor& c) {
    Record r;
    r.p = c.vec("p"), r.n = c.vec("n"), r.E = c.vec("E"), r.ao = c.get<float>("ao"), r.bent = c.vec("bent");
    for (auto& v : r.dir) v = c.vec("dir");
    for (auto& v : r.grad_r) v = c.vec("grad_r");
    for (auto& v : r.grad_t) v = c.vec("grad_t");
    r.ao_grad_r = c.vec("ao_grad_r"), r.ao_grad_t = c.vec("ao_grad_t");
    r.radius = c.get<float>("radius"), r.raw_radius = c.get<float>("raw_radius");
    r.footprint = c.get<float>("footprint"), r.harmonic = c.get<float>("harmonic"), r.dmin = c.get<float>("dmin");
    r.weber = c.get<float>("weber");
    r.radius_long = c.get<float>("radius_long"), r.axis = c.vec("axis");
    r.key = c.get<uint64_t>("key"), r.rays = c.get<uint32_t>("rays"), r.frame = c.get<int32_t>("frame");
    r.origin = c.vec("origin");
    for (float& d : r.reach) d = c.get<float>("reach");
    r.anchor = c.get<uint32_t>("anchor"), r.anchor_p = c.vec("anchor_p"), r.anchor_n = c.vec("anchor_n");
    r.gathered = c.get<int32_t>("gathered"), r.drift = c.get<float>("drift"), r.near = c.get<float>("near");
    r.anchor_prim = c.get<uint32_t>("anchor_prim"), r.noise = c.get<float>("noise");
    std::array<Color, kReachBins> bins;
    for (Color& b : bins) b = c.vec("bins");
    r.set_bins(bins);
    return r;
}

/// Why a record read from a file cannot be used, or nullptr. Values are bounded so that every
/// later sum, square and BVH bound still fits a float.
const char* record_problem(const Record& r) {
    auto fin = [](const Vec3& v) { return isfinite(v); };
    if (!fin(r.p) || !fin(r.n) || !fin(r.E) || !fin(r.bent) || !std::isfinite(r.ao)) return "non-finite values";
    if (!within(r.p, kMaxCoordinate)) return "position beyond +-1e18";
    for (int c = 0; c < 3; ++c) {
        const auto i = static_cast<size_t>(c);
        if (!fin(r.dir[i]) || !fin(r.grad_r[i]) || !fin(r.grad_t[i])) return "non-finite gradients or directions";
        if (!within(r.dir[i], kMaxRadiometric) || !within(r.grad_r[i], kMaxRadiometric) || !within(r.grad_t[i], kMaxRadiometric))
            return "gradients or directions beyond 1e20";
        if (r.E[c] < 0 || r.E[c] > kMaxRadiometric) return "irradiance outside [0, 1e20]";
    }
    if (!fin(r.ao_grad_r) || !fin(r.ao_grad_t) || !within(r.ao_grad_r, kMaxRadiometric) || !within(r.ao_grad_t, kMaxRadiometric))
        return "AO gradients non-finite or beyond 1e20";
    if (r.ao < 0 || r.ao > 1) return "AO outside [0, 1]";
    if (!(r.radius > 0) || !(r.radius <= kMaxCoordinate) || !(r.footprint > 0) || !(r.footprint <= kMaxCoordinate))
        return "radius or footprint not in (0, 1e18]";
    if (std::abs(length(r.n) - 1) > 1e-3f) return "normal is not unit length";
    if (!(r.radius_long == 0 || (r.radius_long >= r.radius && r.radius_long <= kMaxCoordinate)))
        return "long radius is neither 0 nor in [radius, 1e18]";
    if (!isfinite(r.axis) || (r.radius_long > 0 && std::abs(length(r.axis) - 1) > 1e-3f)) return "axis is not a unit vector";
    if (r.weber <= 0 || std::isnan(r.weber)) return "gradient-limit distance is not positive";
    if (!fin(r.origin) || !within(r.origin, kMaxCoordinate)) return "gather origin not finite or beyond +-1e18";
    for (float d : r.reach)
        if (!(d >= 0)) return "reach is negative or NaN";
    if (r.anchor != kNoAnchor && (!fin(r.anchor_p) || !within(r.anchor_p, kMaxCoordinate) || !fin(r.anchor_n)))
        return "anchor not finite or beyond +-1e18";
    if (!(r.drift >= 0 && r.drift <= kMaxRadiometric)) return "drift is not in [0, 1e20]";
    if (!(r.near >= 0 && r.near <= kMaxCoordinate)) return "near distance is not in [0, 1e18]";
    if (!(r.noise >= 0 && r.noise <= kMaxRadiometric)) return "noise is not in [0, 1e20]";
    for (const Color& b : r.bin_values())
        if (!(b.x >= 0 && b.y >= 0 && b.z >= 0 && b.x <= kMaxRadiometric && b.y <= kMaxRadiometric && b.z <= kMaxRadiometric))
            return "direction bins outside [0, 1e20]";
    return nullptr;
}

/// Floats of one light part: E, then dir, grad_r and grad_t (3 vectors each).
constexpr size_t kPartFloats = 3 + 3 * 9;
/// The most lights a file's parts may be for (a bound on the header's word before allocating).
constexpr uint64_t kMaxPartLights = 1u << 16;

void write_part(std::string& out, const LightPart& p) {
    put_vec(out, p.E);
    for (const auto* a : {&p.dir, &p.grad_r, &p.grad_t})
        for (const Vec3& v : *a) put_vec(out, v);
}

LightPart read_part(Cursor& c) {
    LightPart p;
    p.E = c.vec("light part");
    for (auto* a : {&p.dir, &p.grad_r, &p.grad_t})
        for (Vec3& v : *a) v = c.vec("light part");
    return p;
}

/// The number of lights every record keeps its parts for (0: some record has none, or they
/// differ), as the first record says.
size_t parts_lights(const CacheFile& f) {
    const Record* first = !f.records.empty() ? &f.records[0] : !f.fragment_records.empty() ? &f.fragment_records[0] : nullptr;
    const size_t lights = first && first->parts ? first->parts->light.size() : 0;
    return keeps_light_parts(f, lights) ? lights : 0;
}

bool part_in_range(const LightPart& p) {
    const auto ok = [](const Vec3& v) { return isfinite(v) && within(v, kMaxRadiometric); };
    if (!ok(p.E)) return false;
    for (const auto* a : {&p.dir, &p.grad_r, &p.grad_t})
        for (const Vec3& v : *a)
            if (!ok(v)) return false;
    return true;
}

}  // namespace

bool keeps_light_parts(const CacheFile& file, size_t lights) {
    const auto has = [lights](const Record& r) { return r.parts && r.parts->light.size() == lights; };
    return lights > 0 && (!file.records.empty() || !file.fragment_records.empty()) &&
           std::all_of(file.records.begin(), file.records.end(), has) &&
           std::all_of(file.fragment_records.begin(), file.fragment_records.end(), has);
}

std::string serialize_records(std::span<const Record> records) {
    std::string out;
    put(out, static_cast<uint64_t>(records.size()));
    for (const Record& r : records) {
        write_record(out, r);
        put(out, r.support);  // in memory only: files recompute it
        const GatherHits* h = r.hits.get();
        put(out, static_cast<uint32_t>(h ? h->t.size() : 0));
        if (!h) continue;
        put(out, h->m), put(out, h->n);
        for (size_t c = 0; c < h->t.size(); ++c)
            put(out, h->t[c]), put(out, h->u[c]), put(out, h->v[c]), put(out, h->object[c]), put(out, h->prim[c]);
    }
    return out;
}

std::vector<Record> parse_records(const std::string& bytes) {
    const std::string name = "records from another process";
    Cursor c(bytes, name);
    const auto n = c.get<uint64_t>("count");
    std::vector<Record> out;
    out.reserve(static_cast<size_t>(std::min<uint64_t>(n, bytes.size() / kRecordBytes)));
    for (uint64_t i = 0; i < n; ++i) {
        Record r = read_record(c);
        r.support = c.get<float>("support");
        if (const auto cells = c.get<uint32_t>("hits")) {
            auto h = std::make_shared<GatherHits>();
            h->m = c.get<int>("grid"), h->n = c.get<int>("grid");
            h->t.resize(cells), h->u.resize(cells), h->v.resize(cells), h->object.resize(cells), h->prim.resize(cells);
            for (uint32_t k = 0; k < cells; ++k)
                h->t[k] = c.get<float>("t"), h->u[k] = c.get<float>("u"), h->v[k] = c.get<float>("v"),
                h->object[k] = c.get<uint32_t>("object"), h->prim[k] = c.get<uint32_t>("prim");
            r.hits = std::move(h);
        }
        out.push_back(std::move(r));
    }
    return out;
}

nlohmann::json record_layout() {
    nlohmann::json l = nlohmann::json::array();
    for (const auto& f : kFields) l.push_back({{"name", f.name}, {"type", f.type}, {"count", f.count}});
    return l;
}

std::string serialize_cache_file(const CacheFile& file) {
    nlohmann::json h;
    h["format"] = "bounce irradiance cache";
    h["record_layout"] = record_layout();
    h["record_bytes"] = kRecordBytes;
    h["record_count"] = file.records.size();
    // Only when there are any: a cache without them is byte for byte what earlier versions wrote.
    if (!file.fragment_records.empty()) h["fragment_record_count"] = file.fragment_records.size();
    h["block_records"] = kBlockRecords;
    h["scene_fingerprint"] = fmt::format("{:016x}", file.info.scene_fingerprint);
    h["camera_fingerprint"] = fmt::format("{:016x}", file.info.camera_fingerprint);
    h["geometry_fingerprint"] = fmt::format("{:016x}", file.info.geometry_fingerprint);
    h["unscaled_fingerprint"] = fmt::format("{:016x}", file.info.unscaled_fingerprint);
    const size_t lights = parts_lights(file);
    if (lights > 0) h["light_parts"] = lights;
    h["parameters"] = file.info.parameters;
    h["luminance_floor"] = file.info.luminance_floor;
    h["frame"] = file.info.frame;
    h["software"] = bounce_software();
    std::string header = h.dump();
    std::string out(kMagic, 8);
    put(out, kCacheFileVersion);
    put(out, static_cast<uint32_t>(header.size()));
    out += header;
    put(out, fnv1a(header.data(), header.size()));
    const size_t total = file.records.size() + file.fragment_records.size();
    auto at = [&](size_t i) -> const Record& {
        return i < file.records.size() ? file.records[i] : file.fragment_records[i - file.records.size()];
    };
    for (size_t b = 0; b < total; b += kBlockRecords) {
        auto n = static_cast<uint32_t>(std::min<size_t>(kBlockRecords, total - b));
        std::string payload;
        payload.reserve(n * kRecordBytes);
        for (uint32_t i = 0; i < n; ++i) write_record(payload, at(b + i));
        put(out, n);
        put(out, fnv1a(payload.data(), payload.size()));
        out += payload;
    }
    // Version 5: the records' bounce light per light (scales factored out), in blocks of the
    // same records, so a loaded cache takes a light's new colour or intensity exactly.
    for (size_t b = 0; lights > 0 && b < total; b += kBlockRecords) {
        auto n = static_cast<uint32_t>(std::min<size_t>(kBlockRecords, total - b));
        std::string payload;
        payload.reserve(n * (lights + 1) * kPartFloats * 4);
        for (uint32_t i = 0; i < n; ++i) {
            const LightParts& parts = *at(b + i).parts;
            write_part(payload, parts.signal);
            for (const LightPart& p : parts.light) write_part(payload, p);
        }
        put(out, n);
        put(out, fnv1a(payload.data(), payload.size()));
        out += payload;
    }
    return out;
}

void write_cache_file(const std::string& path, const CacheFile& file) {
    std::string bytes = serialize_cache_file(file);
    write_atomically(path, [&](const std::string& tmp) {
        std::ofstream out(tmp, std::ios::binary);
        out.write(bytes.data(), static_cast<std::streamsize>(bytes.size()));
        out.flush();
        if (!out) throw InputError(path, "", "cannot write cache file");
    });
}

namespace {

/// The light-parts section: one block per block of records, each record's signal then its
/// `lights` parts (bounded by the bytes present before anything is allocated).
void read_parts(Cursor& c, const std::string& name, size_t lights, std::vector<Record>& records) {
    const size_t record_bytes = (lights + 1) * kPartFloats * 4;
    if (records.size() > c.remaining() / record_bytes)
        c.fail(
            fmt::format("{} records' parts for {} lights cannot fit in the {} bytes that follow", records.size(), lights, c.remaining()));
    for (size_t done = 0; done < records.size();) {
        const size_t block_at = c.pos();
        const auto n = c.get<uint32_t>("parts block size");
        if (n == 0 || n > kBlockRecords || n > records.size() - done)
            throw InputError(name, fmt::format("byte {}", block_at), fmt::format("bad light-parts block size {}", n));
        const auto sum = c.get<uint64_t>("parts block checksum");
        const std::string payload = c.bytes(n * record_bytes, "light parts");
        if (sum != fnv1a(payload.data(), payload.size()))
            throw InputError(name, fmt::format("light-parts block at byte {}", block_at), "checksum mismatch (file is corrupt)");
        Cursor pc(payload, name);
        for (uint32_t i = 0; i < n; ++i, ++done) {
            auto parts = std::make_shared<LightParts>();
            parts->signal = read_part(pc);
            parts->light.resize(lights);
            for (LightPart& p : parts->light) p = read_part(pc);
            if (!part_in_range(parts->signal) || !std::all_of(parts->light.begin(), parts->light.end(), part_in_range))
                throw InputError(name, fmt::format("record {}'s light parts", done), "non-finite or beyond 1e20");
            records[done].parts = std::move(parts);
        }
    }
}

/// `count` records in checksummed blocks from `c` into `out`, each checked.
void read_record_blocks(Cursor& c, const std::string& name, uint64_t count, std::vector<Record>& out) {
    out.reserve(count);
    while (out.size() < count) {
        size_t block_at = c.pos();
        auto n = c.get<uint32_t>("block size");
        if (n == 0 || n > kBlockRecords || n > count - out.size())
            throw InputError(name, fmt::format("byte {}", block_at), fmt::format("bad block size {}", n));
        auto sum = c.get<uint64_t>("block checksum");
        std::string payload = c.bytes(static_cast<size_t>(n) * kRecordBytes, "records");
        if (sum != fnv1a(payload.data(), payload.size()))
            throw InputError(name, fmt::format("block at byte {}", block_at), "checksum mismatch (file is corrupt)");
        Cursor rc(payload, name);
        for (uint32_t i = 0; i < n; ++i) {
            Record r = read_record(rc);
            if (const char* why = record_problem(r)) throw InputError(name, fmt::format("record {}", out.size()), why);
            out.push_back(r);
        }
    }
}

}  // namespace

CacheFile parse_cache_file(const std::string& bytes, const std::string& name) {
    Cursor c(bytes, name);
    if (bytes.empty()) c.fail("empty file (not an irradiance cache)");
    std::string magic = c.bytes(std::min<size_t>(8, bytes.size()), "magic");
    if (magic.size() < 8 || std::memcmp(magic.data(), kMagic, 8) != 0)
        throw InputError(name, "byte 0", "not a bounce irradiance cache (bad magic)");
    auto version = c.get<uint32_t>("version");
    // Version 4 is version 5 without light parts: still read.
    if (version != kCacheFileVersion && version != 4)
        throw InputError(name, "byte 8",
                         fmt::format("unsupported cache version {} (this bounce reads versions 4 and {})", version, kCacheFileVersion));
    auto hlen = c.get<uint32_t>("header length");
    if (hlen > kMaxHeader || hlen > c.remaining()) c.fail(fmt::format("header length {} is impossible for this file", hlen));
    std::string header = c.bytes(hlen, "header");
    auto hsum = c.get<uint64_t>("header checksum");
    if (hsum != fnv1a(header.data(), header.size())) throw InputError(name, "header", "checksum mismatch (file is corrupt)");
    check_json_nesting(header, name);
    nlohmann::json h = nlohmann::json::parse(header, nullptr, false);
    if (h.is_discarded() || !h.is_object()) throw InputError(name, "header", "header is not valid JSON");
    CacheFile f;
    try {
        if (h.at("record_layout") != record_layout() || h.at("record_bytes").get<uint64_t>() != kRecordBytes)
            throw InputError(name, "header/record_layout", "record layout differs from this version's");
        // Counts are whole numbers >= 0 (nlohmann would read -1 as 2^64 - 1).
        const auto count_of = [&](const char* key, bool required) -> uint64_t {
            if (!h.contains(key)) {
                if (required) throw InputError(name, std::string("header/") + key, "missing");
                return 0;  // fragment_record_count: absent in files written before fragment records
            }
            if (!h[key].is_number_unsigned())
                throw InputError(name, std::string("header/") + key, fmt::format("{} is not a record count", h[key].dump()));
            return h[key].get<uint64_t>();
        };
        const uint64_t shared = count_of("record_count", true);
        const uint64_t own = count_of("fragment_record_count", false);
        // Every record needs kRecordBytes plus its share of block headers: bound the count by
        // the bytes actually present before allocating anything.
        const uint64_t room = c.remaining() / kRecordBytes;
        if (shared > room || own > room - shared)
            throw InputError(name, shared > room ? "header/record_count" : "header/fragment_record_count",
                             fmt::format("{} + {} records cannot fit in the {} bytes that follow", shared, own, c.remaining()));
        const uint64_t count = shared + own;
        f.info.scene_fingerprint = std::stoull(h.at("scene_fingerprint").get<std::string>(), nullptr, 16);
        f.info.camera_fingerprint = std::stoull(h.at("camera_fingerprint").get<std::string>(), nullptr, 16);
        if (h.contains("geometry_fingerprint"))  // absent in files of earlier builds
            f.info.geometry_fingerprint = std::stoull(h.at("geometry_fingerprint").get<std::string>(), nullptr, 16);
        if (h.contains("unscaled_fingerprint"))  // version 5
            f.info.unscaled_fingerprint = std::stoull(h.at("unscaled_fingerprint").get<std::string>(), nullptr, 16);
        const uint64_t lights = count_of("light_parts", false);
        if (lights > kMaxPartLights || (lights > 0 && version < 5))
            throw InputError(
                name, "header/light_parts",
                fmt::format("{} lights' parts cannot be in a version {} file of at most {} lights", lights, version, kMaxPartLights));
        f.info.parameters = h.at("parameters");
        f.info.luminance_floor = h.at("luminance_floor").get<float>();
        // A frame number is an integer within the shots' bound (1e39 was read as -2147483648).
        const nlohmann::json& frame = h.at("frame");
        if (!frame.is_number_integer() || std::abs(frame.get<double>()) > kMaxFrame)
            throw InputError(name, "header/frame", fmt::format("{} is not a whole frame number within +-{}", frame.dump(), kMaxFrame));
        f.info.frame = frame.get<int>();
        read_record_blocks(c, name, count, f.records);
        if (lights > 0) read_parts(c, name, static_cast<size_t>(lights), f.records);
        if (c.remaining() != 0) c.fail(fmt::format("{} unexpected bytes after the last block", c.remaining()));
        f.fragment_records.assign(f.records.begin() + static_cast<std::ptrdiff_t>(shared), f.records.end());
        f.records.resize(shared);
    } catch (const nlohmann::json::exception& e) {
        throw InputError(name, "header", std::string("missing or malformed field: ") + e.what());
    } catch (const std::invalid_argument&) {
        throw InputError(name, "header", "malformed fingerprint");
    } catch (const std::out_of_range&) {
        throw InputError(name, "header", "malformed fingerprint");
    }
    return f;
}

CacheFile read_cache_file(const std::string& path) {
    check_input_file(path);
    std::ifstream in(path, std::ios::binary);
    if (!in) throw InputError(path, "", "cannot open cache file");
    std::string bytes((std::istreambuf_iterator<char>(in)), {});
    return parse_cache_file(bytes, path);
}

std::string expand_frame_pattern(const std::string& pattern, int frame) {
    auto start = pattern.find('#');
    if (start == std::string::npos) return pattern;
    auto end = pattern.find_first_not_of('#', start);
    size_t width = (end == std::string::npos ? pattern.size() : end) - start;
    return pattern.substr(0, start) + fmt::format("{:0{}}", frame, width) + (end == std::string::npos ? "" : pattern.substr(end));
}

}  // namespace bounce
