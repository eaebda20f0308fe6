// Issue 26: time in scenes (keyed values, the shot), frames of a shot as a loop of plans, and
// records across frames — kept exactly when nothing they see moved, travelling with their object.
#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>
#include <map>

#include "bounce/accel/accel.h"
#include "bounce/cache/sites.h"
#include "bounce/cache/temporal.h"
#include "bounce/core/error.h"
#include "bounce/render/shot.h"
#include "bounce/scene/changes.h"
#include "test_util.h"

namespace bounce {
namespace {

using nlohmann::json;

/// A floor, a wall and a sphere under a point light and a dim sky, with a shot of `frames`.
json shot_scene(int frames = 3) {
    json j = test::base_scene();
    j["animation"] = {{"fps", 24}, {"frames", {1, frames}}};
    j["camera"] = {{"position", {0, 3, 8}}, {"look_at", {0, 0.5, 0}}, {"fov", 40}, {"resolution", {24, 16}}};
    j["render"] = {{"spp", 1}, {"gi", "cache"}, {"rays", 32}, {"light_samples", 1}, {"threads", 1}};
    j["objects"] = {{{"name", "floor"}, {"type", "quad"}, {"vertices", {{-6, 0, -6}, {-6, 0, 6}, {6, 0, 6}, {6, 0, -6}}}},
                    {{"name", "wall"}, {"type", "quad"}, {"vertices", {{-6, 0, -3}, {6, 0, -3}, {6, 4, -3}, {-6, 4, -3}}}},
                    {{"name", "ball"}, {"type", "sphere"}, {"radius", 0.5}, {"subdivisions", 2}, {"fine_subdivisions", 0}}};
    j["lights"] = {{{"type", "point"}, {"position", {1, 5, 4}}, {"color", 30}}, {{"type", "sky"}, {"color", 0.2}}};
    return j;
}

Scene at(const json& j, double frame) {
    LoadOptions o;
    o.frame = frame;
    return load_scene_text(j.dump(), "shot.json", {}, o);
}

TEST(Keyframes, LinearSmoothAndStepValuesAtFrames) {
    json j = shot_scene(48);
    j["camera"]["fov"] = {{"keys", {{1, 30}, {11, 50}}}};
    j["lights"][0]["position"] = {{"keys", {{1, {0, 5, 0}}, {5, {4, 5, 0}}, {9, {4, 5, 8}}}}, {"interpolation", "smooth"}};
    j["lights"][0]["color"] = {{"keys", {{1, 10}, {20, 40}}}, {"interpolation", "step"}};
    EXPECT_FLOAT_EQ(at(j, 1).camera.fov, 30);
    EXPECT_FLOAT_EQ(at(j, 6).camera.fov, 40);
    EXPECT_FLOAT_EQ(at(j, 30).camera.fov, 50);  // held after the last key
    // Smooth passes through its keys; between them it is C1 (here: symmetric about frame 5).
    EXPECT_FLOAT_EQ(at(j, 5).lights[0].position.x, 4);
    EXPECT_NEAR(at(j, 3).lights[0].position.x, 2.25, 1e-5);  // Hermite with Catmull-Rom tangents 0.5 and 0.5
    EXPECT_FLOAT_EQ(at(j, 19.9).lights[0].color.x, 10);
    EXPECT_FLOAT_EQ(at(j, 20).lights[0].color.x, 40);
}

TEST(Keyframes, RotationsAreInterpolatedAsQuaternions) {
    json j = shot_scene(48);
    j["objects"][2]["center"] = {1, 0, 0};
    j["objects"][2]["transform"] = {{"rotate", {{"keys", {{1, {0, 0, 0, 1}}, {3, {180, 0, 0, 1}}}}}}};
    // Half way, a quarter turn about z: the centre (1, 0, 0) is at (0, 1, 0).
    const Scene s = at(j, 2);
    const Bounds b = s.objects[2].coarse.bounds();
    const Vec3 c = (b.lo + b.hi) * 0.5f;
    EXPECT_NEAR(c.x, 0, 1e-4);
    EXPECT_NEAR(c.y, 1, 1e-4);
    EXPECT_TRUE(s.objects[2].moves);
    EXPECT_FALSE(s.objects[0].moves);
}

TEST(Keyframes, BadKeysAndFramesAreRefusedWithThePointer) {
    const auto refused = [](json j, const std::string& where, const std::string& says, double frame = 1) {
        try {
            at(j, frame);
            ADD_FAILURE() << where;
        } catch (const InputError& e) {
            EXPECT_EQ(e.place(), where.empty() ? "/" : where) << e.what();
            EXPECT_NE(std::string(e.what()).find(says), std::string::npos) << e.what();
        }
    };
    json j = shot_scene();
    j["camera"]["fov"] = {{"keys", {{5, 30}, {2, 50}}}};
    refused(j, "/camera/fov/keys/1/0", "out of order");
    j["camera"]["fov"] = {{"keys", {{2, 30}, {2, 50}}}};
    refused(j, "/camera/fov/keys/1/0", "keyed twice");
    j["camera"]["fov"] = {{"keys", {{1, 30}, {2, 1e39}}}};
    refused(j, "/camera/fov/keys/1/1", "not a finite value");
    j = shot_scene();
    j["render"]["rays"] = {{"keys", {{1, 30}, {2, 50}}}};
    refused(j, "/render/rays", "cannot be animated");
    j = shot_scene();
    j["lights"][0]["type"] = {{"keys", {{1, 1}}}};
    refused(j, "/lights/0/type", "cannot be animated");
    j = shot_scene();
    j["camera"]["fov"] = {{"keys", {{1, 30}, {3, 200}}}};  // valid keys, a value out of range at frame 3
    refused(j, "/camera/fov", "out of range", 3);
    refused(shot_scene(), "/animation/frames", "outside the shot", 9);
    json keyed_without_shot = shot_scene();
    keyed_without_shot.erase("animation");
    keyed_without_shot["camera"]["fov"] = {{"keys", {{1, 30}}}};
    refused(keyed_without_shot, "", "no \"animation\" block");
}

/// Frames of the shot rendered in order through a Shot; each frame's result and scene kept.
struct Frames {
    Shot shot;
    std::vector<RenderResult> results;
    std::vector<std::shared_ptr<const Scene>> scenes;
    void render(const json& j, int frame) {
        auto scene = std::make_shared<const Scene>(at(j, frame));
        Stats stats;
        RenderRequest req;
        req.frame = frame;
        results.push_back(shot.render(scene, req, stats, nullptr));
        scenes.push_back(scene);
        // The next frame starts from copies of this one's (the result keeps its own).
        RenderResult copy;
        copy.cache = results.back().cache->clone();
        copy.accel = results.back().accel, copy.radiosity = results.back().radiosity, copy.waiting = results.back().waiting;
        copy.gathers = results.back().gathers;
        copy.deep = results.back().deep;
        shot.keep(copy, scene);
    }
};

/// A gatherer of a frame's scene as a fresh render would build it.
struct FreshGatherer {
    explicit FreshGatherer(const Scene& scene)
        : accel(scene, scene.render.lighting),
          materials(scene),
          lighting(scene, accel, scene.render.lighting),
          rt(RadiosityTextures::lazy(scene, materials, lighting, test::still_plan(scene).find<RadiosityStep>()->settings)),
          gatherer(scene, accel, materials, lighting, &rt, test::still_plan(scene).gather) {}
    SceneAccel accel;
    Materials materials;
    DirectLighting lighting;
    RadiosityTextures rt;
    Gatherer gatherer;
};

TEST(TemporalCache, AKeptRecordEqualsAFreshGatherAtItsPlaceBitForBit) {
    // The ball moves behind the wall, out of sight of everything in front of it.
    json j = shot_scene();
    j["objects"][2]["transform"] = {{"translate", {{"keys", {{1, {-2, 0.5, -5}}, {3, {2, 0.5, -5}}}}}}};
    Frames f;
    f.render(j, 1);
    f.render(j, 2);
    const RenderResult& r = f.results[1];
    EXPECT_GT(r.temporal.kept, 20u);
    const Scene& scene = *f.scenes[1];
    const FreshGatherer fresh(scene);
    const Gatherer& gatherer = fresh.gatherer;
    Counters counters;
    size_t compared = 0;
    for (size_t i = 0; i < r.cache->size(); ++i) {
        const Record& k = r.cache->record(i);
        if (k.gathered != 1 || k.frame != 1) continue;  // kept from frame 1 untouched
        const GatherResult g =
            gatherer.gather(k.origin, k.n, record_stream(k, scene.render.visibility.seed, scene.camera.width), counters, k.near);
        // What the gather measured, bit for bit (the record's radius and gradient scaling are
        // the cache's, from the footprint of this frame's camera).
        ASSERT_EQ(g.irradiance, k.E) << "record " << i;
        ASSERT_EQ(g.ao, k.ao) << "record " << i;
        ASSERT_EQ(g.bent_normal, k.bent) << "record " << i;
        ASSERT_EQ(g.light_dir, k.dir) << "record " << i;
        ASSERT_EQ(g.min_distance, k.dmin) << "record " << i;
        ASSERT_EQ(g.grad_rot, k.grad_r) << "record " << i;
        ++compared;
    }
    EXPECT_EQ(compared, r.temporal.kept);
}

TEST(TemporalCache, AMovingCamerasRefinedFragmentsUseTheirOwnGathers) {
    // Fragment records are keyed by pixel: frame 2's must replace frame 1's at the same pixel,
    // or its refinement's gathers are made and never used (shot A's edges, docs/animation.md).
    json j = shot_scene();
    j["camera"]["position"] = {{"keys", {{1, {0, 3, 8}}, {3, {0.4, 3, 7.4}}}}};
    j["render"]["refine"] = 0.01;              // many fragments refine
    j["render"]["refine_noise"] = 0;           // (the raw spread: noise-aware refinement refines few here)
    j["render"]["temporal_refine_reuse"] = 0;  // each gathers its own
    Frames f;
    f.render(j, 1);
    f.render(j, 2);
    const RenderResult& r = f.results[1];
    ASSERT_GT(f.results[0].fragment_records_new, 10u);
    ASSERT_GT(r.fragment_records_new, 10u);
    size_t own = 0, used = 0;
    for (size_t i = 0; i < r.cache->fragment_record_count(); ++i) {
        const Record& k = r.cache->fragment_record_at(i);
        if (k.gathered != 2) continue;
        ++own;
        used += r.cache->fragment_record(k.key, k.p) == &k;
    }
    EXPECT_EQ(own, r.fragment_records_new);
    EXPECT_EQ(used, own);
}

TEST(TemporalCache, RefinementReprojectsEarlierGathersAndKeepsOnlyGathersForLater) {
    // A slow camera: frame 2's fragments lie among frame 1's refinement gathers.
    json j = shot_scene();
    j["camera"]["position"] = {{"keys", {{1, {0, 3, 8}}, {3, {0.04, 3, 7.96}}}}};
    j["render"]["refine"] = 0.01;
    j["render"]["refine_noise"] = 0;  // (the raw spread: noise-aware refinement refines few here)
    j["render"]["temporal_refine_reuse"] = 1.5;
    Frames f;
    f.render(j, 1);
    f.render(j, 2);
    f.render(j, 3);
    const RenderResult& first = f.results[0];
    const RenderResult& second = f.results[1];
    ASSERT_GT(first.fragment_records_new, 10u);
    EXPECT_EQ(first.gathers.size(), first.fragment_records_new);  // frame 1's gathers, all kept for later
    const uint32_t full = first.gathers.front().rays;
    // Frame 2 reprojects some fragments' gathers from frame 1's (records that trace fewer rays
    // and keep no hits, used by their fragments) and gathers fewer in full.
    size_t reprojected = 0;
    uint64_t traced = 0;
    for (size_t i = 0; i < second.cache->fragment_record_count(); ++i) {
        const Record& k = second.cache->fragment_record_at(i);
        if (k.gathered != 2 || k.hits) continue;
        ++reprojected, traced += k.rays;
        EXPECT_EQ(second.cache->fragment_record(k.key, k.p), &k);
        EXPECT_GT(luminance(k.E), 0.0f);
    }
    EXPECT_GT(reprojected, 0u);
    EXPECT_LT(traced, reprojected * full / 2);  // most of their rays are frame 1's
    EXPECT_LT(second.fragment_records_new, first.fragment_records_new);
    EXPECT_EQ(second.shading_misses, 0u);
    // Only gathers serve later frames: frame 1's and frame 2's own, never a reprojection.
    EXPECT_EQ(second.gathers.size(), first.gathers.size() + second.fragment_records_new);
    for (const Record& g : f.results[2].gathers) {
        EXPECT_TRUE(g.hits);
        EXPECT_EQ(g.rays, full);
    }
    // Judged for frame 3, frame 2's cache keeps a moving camera's fragment records of frame 2
    // only (for the hold, by their place: without hits; reprojection's gathers keep theirs), so
    // a shot holds the hits of its gathers alone, not of every pixel ever refined.
    // (Frame 2 refined every pixel frame 1 did: one of frame 1's is put back under a free key.)
    std::unique_ptr<IrradianceCache> copy = second.cache->clone();
    Record old = first.gathers.front();
    old.key = ~uint64_t(0), old.gathered = 1;
    copy->insert_fragment_record(old);
    const IrradianceCache& cache2 = *copy;
    const SceneChanges changes = scene_changes(*f.scenes[1], *f.scenes[2]);
    ASSERT_TRUE(changes.camera);
    const TemporalJudgement judged =
        judge_records(cache2, {}, {}, *f.scenes[1], *f.scenes[2], changes, {}, 0, f.scenes[2]->render.visibility.seed);
    size_t of_two = 0, of_one = 0;
    for (size_t i = 0; i < cache2.fragment_record_count(); ++i) {
        of_two += cache2.fragment_record_at(i).gathered == 2;
        of_one += cache2.fragment_record_at(i).gathered == 1;
    }
    ASSERT_GT(of_two, 0u);
    ASSERT_EQ(of_one, 1u);
    EXPECT_GE(judged.dropped, 1u);
    EXPECT_EQ(judged.fragment_valid.size() + judged.fragment_stale.size(), of_two);
    for (const Record& k : judged.fragment_valid) {
        EXPECT_EQ(k.gathered, 2);
        EXPECT_FALSE(k.hits);
    }
    for (const auto& [key, k] : judged.fragment_stale) EXPECT_TRUE(k.hits);  // updated from them if used
}

TEST(TemporalCache, RecordsOnAMovingObjectTravelWithItAndTheRestUpdateOnlyWhatTheySee) {
    json j = shot_scene();
    j["objects"][2]["transform"] = {{"translate", {{"keys", {{1, {-1, 0.5, 0}}, {3, {1, 0.5, 0}}}}}}};
    Frames f;
    f.render(j, 1);
    f.render(j, 2);
    const RenderResult& second = f.results[1];
    EXPECT_GT(second.temporal.moved, 0u);
    EXPECT_GT(second.temporal.kept + second.temporal.light, 0u);
    // Every record anchored to the ball sits on the ball at frame 2 (radius 0.5 about (0, 0.5, 0)).
    size_t on_ball = 0;
    for (size_t i = 0; i < second.cache->size(); ++i) {
        const Record& rec = second.cache->record(i);
        if (rec.anchor != 2) continue;
        EXPECT_NEAR(length(rec.p - Vec3(0, 0.5f, 0)), 0.5f, 0.02f);
        ++on_ball;
    }
    EXPECT_GT(on_ball, 0u);
    EXPECT_EQ(second.shading_misses, 0u);
    // An updated record (only its rays through the ball's swept bounds traced again) is what a
    // fresh gather with its stream finds, bit for bit.
    const Scene& scene = *f.scenes[1];
    const FreshGatherer fresh(scene);
    const Gatherer& gatherer = fresh.gatherer;
    Counters counters;
    size_t updated = 0;
    for (size_t i = 0; i < second.cache->size(); ++i) {
        const Record& k = second.cache->record(i);
        if (k.gathered != 2 || k.frame != 1 || k.anchor != kNoAnchor) continue;
        const GatherResult g =
            gatherer.gather(k.origin, k.n, record_stream(k, scene.render.visibility.seed, scene.camera.width), counters, k.near);
        ASSERT_EQ(g.irradiance, k.E) << "record " << i;
        ++updated;
    }
    EXPECT_GT(updated, 0u);
}

TEST(TemporalCache, AFragmentRefinedTheFrameBeforeStaysRefinedDownToTheHold) {
    // A still camera and a sliding light: every record is re-shaded each frame and the records'
    // spread at a fragment moves a little. With render.refine_hold h, frame 2 refines a fragment
    // exactly when its spread is above refine, or above h x refine and frame 1 refined it.
    // The frames given (each scene then `edit`ed, if any), rendered with the hold at `hold`.
    auto run = [](float hold, std::vector<int> frames = {1, 2}, const json& edit = json()) {
        json j = shot_scene();
        j["lights"][0]["position"] = {{"keys", {{1, {1, 5, 4}}, {3, {1.6, 5, 3.4}}}}};
        j["render"]["refine"] = 0.02;
        j["render"]["refine_noise"] = 0;  // the raw spread: more fragments hover about this threshold
        j["render"]["refine_hold"] = hold;
        auto f = std::make_unique<Frames>();
        for (size_t k = 0; k < frames.size(); ++k) {
            if (k > 0 && !edit.is_null()) j["lights"][0]["position"] = edit;
            f->render(j, frames[k]);
        }
        return f;
    };
    const auto held = run(0.5f), free = run(1.0f);
    const RenderResult &one = held->results[0], &two = held->results[1];
    const Layer &m1 = *one.image.find("refined"), &m2 = *two.image.find("refined"), &m2free = *free->results[1].image.find("refined");
    EXPECT_EQ(m1.data, free->results[0].image.find("refined")->data);  // frame 1 has nothing to hold
    const Scene& scene = *held->scenes[1];
    size_t kept_by_hold = 0, refined = 0;
    for (int y = 0; y < two.deep.height; ++y)
        for (int x = 0; x < two.deep.width; ++x) {
            if (two.deep.pixel(x, y).size() != 1 || one.deep.pixel(x, y).size() != 1) continue;
            const Fragment& f = two.deep.pixel(x, y)[0];
            if (!needs_bounce_light(scene, f)) continue;
            const Interpolated in = interpolate_at(*two.cache, f, record_site(scene, f, two.cache->settings()));
            const auto i = static_cast<size_t>(y * two.deep.width + x);
            const bool before = m1.data[i] == 1, above = in.spread > 0.02f, above_hold = in.spread > 0.01f;
            EXPECT_EQ(m2.data[i] == 1, in.weight <= 0 || above || (before && above_hold)) << x << "," << y << " spread " << in.spread;
            if (before && above_hold && !above && in.weight > 0) {
                ++kept_by_hold;
                EXPECT_EQ(m2free.data[i], 0.0f) << x << "," << y;  // without the hold: the interpolation
            }
            refined += m2.data[i] == 1;
        }
    EXPECT_GT(kept_by_hold, 3u);
    EXPECT_GT(refined, kept_by_hold);
    // Frame 2 rendered again after the light moved (as the lighting tool does): no hold within a
    // frame, the fragments refined are those without it.
    const json moved = {1.9, 5, 3.1};
    const auto a = run(0.5f, {2, 2}, moved), b = run(1.0f, {2, 2}, moved);
    EXPECT_GT(a->results[1].temporal.light + a->results[1].temporal.kept + a->results[1].temporal.moved, 0u);
    EXPECT_EQ(a->results[1].image.find("refined")->data, b->results[1].image.find("refined")->data);
    EXPECT_EQ(a->results[1].image.find("indirect")->data, b->results[1].image.find("indirect")->data);
}

TEST(TemporalCache, AMovingCamerasFragmentNearAPointRefinedTheFrameBeforeKeepsTheHold) {
    // A moving camera's fragments never land on the points of the frame before, so the hold
    // reaches those within render.refine_hold_reach pixel footprints of a point refined then.
    // The frames' records are the same with any reach (only refinement reads it), so frame 2
    // refines what it refines without the reach, and besides exactly the fragments whose spread
    // lies between hold x refine and refine, near (on their surface) a point frame 1 refined.
    auto run = [](float reach) {
        json j = shot_scene();
        j["camera"]["position"] = {{"keys", {{1, {0, 3, 8}}, {3, {0.1, 3, 7.9}}}}};
        j["camera"]["resolution"] = {48, 32};
        j["render"]["refine"] = 0.02;
        j["render"]["refine_noise"] = 0;
        j["render"]["temporal_refine_reuse"] = 0;  // every refined fragment gathers its own
        j["render"]["refine_hold_reach"] = reach;
        auto f = std::make_unique<Frames>();
        f->render(j, 1);
        f->render(j, 2);
        return f;
    };
    const auto near = run(3), none = run(0);
    const auto refined_at = [](const RenderResult& r, int frame) {
        std::map<uint64_t, Vec3> keys;
        for (size_t i = 0; i < r.cache->fragment_record_count(); ++i)
            if (const Record& k = r.cache->fragment_record_at(i); k.gathered == frame) keys.emplace(k.key, k.p);
        return keys;
    };
    const RenderResult& two = near->results[1];
    const auto first = refined_at(near->results[0], 1), with = refined_at(two, 2), without = refined_at(none->results[1], 2);
    ASSERT_EQ(first, refined_at(none->results[0], 1));  // frame 1 holds nothing
    ASSERT_GT(first.size(), 10u);
    for (const auto& [key, p] : without) EXPECT_EQ(with.count(key), 1u) << key;
    const Scene& scene = *near->scenes[1];
    size_t held = 0;
    for (int y = 0; y < two.deep.height; ++y)
        for (int x = 0; x < two.deep.width; ++x)
            for (uint32_t k = 0; k < two.deep.pixel(x, y).size(); ++k) {
                const Fragment& f = two.deep.pixel(x, y)[k];
                const uint64_t key = candidate_key(two.deep, x, y, k);
                if (!with.count(key) || without.count(key)) continue;
                ++held;
                const Interpolated in = interpolate_at(*two.cache, f, record_site(scene, f, two.cache->settings()));
                EXPECT_GT(in.spread, 0.01f) << x << "," << y;
                EXPECT_LE(in.spread, 0.02f) << x << "," << y;
                float nearest = 1e30f;
                for (const auto& [k1, p1] : first) nearest = std::min(nearest, length(p1 - f.p));
                EXPECT_LT(nearest, 3 * f.footprint) << x << "," << y;
            }
    EXPECT_GT(held, 3u);
    EXPECT_EQ(with.size(), without.size() + held);
}

TEST(TemporalCache, EveryStaleRecordThatCoversAFragmentIsRedoneSoAPointBlendsTheSameRecords) {
    // Every light twice as bright at frame 2, nothing else changes: each record is stale (its
    // light changed) and re-shaded from its hits, to exactly twice its value. If only the
    // records that fill a miss were redone, a point would blend another subset of them (which
    // ones depends on the order of the misses) and its bounce light would not simply double.
    json j = shot_scene();
    j["lights"][0]["color"] = {{"keys", {{1, 30}, {3, 90}}}};
    j["lights"][1]["color"] = {{"keys", {{1, 0.2}, {3, 0.6}}}};
    j["camera"]["resolution"] = {64, 48};
    Frames f;
    f.render(j, 1);
    f.render(j, 2);
    const RenderResult &one = f.results[0], &two = f.results[1];
    EXPECT_EQ(two.temporal.kept, 0u);
    EXPECT_EQ(two.temporal.light, one.cache->size());
    EXPECT_EQ(two.temporal.reshaded, one.cache->size());  // every record: each covers at least its own fragment
    EXPECT_TRUE(two.waiting.empty());
    EXPECT_EQ(two.records_new, 0u);
    EXPECT_EQ(two.cache->size(), one.cache->size());
    const Layer &a = *one.image.find("indirect"), &b = *two.image.find("indirect");
    ASSERT_EQ(a.data.size(), b.data.size());
    size_t lit = 0;
    for (size_t i = 0; i < a.data.size(); ++i) {
        ASSERT_NEAR(b.data[i], 2 * a.data[i], 1e-5f * (1 + a.data[i])) << "value " << i;
        lit += a.data[i] > 0;
    }
    EXPECT_GT(lit, a.data.size() / 2);
}

TEST(Sequences, AFrameThatFailsStopsTheShotThereAndResumeSkipsWhatIsDone) {
    test::TempDir d;
    json j = shot_scene(4);
    j["camera"]["fov"] = {{"keys", {{1, 40}, {3, 60}, {4, 300}}}, {"interpolation", "step"}};  // frame 4: out of range
    d.write("s.json", j.dump());
    const std::string args =
        "render " + d.file("s.json") + " -q -o " + d.file("f.####.exr") + " --cache-out " + d.file("f.####.bic") + " --frames 1-4";
    std::string err;
    EXPECT_EQ(test::run_bounce(args, &err), 2);
    EXPECT_NE(err.find("/camera/fov"), std::string::npos) << err;
    for (const char* f : {"f.0001.exr", "f.0002.exr", "f.0003.exr", "f.0001.bic", "f.0003.bic"})
        EXPECT_TRUE(std::filesystem::exists(d.file(f))) << f;
    EXPECT_FALSE(std::filesystem::exists(d.file("f.0004.exr")));
    // --resume renders only the missing frames (here: 3, starting from frame 2's cache file).
    j["camera"]["fov"] = {{"keys", {{1, 40}, {3, 60}}}, {"interpolation", "step"}};
    d.write("s.json", j.dump());
    std::filesystem::remove(d.file("f.0003.exr"));
    const std::string before = test::bytes_of(d.file("f.0001.exr"));
    EXPECT_EQ(test::run_bounce(args + " --resume"), 0);
    EXPECT_EQ(test::bytes_of(d.file("f.0001.exr")), before);
    EXPECT_TRUE(std::filesystem::exists(d.file("f.0003.exr")));
    EXPECT_TRUE(std::filesystem::exists(d.file("f.0004.exr")));
}

TEST(Sequences, ARangePastTheShotOrASubframeOntoAFramePatternIsRefusedBeforeAnyFrameRenders) {
    test::TempDir d;
    d.write("s.json", shot_scene(4).dump());
    const std::string scene = "render " + d.file("s.json") + " -q --res 8x8 ";
    // Frames 3 and 4 exist in the shot; 5 does not: nothing is rendered (it used to render 3
    // and 4 before failing at 5).
    test::expect_refused(scene + "-o " + d.file("f.####.exr") + " --frames 3-5",
                         {"command line", "--frames 3-5", "frame 5 is outside the shot, frames 1 to 4"});
    EXPECT_FALSE(std::filesystem::exists(d.file("f.0003.exr")));
    // A subframe would write frame 3's names (and overwrite its files); with a plain name it renders.
    test::expect_refused(scene + "-o " + d.file("f.####.exr") + " --frame 2.5",
                         {"--frame 2.5", "a #### file name needs a whole frame number"});
    test::expect_refused(scene + "-o " + d.file("sub.exr") + " --stats-json " + d.file("f.####.json") + " --frame 2.5",
                         {"--frame 2.5", "a #### file name needs a whole frame number"});
    EXPECT_FALSE(std::filesystem::exists(d.file("f.0003.exr")));
    EXPECT_FALSE(std::filesystem::exists(d.file("sub.exr")));
    EXPECT_EQ(test::run_bounce(scene + "-o " + d.file("sub.exr") + " --frame 2.5"), 0);
    EXPECT_TRUE(std::filesystem::exists(d.file("sub.exr")));
    // Not a frame at all, in a shot or a still.
    for (const std::string& file : {d.file("s.json"), test::cornell_scene()})
        for (const char* frame : {"nan", "1e39", "-inf", "0x2", "''"})
            test::expect_refused("render " + file + " -q --res 8x8 -o " + d.file("n.####.exr") + " --frame " + frame,
                                 {"--frame", std::string(frame) == "1e39" ? "a frame must be a finite number within +-1e+06"
                                                                          : "is not a decimal frame number"});
    EXPECT_EQ(test::run_bounce(scene + "-o " + d.file("f.####.exr") + " --frame 3"), 0);
    EXPECT_TRUE(std::filesystem::exists(d.file("f.0003.exr")));
}

TEST(TemporalCache, SceneChangesTellRigidFromStaticAndSeeEmissiveObjectsAsLights) {
    json j = shot_scene();
    j["objects"][2]["transform"] = {{"translate", {{"keys", {{1, {0, 0.5, 0}}, {3, {2, 0.5, 0}}}}}}};
    const SceneChanges c = scene_changes(at(j, 1), at(j, 2));
    ASSERT_TRUE(c.comparable);
    EXPECT_EQ(c.objects[0].kind, ObjectMotion::Kind::Static);
    EXPECT_EQ(c.objects[2].kind, ObjectMotion::Kind::Rigid);
    EXPECT_NEAR(c.objects[2].delta.point(Vec3(0)).x, 1, 1e-5);
    EXPECT_FALSE(c.lights);
    EXPECT_FALSE(c.camera);
    json moving = j;
    moving["camera"]["position"] = {{"keys", {{1, {0, 3, 8}}, {3, {0, 3, 6}}}}};
    EXPECT_TRUE(scene_changes(at(moving, 1), at(moving, 2)).camera);
    j["materials"] = {{"glow", {{"emission", 3}}}};
    j["objects"][2]["material"] = "glow";
    EXPECT_TRUE(scene_changes(at(j, 1), at(j, 2)).lights);
}

TEST(TemporalCache, AutomaticDistancesDoNotChangeAsAnObjectMovesOutOfTheSet) {
    // The ball leaves the floor's bounds: the scene's bounds grow from frame to frame, its size
    // (what the ray offset, radiosity texel and AO distance are fractions of) must not.
    json j = shot_scene();
    j["objects"][2]["transform"] = {{"translate", {{"keys", {{1, {0, 0.5, 0}}, {3, {20, 0.5, 0}}}}}}};
    const Scene a = at(j, 1), b = at(j, 3);
    ASSERT_NE(length(a.bounds().diagonal()), length(b.bounds().diagonal()));
    EXPECT_FLOAT_EQ(a.size(), std::sqrt(12.0f * 12 + 4 * 4 + 12 * 12));  // the floor and the wall
    EXPECT_EQ(a.size(), b.size());
    EXPECT_EQ(SceneAccel(a, a.render.lighting).ray_offset(), SceneAccel(b, b.render.lighting).ray_offset());
    // When everything moves there is nothing else to measure: the bounds at the frame.
    j["objects"] = {j["objects"][2]};
    EXPECT_EQ(at(j, 3).size(), length(at(j, 3).bounds().diagonal()));
}

}  // namespace
}  // namespace bounce
