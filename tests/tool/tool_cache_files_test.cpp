// Issue 65: a cache file brought into the lighting tool (Load cache, --cache-in) is checked
// against the session's scene as the CLI checks it, and keeps its records' light parts, so a
// saved cache relights exactly and one gathered under other lighting says it is stale.
#include <cmath>
#include <cstring>
#include <filesystem>
#include <limits>

#include "bounce/cache/cache_file.h"
#include "bounce/core/error.h"
#include "tool_util.h"

namespace bounce {
namespace {

using nlohmann::json;
using test::render_and_wait;

/// The small Cornell box with a spot through its open front (a light with a colour and an
/// intensity; the ceiling panel is a material's emission). The spot is lights.1.
SessionOptions with_spot(const test::TempDir& d) {
    SessionOptions o = test::small_session(d);
    o.sets.push_back(R"(lights=[{"type":"spot","position":[278,300,-500],"direction":[0,-0.2,1],"cone_angle":30,"color":2e5}])");
    return o;
}

std::string spot_key(const LightingSession& s) {
    for (const json& row : s.params())
        if (row["key"] == "lights.1.cone_angle") return "lights.1.";
    return "lights.0.";
}

TEST(LightingToolCacheFiles, ASavedCacheKeepsItsLightPartsAndRelightsExactly) {
    test::TempDir d;
    const SessionOptions options = with_spot(d);
    LightingSession first(options);
    render_and_wait(first, SessionAction::Rasterize);
    const std::string key = spot_key(first);
    std::filesystem::copy_file(first.deep_path(), d.file("y.deep.exr"));
    std::filesystem::copy_file(first.cache_path(), d.file("y.bic"));
    // The file holds every record's part per light (version 5).
    const CacheFile file = read_cache_file(d.file("y.bic"));
    ASSERT_FALSE(file.records.empty());
    for (const Record& r : file.records) {
        ASSERT_TRUE(r.parts);
        EXPECT_EQ(r.parts->light.size(), 2u);
    }
    // The session that gathered it takes a colour and intensity edit on a re-shade.
    first.edit(key + "intensity", 0.4);
    first.edit(key + "color", json{1.0, 0.5, 0.2});
    render_and_wait(first, SessionAction::Reshade);
    ASSERT_EQ(first.status()["bounce_stale"], false);
    // A session started from the files takes the same edits exactly: the same image, not stale.
    SessionOptions o = options;
    o.out_dir = d.file("out2");
    o.deep_in = d.file("y.deep.exr");
    o.cache_in = d.file("y.bic");
    LightingSession second(o);
    EXPECT_EQ(second.status()["bounce_stale"], false);
    EXPECT_EQ(second.edit(key + "intensity", 0.4)["needs"], "reshade");
    second.edit(key + "color", json{1.0, 0.5, 0.2});
    EXPECT_EQ(second.status()["bounce_stale"], false);
    render_and_wait(second, second.pending());
    EXPECT_EQ(second.status()["bounce_stale"], false);
    EXPECT_EQ(second.status()["stats"]["rays"]["gather"], 0);
    EXPECT_EQ(test::differing_values(second.image(), first.image()), 0u);
}

TEST(LightingToolCacheFiles, LoadingACacheOfOtherLightingSaysItsBounceLightIsStale) {
    test::TempDir d;
    LightingSession s(with_spot(d));
    const std::string key = spot_key(s);
    render_and_wait(s, SessionAction::Rasterize);
    s.save_cache("old.bic");
    s.edit("materials.red.color", json{0.2, 0.2, 0.8});
    render_and_wait(s, SessionAction::Regather);
    ASSERT_EQ(s.status()["bounce_stale"], false);
    s.save_cache("blue.bic");
    // Gathered with a red wall, shown beside a blue one: stale, and a re-shade is pending.
    s.load_cache("old.bic");
    EXPECT_EQ(s.status()["bounce_stale"], true);
    EXPECT_EQ(s.status()["pending"], "reshade");
    render_and_wait(s, SessionAction::Reshade);
    EXPECT_EQ(s.status()["bounce_stale"], true);
    // A cache of this lighting is current again.
    s.load_cache("blue.bic");
    EXPECT_EQ(s.status()["bounce_stale"], false);
    render_and_wait(s, SessionAction::Reshade);
    const Image blue = s.image();
    // Only the spot's intensity differs from a cache whose records keep their light parts:
    // loaded at the session's intensity, exactly.
    s.edit(key + "intensity", 0.5);
    render_and_wait(s, SessionAction::Reshade);
    const Image dimmer = s.image();
    EXPECT_NE(test::differing_values(dimmer, blue), 0u);
    s.load_cache("blue.bic");
    EXPECT_EQ(s.status()["bounce_stale"], false);
    render_and_wait(s, SessionAction::Reshade);
    EXPECT_EQ(test::differing_values(s.image(), dimmer), 0u);
    // Other objects: refused, and the session's cache is unchanged.
    const std::string before = test::bytes_of(s.cache_path().string());
    s.edit("objects.6.transform", json{{"translate", {60, 0, -60}}});
    render_and_wait(s, s.pending());
    const std::string moved = test::bytes_of(s.cache_path().string());
    try {
        s.load_cache("blue.bic");
        ADD_FAILURE() << "a cache of other objects was loaded";
    } catch (const InputError& e) {
        EXPECT_NE(std::string(e.what()).find("other objects"), std::string::npos) << e.what();
    }
    EXPECT_EQ(test::bytes_of(s.cache_path().string()), moved);
    EXPECT_NE(moved, before);
}

TEST(LightingToolCacheFiles, ACacheFileWithoutPartsIsReadAndOneWithBadPartsRefused) {
    test::TempDir d;
    LightingSession s(with_spot(d));
    render_and_wait(s, SessionAction::Rasterize);
    CacheFile f = read_cache_file(s.cache_path().string());
    // Parts round-trip bit for bit.
    const std::string bytes = serialize_cache_file(f);
    const CacheFile back = parse_cache_file(bytes, "back.bic");
    ASSERT_EQ(back.records.size(), f.records.size());
    for (size_t i = 0; i < f.records.size(); ++i)
        for (size_t l = 0; l < f.records[i].parts->light.size(); ++l)
            ASSERT_EQ(std::memcmp(&back.records[i].parts->light[l], &f.records[i].parts->light[l], sizeof(LightPart)), 0);
    // A version 4 file (no parts) is still read.
    for (Record& r : f.records) r.parts.reset();
    for (Record& r : f.fragment_records) r.parts.reset();
    std::string v4 = serialize_cache_file(f);
    const uint32_t four = 4;
    std::memcpy(v4.data() + 8, &four, 4);
    EXPECT_EQ(parse_cache_file(v4, "v4.bic").records.size(), f.records.size());
    // A part of NaN, 1e39 (inf) or 1e30 (past 1e20), its block's checksum made right: refused, naming the record.
    const size_t lights = back.records[0].parts->light.size(), total = back.records.size() + back.fragment_records.size();
    ASSERT_LE(total, 4096u);  // one block of parts: u32 count, u64 FNV-1a, then the payload
    const size_t payload = total * (lights + 1) * 30 * 4, at = bytes.size() - payload;
    for (const float bad : {std::nanf(""), std::numeric_limits<float>::infinity(), 1e30f}) {  // 1e39 reads as inf
        std::string crafted = bytes;
        std::memcpy(crafted.data() + at, &bad, 4);
        uint64_t h = 0xcbf29ce484222325ULL;
        for (size_t i = at; i < crafted.size(); ++i) h = (h ^ static_cast<uint8_t>(crafted[i])) * 0x100000001b3ULL;
        std::memcpy(crafted.data() + at - 8, &h, 8);
        try {
            parse_cache_file(crafted, "bad.bic");
            ADD_FAILURE() << "a part of " << bad << " was read";
        } catch (const InputError& e) {
            EXPECT_NE(std::string(e.what()).find("record 0's light parts"), std::string::npos) << e.what();
        }
    }
    // Parts cut short: refused by name.
    try {
        parse_cache_file(bytes.substr(0, bytes.size() - 100), "short.bic");
        ADD_FAILURE() << "a file with parts cut short was read";
    } catch (const InputError& e) {
        EXPECT_NE(std::string(e.what()).find("short.bic"), std::string::npos) << e.what();
    }
}

}  // namespace
}  // namespace bounce
