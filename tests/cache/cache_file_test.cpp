// Cache files and the cache tools: bit-exact round trips, duplicate-free and commutative
// merges, exact box filters, reuse without new records, sequences, and every kind of bad file.
#include <fmt/format.h>

#include <regex>
#include <gtest/gtest.h>

#include <cstring>
#include <set>

#include "bounce/cache/cache_file.h"
#include "bounce/cache/cache_tools.h"
#include "bounce/core/error.h"
#include "bounce/render/render.h"
#include "test_util.h"

namespace bounce {
namespace {

Record random_record(uint64_t i) {
    RandomStream rng(11, i);
    auto f = [&](uint32_t d) { return rng.get(0, d) * 2 - 1; };
    Record r;
    r.p = {f(0) * 5, f(1) * 5, f(2) * 5};
    r.n = normalize(Vec3(f(3), f(4) + 2, f(5)));
    r.E = {rng.get(0, 6), rng.get(0, 7), rng.get(0, 8)};
    r.ao = rng.get(0, 9);
    r.bent = normalize(Vec3(f(10), 1, f(11)));
    for (uint32_t c = 0; c < 3; ++c) {
        r.dir[c] = {f(12 + c), f(15 + c), f(18 + c)};
        r.grad_r[c] = {f(21 + c), f(24 + c), f(27 + c)};
        r.grad_t[c] = {f(30 + c), f(33 + c), f(36 + c)};
    }
    r.ao_grad_r = {f(40), f(41), f(42)};
    r.ao_grad_t = {f(43), f(44), f(45)};
    r.footprint = 0.01f + rng.get(0, 46) * 0.01f;
    r.radius = r.footprint * (2 + 20 * rng.get(0, 47));
    r.raw_radius = i % 3 ? r.radius : INFINITY;
    r.harmonic = 1 + rng.get(0, 48);
    r.dmin = i % 2 ? INFINITY : 0.5f;
    r.weber = i % 4 ? INFINITY : 0.3f;
    r.key = (i * 7919) << 8;
    r.rays = 512;
    r.frame = static_cast<int32_t>(i % 3);
    r.noise = rng.get(0, 49) * 0.3f;
    return r;
}

CacheFile random_cache(size_t n, uint64_t salt = 0) {
    CacheFile f;
    f.info.scene_fingerprint = 0x1234;
    f.info.camera_fingerprint = 0x5678;
    f.info.parameters = {{"metric", "tl04"}, {"min_weight", 0.5}};
    f.info.luminance_floor = 1e-3f;
    for (size_t i = 0; i < n; ++i) f.records.push_back(random_record(i + salt));
    return f;
}

/// `file` (serialised, no records after the header) with `from` replaced by `to` in its header
/// and the header checksum made valid again, so only that edit is wrong.
std::string with_header_edit(const std::string& file, const std::string& from, const std::string& to) {
    uint32_t old_len;
    std::memcpy(&old_len, file.data() + 12, 4);
    std::string header = file.substr(16, old_len);
    const auto at = header.find(from);
    if (at == std::string::npos) throw std::logic_error("no " + from + " in the header");
    header.replace(at, from.size(), to);
    std::string out = file.substr(0, 12);
    const auto len = static_cast<uint32_t>(header.size());
    out.append(reinterpret_cast<const char*>(&len), 4);
    out += header;
    uint64_t h = 0xcbf29ce484222325ULL;  // FNV-1a 64, as the format says
    for (unsigned char ch : header) h = (h ^ ch) * 0x100000001b3ULL;
    out.append(reinterpret_cast<const char*>(&h), 8);
    return out + file.substr(16 + old_len + 8);  // the blocks, unchanged
}

bool same_bits(const Record& a, const Record& b) {
    CacheFile x, y;
    x.records = {a};
    y.records = {b};
    return serialize_cache_file(x) == serialize_cache_file(y);
}

TEST(CacheFile, ARecordWithoutDirectionBinsKeepsNoneAndItsFileHoldsZeros) {
    // Bins are kept only where one is not 0 (memory: 384 bytes a record otherwise).
    CacheFile f = random_cache(3);
    f.records[0].set_bins({});
    std::array<Color, kReachBins> some{};
    some[5] = Color(0.25f, 0.5f, 1.0f);
    f.records[1].set_bins(some);
    EXPECT_FALSE(f.records[0].bins);
    ASSERT_TRUE(f.records[1].bins);
    const std::string bytes = serialize_cache_file(f);
    const CacheFile back = parse_cache_file(bytes, "mem");
    EXPECT_FALSE(back.records[0].bins);
    ASSERT_TRUE(back.records[1].bins);
    EXPECT_TRUE((*back.records[1].bins)[5] == some[5]);
    EXPECT_TRUE(back.records[1].bin_values()[4] == Color(0));
    EXPECT_TRUE(back.records[0].bin_values()[5] == Color(0));
    EXPECT_EQ(serialize_cache_file(back), bytes);
}

TEST(CacheFile, RoundTripIsBitExactForEveryField) {
    CacheFile f = random_cache(5000);  // more than one block
    CacheFile back = parse_cache_file(serialize_cache_file(f), "mem");
    ASSERT_EQ(back.records.size(), f.records.size());
    EXPECT_EQ(back.info.scene_fingerprint, 0x1234u);
    EXPECT_EQ(back.info.camera_fingerprint, 0x5678u);
    EXPECT_EQ(back.info.parameters, f.info.parameters);
    for (size_t i = 0; i < f.records.size(); ++i) {
        const Record &a = f.records[i], &b = back.records[i];
        ASSERT_EQ(std::memcmp(&a.p, &b.p, sizeof(Vec3)), 0);
        ASSERT_TRUE(a.E == b.E && a.n == b.n && a.bent == b.bent && a.ao == b.ao);
        ASSERT_TRUE(a.dir == b.dir && a.grad_r == b.grad_r && a.grad_t == b.grad_t);
        ASSERT_TRUE(a.ao_grad_r == b.ao_grad_r && a.ao_grad_t == b.ao_grad_t);
        ASSERT_TRUE(a.radius == b.radius && a.footprint == b.footprint && a.harmonic == b.harmonic);
        ASSERT_EQ(std::isinf(a.raw_radius), std::isinf(b.raw_radius));
        ASSERT_EQ(std::isinf(a.dmin), std::isinf(b.dmin));
        ASSERT_TRUE(a.key == b.key && a.rays == b.rays && a.frame == b.frame && a.noise == b.noise);
        ASSERT_TRUE(same_bits(a, b));
    }
}

TEST(CacheTools, MergeWithItselfAddsNothing) {
    CacheFile a = random_cache(300);
    for (uint64_t i = 0; i < 40; ++i) a.fragment_records.push_back(random_record(5000 + i));
    CacheFile m = merge_caches(a, a, "a", "a", false);
    EXPECT_EQ(m.records.size(), a.records.size());
    EXPECT_EQ(m.fragment_records.size(), 40u);
}

TEST(CacheTools, MergeKeepsOneFragmentRecordPerKeyWhateverTheOrder) {
    CacheFile a = random_cache(0), b = random_cache(0);
    for (uint64_t i = 0; i < 30; ++i) a.fragment_records.push_back(random_record(7000 + i));
    for (uint64_t i = 20; i < 50; ++i) b.fragment_records.push_back(random_record(7000 + i));
    b.fragment_records[0].E = Color(0.25f);  // the same fragment (key), gathered again: another value
    CacheFile ab = merge_caches(a, b, "a", "b", false), ba = merge_caches(b, a, "b", "a", false);
    ASSERT_EQ(ab.fragment_records.size(), 50u);
    EXPECT_EQ(serialize_cache_file(ab), serialize_cache_file(ba));
    RecordFilter inside;
    inside.where = {WhereTerm::parse("frame==1")};
    for (const Record& r : filter_cache(ab, inside, false).fragment_records) EXPECT_EQ(r.frame, 1);
    EXPECT_EQ(filter_cache(ab, inside, false).fragment_records.size() + filter_cache(ab, inside, true).fragment_records.size(), 50u);
}

TEST(CacheTools, MergeIsCommutativeInContent) {
    CacheFile a = random_cache(300, 0), b = random_cache(300, 150);  // half overlapping
    auto content = [](const CacheFile& f) {
        std::multiset<std::string> s;
        for (const auto& r : f.records) {
            CacheFile one;
            one.records = {r};
            s.insert(serialize_cache_file(one));
        }
        return s;
    };
    CacheFile ab = merge_caches(a, b, "a", "b", false), ba = merge_caches(b, a, "b", "a", false);
    EXPECT_EQ(content(ab), content(ba));
    EXPECT_LT(ab.records.size(), a.records.size() + b.records.size());  // the shared half is not doubled
    EXPECT_GE(ab.records.size(), 450u);
    CacheFile other = a;
    other.info.camera_fingerprint = 1;
    EXPECT_THROW(merge_caches(a, other, "a", "other", false), InputError);
}

TEST(CacheTools, BoxFilterKeepsExactlyTheRecordsInside) {
    CacheFile a = random_cache(1000);
    RecordFilter f;
    f.has_box = true;
    f.box_lo = {-1, -2, -3};
    f.box_hi = {2, 1, 0.5f};
    size_t inside = 0;
    for (const auto& r : a.records) inside += r.p.x >= -1 && r.p.x <= 2 && r.p.y >= -2 && r.p.y <= 1 && r.p.z >= -3 && r.p.z <= 0.5f;
    CacheFile kept = filter_cache(a, f, false), removed = filter_cache(a, f, true);
    EXPECT_EQ(kept.records.size(), inside);
    EXPECT_EQ(removed.records.size(), a.records.size() - inside);
    for (const auto& r : kept.records) EXPECT_TRUE(f.matches(r));
    RecordFilter w;
    w.where = {WhereTerm::parse("frame==1"), WhereTerm::parse("E.g>0.5")};
    for (const auto& r : filter_cache(a, w, false).records) EXPECT_TRUE(r.frame == 1 && r.E.y > 0.5f);
    EXPECT_THROW(WhereTerm::parse("colour<3"), InputError);
}

TEST(CacheTools, EveryWhereOperatorAndFieldReadsTheRecord) {
    Record r;
    r.p = {1, 2, 3}, r.n = {0, 0.6f, 0.8f}, r.E = Color(0.25f, 0.5f, 1.0f), r.ao = 0.75f;
    r.radius = 4, r.footprint = 0.5f, r.rays = 256, r.frame = 7;
    const std::pair<const char*, bool> cases[] = {{"p.x==1", true},    {"p.y<2", false},    {"p.z<=3", true},    {"n.x!=0", false},
                                                  {"n.y>0.5", true},   {"n.z>=0.8", true},  {"E.r==0.25", true}, {"E.g<0.5", false},
                                                  {"E.b>=1", true},    {"ao>0.8", false},   {"radius==4", true}, {"pixels==8", true},
                                                  {"rays>=256", true}, {"frame!=7", false}, {"frame > 6", true}};
    for (const auto& [term, holds] : cases) EXPECT_EQ(WhereTerm::parse(term).holds(r), holds) << term;
    EXPECT_NEAR(luminance(r.E), 0.25 * 0.2126 + 0.5 * 0.7152 + 0.0722, 1e-6);
    EXPECT_TRUE(WhereTerm::parse("E.y>0.48").holds(r));
    EXPECT_FALSE(WhereTerm::parse("E.y>0.49").holds(r));
    for (const char* bad : {"radius<", "radius~1", "radius<1e999", "<1", "E.q>1"}) EXPECT_THROW(WhereTerm::parse(bad), InputError) << bad;
}

TEST(CacheTools, PlyExportHasOnePointPerRecord) {
    test::TempDir d;
    CacheFile a = random_cache(10);
    export_ply(a, d.file("c.ply"));
    std::ifstream in(d.file("c.ply"), std::ios::binary);
    std::string s((std::istreambuf_iterator<char>(in)), {});
    auto end = s.find("end_header\n");
    ASSERT_NE(end, std::string::npos);
    EXPECT_NE(s.find("element vertex 10\n"), std::string::npos);
    EXPECT_EQ(s.size() - (end + 11), 10u * (11 * 4 + 3));  // 11 floats + 3 colour bytes each
}

TEST(CacheFile, FragmentRecordsRoundTripAfterTheSharedOnes) {
    CacheFile f = random_cache(3000);
    for (uint64_t i = 0; i < 2000; ++i) f.fragment_records.push_back(random_record(10000 + i));  // blocks mix both
    const std::string bytes = serialize_cache_file(f);
    CacheFile back = parse_cache_file(bytes, "mem");
    ASSERT_EQ(back.records.size(), 3000u);
    ASSERT_EQ(back.fragment_records.size(), 2000u);
    for (size_t i = 0; i < 3000; ++i) ASSERT_TRUE(same_bits(f.records[i], back.records[i])) << i;
    for (size_t i = 0; i < 2000; ++i) ASSERT_TRUE(same_bits(f.fragment_records[i], back.fragment_records[i])) << i;
    // Moving the split between the two kinds is caught as a count the bytes cannot hold or leave over.
    EXPECT_THROW(parse_cache_file(with_header_edit(bytes, "\"fragment_record_count\":2000", "\"fragment_record_count\":2001"), "m"),
                 InputError);
    EXPECT_THROW(parse_cache_file(with_header_edit(bytes, "\"fragment_record_count\":2000", "\"fragment_record_count\":-1"), "m"),
                 InputError);
    // A cache without fragment records is written as before they existed (no such key).
    const std::string old = serialize_cache_file(random_cache(7));
    EXPECT_EQ(old.find("fragment_record_count"), std::string::npos);
    CacheFile o = parse_cache_file(old, "old.bic");
    EXPECT_EQ(o.records.size(), 7u);
    EXPECT_TRUE(o.fragment_records.empty());
}

TEST(CacheFile, BadFilesAreRefusedCleanly) {
    const std::string good = serialize_cache_file(random_cache(20));
    auto refused = [](const std::string& bytes, const std::string& expect) {
        try {
            parse_cache_file(bytes, "bad.bic");
            ADD_FAILURE() << "accepted: " << expect;
        } catch (const InputError& e) {
            EXPECT_NE(std::string(e.what()).find(expect), std::string::npos) << e.what();
        }
    };
    refused("", "empty");
    refused("not a cache at all", "bad magic");
    std::string v9 = good;
    v9[8] = 9;
    refused(v9, "unsupported cache version 9");
    // A version 3 file (records without direction bins) is refused by name, as version 3's
    // reader refuses this version's (it checks the same version word).
    std::string v3 = good;
    v3[8] = 3;
    refused(v3, "unsupported cache version 3 (this bounce reads versions 4 and 5)");
    // Every truncation is an error, never a crash.
    for (size_t n = 1; n < good.size(); n += 7) EXPECT_THROW(parse_cache_file(good.substr(0, n), "t.bic"), InputError) << n;
    // Every single flipped bit after the magic and version is caught (checksums, bounds).
    int caught = 0, tried = 0;
    for (size_t i = 12; i < good.size(); i += 5) {
        std::string bad = good;
        bad[i] = static_cast<char>(bad[i] ^ (1 << (i % 8)));
        ++tried;
        try {
            parse_cache_file(bad, "flip.bic");
        } catch (const InputError&) {
            ++caught;
        }
    }
    EXPECT_EQ(caught, tried);
    // A header promising 10^15 records is refused before anything is allocated.
    CacheFile empty = random_cache(0);
    std::string huge = serialize_cache_file(empty);
    auto pos = huge.find("\"record_count\":0");
    ASSERT_NE(pos, std::string::npos);
    refused(with_header_edit(huge, "\"record_count\":0", "\"record_count\":1000000000000000"), "cannot fit");
}

/// Renders and, like a front end, writes the cache after the image.
RenderResult render_with(const std::vector<std::string>& extra, RenderRequest req, Stats& stats, const std::string& cache_out = "") {
    std::vector<Override> o = {"camera.resolution=[40,40]", "render.spp=1", "render.gi=\"cache\"", "render.rays=64"};
    o.insert(o.end(), extra.begin(), extra.end());
    RenderResult r = render(load_scene(test::cornell_scene(), o), req, stats, nullptr);
    if (!cache_out.empty()) write_cache_file(cache_out, r.cache->to_file(r.cache_info));
    return r;
}

TEST(CacheReuse, OwnCacheCreatesNoRecordsAndTheSameImage) {
    test::TempDir d;
    RenderRequest first;
    Stats s1, s2, s3;
    RenderResult a = render_with({}, first, s1, d.file("c.bic"));
    RenderRequest again;
    again.cache_in = d.file("c.bic");
    RenderResult b = render_with({}, again, s2);
    EXPECT_GT(a.records_new, 20u);
    EXPECT_EQ(b.records_new, 0u);
    EXPECT_EQ(b.records_loaded, a.records_new);
    EXPECT_EQ(s2.total().gather_rays, 0u);
    EXPECT_TRUE(a.image.find("indirect")->data == b.image.find("indirect")->data);
    // --regather flushes: everything is gathered again.
    again.kind = FrameKind::Regather;
    RenderResult c = render_with({}, again, s3);
    EXPECT_EQ(c.records_new, a.records_new);
}

TEST(CacheReuse, CacheForOtherObjectsOrCameraIsRefusedUnlessForced) {
    test::TempDir d;
    RenderRequest first;
    Stats s;
    render_with({}, first, s, d.file("c.bic"));
    RenderRequest reuse;
    reuse.cache_in = d.file("c.bic");
    EXPECT_THROW(render_with({"camera.fov=50"}, reuse, s), InputError);
    EXPECT_THROW(render_with({"objects.0.material=\"red\""}, reuse, s), InputError);
    // A light or material edit keeps the records (the lighter's loop), saying their bounce
    // light is the old lights'.
    EXPECT_TRUE(render_with({"materials.light.emission=[1,1,1]"}, reuse, s).cache_other_lighting);
    EXPECT_FALSE(render_with({}, reuse, s).cache_other_lighting);
    reuse.force = true;
    EXPECT_NO_THROW(render_with({"camera.fov=50"}, reuse, s));
}

TEST(CacheCli, SequencesReuseThePreviousFrameAndInfoPlaysThem) {
    test::TempDir d;
    std::string common = " --res 32x32 --spp 1 --gi cache --rays 32 -q";
    ASSERT_EQ(test::run_bounce("render " + test::cornell_scene() + " -o " + d.file("f.####.exr") + " --cache-out " + d.file("c.####.bic") +
                               " --frames 1-3" + common),
              0);
    std::string cmd = std::string(BOUNCE_BINARY) + " cache info '" + d.file("c.####.bic") + "' --json > " + d.file("seq.json");
    ASSERT_EQ(std::system(cmd.c_str()), 0);
    std::ifstream in(d.file("seq.json"));
    auto j = nlohmann::json::parse(in);
    ASSERT_EQ(j.size(), 3u);
    EXPECT_GT(j[0]["new"].get<int>(), 0);
    EXPECT_EQ(j[1]["new"].get<int>(), 0);
    EXPECT_EQ(j[2]["reused"], j[0]["records"]);
    // Tools through the CLI, and bad files exit 2.
    EXPECT_EQ(test::run_bounce("cache merge " + d.file("c.0001.bic") + " " + d.file("c.0002.bic") + " -o " + d.file("m.bic")), 0);
    EXPECT_EQ(read_cache_file(d.file("m.bic")).records.size(), read_cache_file(d.file("c.0001.bic")).records.size());
    EXPECT_EQ(test::run_bounce("cache filter " + d.file("m.bic") + " -o " + d.file("f.bic") + " --box 0,0,0,300,300,300"), 0);
    EXPECT_EQ(test::run_bounce("cache export " + d.file("m.bic") + " -o " + d.file("m.ply")), 0);
    std::string err;
    d.write("junk.bic", "BOUNCEIC junk");
    EXPECT_EQ(test::run_bounce("cache info " + d.file("junk.bic"), &err), 2);
    EXPECT_NE(err.find("junk.bic"), std::string::npos);
    EXPECT_EQ(test::run_bounce("cache filter " + d.file("m.bic") + " -o " + d.file("g.bic") + " --where 'colour<1'"), 2);
    EXPECT_EQ(test::run_bounce("render " + test::cornell_scene() + " -o " + d.file("x.exr") + " --show records" + common + " --cache-in " +
                               d.file("junk.bic")),
              2);
}

}  // namespace
}  // namespace bounce

