// The parameter table: one declaration drives the scene keys, CLI flags, listing, docs table,
// cache identity and metadata.
#include "bounce/config/params.h"

#include <gtest/gtest.h>

#include <fstream>
#include <regex>
#include <sstream>

#include "bounce/cache/cache_identity.h"
#include "bounce/core/error.h"
#include "bounce/scene/params_cli.h"
#include "test_util.h"

namespace bounce {
namespace {

TEST(Params, EveryRowRoundTripsItsDefaultAndEveryKeyIsUnique) {
    std::set<std::string> keys, flags;
    Scene s;
    for (const Param& p : scene_params()) {
        EXPECT_TRUE(keys.insert(p.key).second) << p.key;
        if (!p.flag.empty()) {
            EXPECT_TRUE(flags.insert(p.flag).second) << p.flag;
        }
        EXPECT_FALSE(p.doc.empty()) << p.key;
        // The default passes its own validation and setting it changes nothing.
        nlohmann::json v = check_param(p, p.default_value(),
                                       [&](const std::string&, const std::string& m) { throw std::runtime_error(p.key + ": " + m); });
        if (!p.required) {
            p.set(s, v);
            EXPECT_EQ(p.get(s), p.default_value()) << p.key;
        }
    }
    EXPECT_EQ(scene_params().size(), keys.size());
    EXPECT_NE(find_param(scene_params(), "render.min_spacing"), nullptr);
}

TEST(Params, ValuesAreCheckedAsTheFloatTheyBecome) {
    const Param& p = *find_param(scene_params(), "render.min_spacing");
    auto message = [&](const nlohmann::json& v) {
        try {
            check_param(p, v, [](const std::string&, const std::string& m) { throw std::runtime_error(m); });
        } catch (const std::runtime_error& e) {
            return std::string(e.what());
        }
        return std::string("accepted");
    };
    EXPECT_EQ(message(4.0), "accepted");
    EXPECT_NE(message(1e39).find("does not fit a float"), std::string::npos);
    EXPECT_NE(message(-1).find("out of range"), std::string::npos);
    EXPECT_NE(message("nan").find("expected a number"), std::string::npos);
    const Param& metric = *find_param(scene_params(), "render.metric");
    try {
        check_param(metric, "hessain", [](const std::string&, const std::string& m) { throw std::runtime_error(m); });
        FAIL();
    } catch (const std::runtime_error& e) {
        EXPECT_NE(std::string(e.what()).find("valid: tl04, ward"), std::string::npos);
    }
}

TEST(Params, TheDocsTableIsTheGeneratedOne) {
    std::ifstream in(test::source_dir() + "/docs/scene-format.md");
    std::stringstream ss;
    ss << in.rdbuf();
    std::string doc = ss.str();
    const std::string begin = "<!-- params:begin -->\n", end = "<!-- params:end -->";
    auto a = doc.find(begin), b = doc.find(end);
    ASSERT_NE(a, std::string::npos);
    ASSERT_NE(b, std::string::npos);
    EXPECT_EQ(doc.substr(a + begin.size(), b - a - begin.size()), params_markdown())
        << "docs/scene-format.md is stale: paste `bounce params --markdown` between its params markers";
}

TEST(Params, ARowAddedInOnePlaceReachesTheCliTheListingTheDocsAndTheCacheIdentity) {
    ParamTable table = scene_params();
    // A new cache parameter, bound (for the test) to an existing field.
    Param extra = *find_param(table, "render.quality");
    extra.key = "render.test_knob";
    extra.flag = "--test-knob";
    extra.doc = "a knob added by the test";
    table.push_back(extra);

    // The CLI flag exists and becomes a validated override.
    CLI::App app;
    std::vector<Override> out;
    add_param_flags(app, table, out);
    std::vector<std::string> argv{"--test-knob", "2.5"};
    std::reverse(argv.begin(), argv.end());
    app.parse(argv);
    ASSERT_EQ(out.size(), 1u);
    EXPECT_EQ(out[0].assignment, "render.test_knob=2.5");
    EXPECT_EQ(out[0].origin, "--test-knob 2.5");

    // The listing and the docs table carry it.
    bool listed = false;
    for (const auto& row : params_listing(table)) listed |= row["key"] == "render.test_knob" && row["flag"] == "--test-knob";
    EXPECT_TRUE(listed);
    EXPECT_NE(params_markdown(table).find("| `render.test_knob` |"), std::string::npos);

    // It is part of the cache identity, with the value of the scene.
    Scene s;
    s.render.cache.quality = 2.5f;
    nlohmann::json id = param_values(s, kCacheIdentity, table);
    EXPECT_EQ(id["render.test_knob"], 2.5);
    EXPECT_FALSE(param_values(s, kCacheIdentity, scene_params()).contains("render.test_knob"));
}

TEST(Params, SceneFileAndFlagsShareTheNamesAndErrorsNameTheFlag) {
    Scene s = test::scene_from(test::base_scene(), {Override("render.min_spacing=3", "--min-spacing 3")});
    EXPECT_FLOAT_EQ(s.render.cache.min_spacing, 3.0f);
    nlohmann::json j = test::base_scene();
    j["render"] = {{"metric", "ward"}, {"tile_order", "spiral"}, {"cache_sharing", "per-thread"}, {"gi", "cache"}};
    s = test::scene_from(j);
    EXPECT_EQ(s.render.cache.metric, Metric::Ward);
    EXPECT_EQ(s.render.parallel.tile_order, TileOrder::Spiral);
    EXPECT_EQ(s.render.parallel.cache_sharing, CacheSharing::PerThread);
    EXPECT_EQ(s.render.indirect.gi, GiMode::Cache);
    try {
        test::scene_from(test::base_scene(), {Override("render.rays=-1", "--rays -1")});
        FAIL();
    } catch (const InputError& e) {
        EXPECT_STREQ(e.what(), "command line: --rays -1 (/render/rays): error: -1 is out of range [1, 1048576]");
    }
    // Lists as the help writes them ("[x0, x1, y0, y1]") or bare; a wrong count says how many came.
    const Param* crop = find_param(scene_params(), "render.crop");
    ASSERT_NE(crop, nullptr);
    for (const char* text : {"[1,5,2,6]", "1,5,2,6", "[1, 5, 2, 6]"}) {
        s = test::scene_from(test::base_scene(), {flag_override(*crop, text)});
        EXPECT_EQ(s.render.visibility.crop, (std::array<int, 4>{1, 5, 2, 6})) << text;
    }
    try {
        test::scene_from(test::base_scene(), {flag_override(*crop, "[[1,5,2,6]]")});
        FAIL();
    } catch (const InputError& e) {
        EXPECT_NE(std::string(e.what()).find("expected an array of 4 integers, got an array of 1"), std::string::npos) << e.what();
    }
    j = test::base_scene();
    j["render"] = {{"min_spacnig", 1}};
    try {
        test::scene_from(j);
        FAIL();
    } catch (const InputError& e) {
        EXPECT_NE(std::string(e.what()).find("did you mean \"min_spacing\""), std::string::npos);
    }
}

TEST(Params, CacheIdentityHoldsEveryRecordChangingSettingAndNoShadingOne) {
    Scene s;
    nlohmann::json id = cache_file_info(s, 0).parameters;
    for (const char* key : {"render.metric", "render.min_spacing", "render.max_spacing", "render.max_angle", "render.gradient_limit",
                            "render.rays", "render.gradients", "render.ao", "render.seed"})
        EXPECT_TRUE(id.contains(key)) << key;
    for (const char* key : {"render.shading_reach", "render.light_per_channel", "render.threads", "render.light_samples"})
        EXPECT_FALSE(id.contains(key)) << key;
    Scene t = s;
    t.render.cache.min_spacing = 1;
    auto diff = param_differences(id, cache_file_info(t, 0).parameters);
    ASSERT_EQ(diff.size(), 1u);
    EXPECT_EQ(diff[0], "render.min_spacing: 2.0 -> 1.0");
}

}  // namespace
}  // namespace bounce

