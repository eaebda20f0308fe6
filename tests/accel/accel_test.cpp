// Ray-origin offsetting between a fine and a coarse tessellation of the same sphere.
#include <gtest/gtest.h>

#include "bounce/accel/accel.h"
#include "bounce/core/random.h"
#include "bounce/core/sampling.h"
#include "test_util.h"

namespace bounce {
namespace {

using nlohmann::json;

Scene sphere_scene(float offset = -1) {
    json j = test::base_scene();
    j["objects"] = {{{"type", "sphere"}, {"center", {0, 0, 0}}, {"radius", 1.0}, {"subdivisions", 2}, {"fine_subdivisions", 3}}};
    if (offset >= 0) j["render"] = {{"ray_offset", offset}};
    return test::scene_from(j);
}

struct RayStats {
    int rays = 0, self_hits = 0, misses = 0, wrong_distance = 0;
};

/// Rays from points on the fine sphere. `inside`: normal points to the centre (the sphere seen
/// from within, where fine points lie outside the coarse chords) and rays must reach the far
/// side at the chord length 2 R cos(theta); otherwise rays leave the convex sphere and must
/// hit nothing.
template <typename Trace>
RayStats shoot(const Scene& s, float gap, bool inside, Trace trace) {
    const TriangleMesh& fine = s.objects[0].fine;
    RayStats st;
    for (uint32_t t = 0; t < fine.triangle_count(); t += 7) {
        RandomStream rng(3, t);
        SurfacePoint sp = surface_point(fine, t, rng.get(0, 0) * 0.5f, rng.get(0, 1) * 0.5f);
        Vec3 n = normalize(sp.p) * (inside ? -1.0f : 1.0f);
        Frame f(n);
        for (int k = 0; k < 16; ++k) {
            Vec3 local = cosine_hemisphere(rng.get(static_cast<uint64_t>(k + 1), 0), rng.get(static_cast<uint64_t>(k + 1), 1));
            // The default offset (4x the gap) covers rays whose cosine exceeds 1/4.
            if (local.z < 0.3f) continue;
            Vec3 d = f.to_world(local);
            ++st.rays;
            Hit h = trace(sp.p, d);
            if (!inside) {
                st.self_hits += h.valid();
                continue;
            }
            float chord = 2 * length(sp.p) * local.z;
            if (!h.valid())
                ++st.misses;
            else if (h.t < 0.5f * chord)
                ++st.self_hits;
            // The far coarse surface sags up to `gap` inside the sphere: the hit can come that
            // much earlier along the ray (divided by the cosine there, which equals ours).
            else if (h.t > chord + 1e-3f || h.t < chord - 1.5f * gap / local.z)
                ++st.wrong_distance;
        }
    }
    return st;
}

TEST(RayOffset, FineAndCoarseSpheresDifferMeasurably) {
    Scene s = sphere_scene();
    SceneAccel accel(s, s.render.lighting);
    // A level-2 icosphere (edges ~0.27 rad) sags at most 1 - cos(~0.19) ~ 1.8% below its sphere.
    EXPECT_GT(accel.fine_coarse_gap(), 0.01f);
    EXPECT_LT(accel.fine_coarse_gap(), 0.02f);
    EXPECT_GE(accel.ray_offset(), 2 * accel.fine_coarse_gap());
}

TEST(RayOffset, NoSelfHitsFromInsideTheSphere) {
    Scene s = sphere_scene();
    SceneAccel accel(s, s.render.lighting);
    RayStats st = shoot(s, accel.fine_coarse_gap(), true, [&](const Vec3& p, const Vec3& d) { return accel.trace(p, d); });
    ASSERT_GT(st.rays, 1000);
    EXPECT_EQ(st.self_hits, 0);
    EXPECT_EQ(st.misses, 0);
    EXPECT_EQ(st.wrong_distance, 0);
}

TEST(RayOffset, NaiveTracingSelfHitsWhereOffsettingDoesNot) {
    // The same rays traced from the fine point without offsetting hit the coarse chord they
    // start above: this is the artefact offsetting removes (and shows this test can fail).
    Scene s = sphere_scene();
    SceneAccel accel(s, s.render.lighting);
    RayStats st = shoot(s, accel.fine_coarse_gap(), true,
                        [&](const Vec3& p, const Vec3& d) { return accel.coarse().intersect(p, d, 1e-5f, INFINITY); });
    EXPECT_GT(st.self_hits, st.rays / 2);
}

TEST(RayOffset, NoSelfHitsLeavingTheConvexSphere) {
    Scene s = sphere_scene();
    SceneAccel accel(s, s.render.lighting);
    RayStats st = shoot(s, accel.fine_coarse_gap(), false, [&](const Vec3& p, const Vec3& d) { return accel.trace(p, d); });
    ASSERT_GT(st.rays, 1000);
    EXPECT_EQ(st.self_hits, 0);
}

TEST(RayOffset, TooSmallOffsetSelfHits) {
    // A user distance below the tessellation gap cannot hide the coarse surface.
    Scene s = sphere_scene(1e-5f);
    SceneAccel accel(s, s.render.lighting);
    RayStats st = shoot(s, accel.fine_coarse_gap(), true, [&](const Vec3& p, const Vec3& d) { return accel.trace(p, d); });
    EXPECT_GT(st.self_hits, 0);
}

TEST(RayOffset, ShadowRaysSeeTheFarSideOnly) {
    Scene s = sphere_scene();
    SceneAccel accel(s, s.render.lighting);
    const TriangleMesh& fine = s.objects[0].fine;
    int blocked_short = 0, blocked_long = 0;
    for (uint32_t t = 0; t < fine.triangle_count(); t += 11) {
        SurfacePoint sp = surface_point(fine, t, 0.3f, 0.3f);
        Vec3 d = -normalize(sp.p);                       // straight through the centre
        blocked_short += accel.occluded(sp.p, d, 1.0f);  // stops at the centre: free
        blocked_long += accel.occluded(sp.p, d, 3.0f);   // crosses the far side: blocked
    }
    EXPECT_EQ(blocked_short, 0);
    EXPECT_EQ(blocked_long, static_cast<int>((fine.triangle_count() + 10) / 11));
}

TEST(RayOffset, PacketTraceMatchesOneRayAtATime) {
    // The gather traces its hemisphere in packets of 16 (trace_many); every ray must find the
    // same surface at the same distance as trace() finds for it alone, including the rays that
    // need the offset probe (from inside the sphere, where the coarse chords lie within delta).
    Scene s = sphere_scene();
    SceneAccel accel(s, s.render.lighting);
    const TriangleMesh& fine = s.objects[0].fine;
    int rays = 0, mismatches = 0;
    for (uint32_t t = 0; t < fine.triangle_count(); t += 13) {
        SurfacePoint sp = surface_point(fine, t, 0.25f, 0.25f);
        for (float side : {-1.0f, 1.0f}) {
            Frame f(normalize(sp.p) * side);
            RandomStream rng(5, t);
            std::vector<Vec3> dirs;
            for (uint64_t k = 0; k < 37; ++k)  // not a multiple of 16: a partial last packet
                dirs.push_back(f.to_world(cosine_hemisphere(rng.get(k, 0), rng.get(k, 1))));
            std::vector<Hit> hits(dirs.size());
            accel.trace_many(sp.p, dirs, hits);
            for (size_t k = 0; k < dirs.size(); ++k) {
                Hit one = accel.trace(sp.p, dirs[k]);
                ++rays;
                bool same =
                    one.valid() == hits[k].valid() && (!one.valid() || (one.object == hits[k].object && one.prim == hits[k].prim &&
                                                                        std::abs(one.t - hits[k].t) <= 1e-5f * std::max(1.0f, one.t)));
                mismatches += !same;
            }
        }
    }
    ASSERT_GT(rays, 2000);
    EXPECT_EQ(mismatches, 0);
}

}  // namespace
}  // namespace bounce