namespace bounce {
namespace {

std::pair<std::string, std::string> image_and_cache_bytes(const std::vector<std::string>& settings, const std::string& file, Stats& s) {
    RenderRequest req;
    RenderResult r = render_with(settings, req, s, file);
    std::ifstream in(file, std::ios::binary);
    std::string bytes((std::istreambuf_iterator<char>(in)), {});
    const auto& ind = r.image.find("indirect")->data;
    return {std::string(reinterpret_cast<const char*>(ind.data()), ind.size() * sizeof(float)), bytes};
}

// Shared mode: tile size and order are scheduling only. Per-thread mode: a tile's private
// cache depends on the tile, so the tile size is fixed, but threads and order are not.
TEST(CacheDeterminism, ImageAndCacheBytesDoNotDependOnThreadCountInEitherMode) {
    test::TempDir d;
    for (std::string mode : {"shared", "per-thread"}) {
        std::pair<std::string, std::string> first;
        for (int threads : {1, 2, 8}) {
            std::vector<std::string> o = {"render.threads=" + std::to_string(threads), "render.cache_sharing=\"" + mode + "\"",
                                          "render.tile_order=\"" + std::string(threads == 2 ? "spiral" : "rows") + "\""};
            o.push_back("render.tile_size=" + std::to_string(mode == "shared" ? 4 + threads : 8));
            Stats s;
            auto got = image_and_cache_bytes(o, d.file(mode + std::to_string(threads) + ".bic"), s);
            if (threads == 1) {
                first = got;
                ASSERT_GT(got.second.size(), 1000u);
                continue;
            }
            EXPECT_EQ(got.first, first.first) << mode << ", " << threads << " threads";
            EXPECT_EQ(got.second, first.second) << mode << ", " << threads << " threads";
        }
    }
}

TEST(CacheSharing, PerThreadMergesNeverDuplicateARecordAndNeverMiss) {
    test::TempDir d;
    Stats shared, per_thread;
    image_and_cache_bytes({"render.threads=2", "render.tile_size=8"}, d.file("s.bic"), shared);
    image_and_cache_bytes({"render.threads=2", "render.tile_size=8", "render.cache_sharing=\"per-thread\""}, d.file("p.bic"), per_thread);
    CacheFile f = read_cache_file(d.file("p.bic"));
    std::set<uint64_t> keys;
    for (const Record& r : f.records) EXPECT_TRUE(keys.insert(r.key).second) << "record " << r.key << " merged twice";
    // Every gather of a per-thread render becomes a record (none is dropped); the shared
    // cache drops the candidates its own sub-pass covered.
    auto value = [](const Stats& s, const char* k) { return s.extra()[k].get<double>(); };
    EXPECT_EQ(value(per_thread, "records"), value(per_thread, "record_gathers"));
    EXPECT_EQ(value(per_thread, "records_dropped"), 0.0);
    EXPECT_EQ(value(shared, "records") + value(shared, "records_dropped"), value(shared, "record_gathers"));
    EXPECT_EQ(value(per_thread, "shading_misses"), 0.0);
    EXPECT_EQ(static_cast<double>(f.records.size()), value(per_thread, "records"));
}

}  // namespace
}  // namespace bounce