namespace bounce {
namespace {

TEST(Params, TheHelpOfANoFlagSaysItTurnsTheSettingOff) {
    std::string help;
    ASSERT_EQ(test::run_bounce_shell(std::string(BOUNCE_BINARY) + " render --help 1>&2", &help), 0);
    for (const char* flag : {"--no-gradients", "--no-neighbour-clamp", "--no-radiosity"}) {
        const size_t at = help.find(flag);
        ASSERT_NE(at, std::string::npos) << flag;
        const std::string line = help.substr(at, help.find('\n', at) - at);
        EXPECT_NE(line.find("turn off: "), std::string::npos) << line;
    }
}

}  // namespace
}  // namespace bounce

namespace bounce {
namespace {

/// Every `render.x` / `camera.x` key named in back-quotes in the docs and bench scripts is a row
/// of the parameter table (docs/displacement.md and bench/ogre once named keys that were not).
TEST(Params, EveryKeyTheDocsNameExists) {
    const std::regex key("`((render|camera)\\.[a-z_]+)[`=]");
    for (const char* file : {"docs/displacement.md", "docs/animation.md", "docs/irradiance-cache.md", "docs/fur.md", "docs/parallel.md",
                             "docs/shading.md", "docs/usage.md", "docs/benchmarks.md", "docs/scene-format.md", "README.md"}) {
        const std::string text = test::bytes_of(test::source_dir() + "/" + file);
        ASSERT_FALSE(text.empty()) << file;
        for (auto it = std::sregex_iterator(text.begin(), text.end(), key); it != std::sregex_iterator(); ++it)
            EXPECT_NE(find_param(scene_params(), (*it)[1]), nullptr) << file << " names " << (*it)[1];
    }
    for (const char* old : {"`cache.", "`render.dicing`"})
        EXPECT_EQ(test::bytes_of(test::source_dir() + "/docs/displacement.md").find(old), std::string::npos) << old;
}

}  // namespace
}  // namespace bounce