namespace bounce {
namespace {

/// docs/cache-format.md's record table is the layout files declare, row for row, and its
/// record_bytes the sum (the docs once said 224 bytes and left fields out).
TEST(CacheFile, TheDocumentedLayoutIsTheWrittenOne) {
    const std::string doc = test::bytes_of(test::source_dir() + "/docs/cache-format.md");
    const std::regex row("\\n\\| (\\w+) \\| (f32|u32|i32|u64) × (\\d+) \\|");
    nlohmann::json documented = nlohmann::json::array();
    const size_t from = doc.find("## Record layout");
    ASSERT_NE(from, std::string::npos);
    const std::string table = doc.substr(from, doc.find("## Validation") - from);
    size_t bytes = 0;
    for (auto it = std::sregex_iterator(table.begin(), table.end(), row); it != std::sregex_iterator(); ++it) {
        const int count = std::stoi((*it)[3]);
        documented.push_back({{"name", (*it)[1]}, {"type", (*it)[2]}, {"count", count}});
        bytes += static_cast<size_t>(count) * ((*it)[2] == "u64" ? 8 : 4);
    }
    EXPECT_EQ(documented, record_layout());
    EXPECT_NE(doc.find(fmt::format("bytes per record ({} in version", bytes)), std::string::npos) << bytes;
}

}  // namespace
}  // namespace bounce
