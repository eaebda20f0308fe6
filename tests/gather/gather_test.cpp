// The hemisphere gather against closed forms: open plane, floor beside an infinite wall,
// the inside of a uniformly lit sphere (white furnace), convergence rates, and radiosity
// textures converging to shadow-ray shading.
#include <gtest/gtest.h>

#include <thread>

#include "bounce/gather/gather.h"
#include "bounce/radiosity/radiosity.h"
#include "test_util.h"

namespace bounce {
namespace {

using nlohmann::json;

/// Everything a gather needs, built from one scene.
struct Rig {
    Scene scene;
    SceneAccel accel;
    Materials materials;
    DirectLighting lighting;
    std::unique_ptr<RadiosityTextures> radiosity;
    Stats stats;
    explicit Rig(Scene s, bool with_radiosity = false, RadiositySettings rs = {})
        : scene(std::move(s)), accel(scene, scene.render.lighting), materials(scene), lighting(scene, accel, scene.render.lighting) {
        if (with_radiosity)
            radiosity = std::make_unique<RadiosityTextures>(RadiosityTextures::bake(scene, materials, lighting, rs, stats, nullptr));
    }
    GatherResult gather(const Vec3& p, const Vec3& n, GatherSettings gs, uint64_t key = 7) {
        Gatherer g(scene, accel, materials, lighting, radiosity.get(), gs);
        Counters c;
        return g.gather(p, n, RandomStream(1, key), c);
    }
};

json floor_and_wall(float d) {
    json j = test::base_scene();
    const float big = 1e4f;
    j["objects"].push_back({{"type", "quad"}, {"vertices", {{d, -big, -big}, {d, big, -big}, {d, big, big}, {d, -big, big}}}});
    return j;
}

TEST(Gather, GridIsCosineStratifiedWithNAboutPiM) {
    GatherGrid g = gather_grid(512);
    EXPECT_EQ(g.m, 13);
    EXPECT_EQ(g.n, 39);
    EXPECT_EQ(gather_grid(1).rays(), 1);
}

TEST(Gather, OpenPlaneIsUnoccluded) {
    Rig rig(test::scene_from(test::base_scene()));
    GatherSettings gs;
    gs.ao_distance = 0;  // unlimited
    GatherResult r = rig.gather({0, 0, 0}, {0, 1, 0}, gs);
    EXPECT_EQ(r.ao, 1.0f);
    EXPECT_EQ(r.irradiance, Color(0));  // no lights, no sky
    EXPECT_EQ(r.harmonic_distance, INFINITY);
    // Cosine-weighted mean direction of the full hemisphere is the normal.
    EXPECT_GT(r.bent_normal.y, 0.9995f);
}

/// Cosine-weighted directions project uniformly onto the unit disk (x, z) (y = normal): the
/// AO beside a wall at x = d with occlusion distance D is 1 - (fraction of the disk with
/// x > d/D). The bent normal is the mean of the unoccluded directions, by quadrature.
struct WallClosedForm {
    float ao;
    Vec3 bent;
};
WallClosedForm wall_closed_form(float a) {
    float ao = 1 - (std::acos(a) - a * std::sqrt(1 - a * a)) / kPi;
    double sx = 0, sy = 0;
    const int n = 2000;
    for (int i = 0; i < n; ++i)
        for (int k = 0; k < n; ++k) {
            double x = -1 + 2 * (i + 0.5) / n, z = -1 + 2 * (k + 0.5) / n, r2 = x * x + z * z;
            if (r2 >= 1 || x > a) continue;
            sx += x, sy += std::sqrt(1 - r2);
        }
    return {ao, normalize(Vec3(static_cast<float>(sx), static_cast<float>(sy), 0))};
}

TEST(Gather, FloorBesideAnInfiniteWallMatchesTheClosedForm) {
    const float d = 0.7f;
    Rig rig(test::scene_from(floor_and_wall(d)));
    for (float D : {0.0f, 2 * d, 1.25f * d}) {
        GatherSettings gs;
        gs.rays = 2048;
        gs.ao_distance = D;
        float a = D > 0 ? d / D : 0;
        WallClosedForm cf = wall_closed_form(a);
        double ao = 0;
        Vec3 bent(0);
        const int runs = 8;
        for (int s = 0; s < runs; ++s) {
            GatherResult r = rig.gather({0, 0, 0}, {0, 1, 0}, gs, static_cast<uint64_t>(s));
            ao += r.ao / runs;
            bent += r.bent_normal;
        }
        // Stratified: only cells on the occlusion boundary (~2 sqrt(S) of S) are uncertain,
        // each by at most 1/S: the mean of 8 runs is well within 0.005.
        EXPECT_NEAR(ao, cf.ao, 0.005) << "D = " << D;
        bent = normalize(bent);
        EXPECT_GT(dot(bent, cf.bent), std::cos(0.5f * kPi / 180)) << "D = " << D;  // within 0.5 degree
    }
}

TEST(Gather, HitsNearerThanNearDoNotSizeTheRecordButStillShadeIt) {
    // Beside a low wall (height h at distance d) every hit is at least d away: a near distance
    // under d changes nothing; one above it leaves the light alone but lifts d_min past it and
    // flattens the translational gradient of the wall's top edge.
    const float d = 0.7f, h = 0.3f, big = 1e4f;
    json j = test::base_scene();
    j["objects"].push_back({{"type", "quad"}, {"vertices", {{d, 0, -big}, {d, h, -big}, {d, h, big}, {d, 0, big}}}});
    Rig rig(test::scene_from(j));
    GatherSettings gs;
    gs.rays = 1024;
    gs.ao_distance = 0;
    Gatherer g(rig.scene, rig.accel, rig.materials, rig.lighting, nullptr, gs);
    auto at = [&](float near) {
        Counters c;
        return g.gather({0, 0, 0}, {0, 1, 0}, RandomStream(1, 5), c, near);
    };
    const GatherResult plain = at(0), under = at(0.5f * d), over = at(3 * d);
    EXPECT_NEAR(plain.min_distance, d, 0.02f * d);
    EXPECT_EQ(under.min_distance, plain.min_distance);
    EXPECT_EQ(under.ao_grad_trans, plain.ao_grad_trans);
    EXPECT_EQ(over.ao, plain.ao);
    EXPECT_EQ(over.bent_normal, plain.bent_normal);
    EXPECT_GE(over.min_distance, 3 * d);
    EXPECT_LT(length(over.ao_grad_trans), 0.5f * length(plain.ao_grad_trans));
    EXPECT_GT(length(plain.ao_grad_trans), 0.0f);
}

Scene lit_sphere_interior(float albedo, float intensity, int level) {
    json j = test::base_scene();
    j["materials"] = {{"m", {{"color", albedo}}}};
    j["objects"] = {{{"type", "sphere"}, {"radius", 1.0}, {"subdivisions", level}, {"fine_subdivisions", 0}, {"material", "m"}}};
    j["lights"] = {{{"type", "point"}, {"position", {0, 0, 0}}, {"color", intensity}}};
    return test::scene_from(j);
}

TEST(Gather, InsideAUniformlyLitSphereOneBounceIsAlbedoTimesDirect) {
    // A point light at the centre of a sphere of radius R gives every wall point E_d = I/R^2;
    // the wall's radiance is rho E_d / pi everywhere, so the one-bounce irradiance at any wall
    // point is pi * that = rho I / R^2. The hit distances from a wall point are 2R cos(theta):
    // their harmonic mean over cosine-weighted directions is exactly R.
    const float rho = 0.6f, I = 2.0f;
    Scene s = lit_sphere_interior(rho, I, 5);
    for (bool textures : {false, true}) {
        RadiositySettings rs;
        rs.texel = 0.02f;
        Rig rig(lit_sphere_interior(rho, I, 5), textures, rs);
        const TriangleMesh& m = rig.scene.objects[0].coarse;
        GatherSettings gs;
        gs.rays = 1024;
        for (uint32_t t : {0u, 777u, 5000u}) {
            SurfacePoint sp = surface_point(m, t, 0.3f, 0.3f);
            Vec3 n = -normalize(sp.p);
            GatherResult r = rig.gather(sp.p, n, gs, t);
            // The level-5 icosphere's chords sit up to 0.1% inside the sphere: E_d varies by
            // ~0.3%; tolerance 1%.
            EXPECT_NEAR(r.irradiance.x, rho * I, 0.01f * rho * I) << (textures ? "textures" : "shadow rays");
            // 1/r ~ 1/cos(theta) has infinite variance at the horizon: a finite grid usually
            // under-counts that tail, so the harmonic mean comes out a few percent long.
            EXPECT_NEAR(r.harmonic_distance, 1.0f, 0.08f);
            EXPECT_EQ(r.ao, 0.0f);  // closed: every ray occluded (ao_distance unlimited below)
            // Rays beyond 80 degrees at both ends are left out; facet normals of the coarse
            // sphere differ from the true ones by up to ~2 degrees.
            float lo = 2 * std::cos(82 * kPi / 180);
            EXPECT_GE(r.min_distance, lo);
            EXPECT_LE(r.min_distance, 2 * std::cos(75 * kPi / 180));
        }
    }
    (void)s;
}

TEST(Gather, ErrorFallsAtLeastLikeOneOverSqrtN) {
    // A floor point in the Cornell box: light arrives from walls, blocks and the lit floor.
    Rig rig(load_scene(test::cornell_scene()), true);
    Vec3 p{400, 0, 150}, n{0, 1, 0};
    GatherSettings ref;
    ref.rays = 65536;
    Color exact = rig.gather(p, n, ref, 999).irradiance;
    auto rms = [&](int rays) {
        GatherSettings gs;
        gs.rays = rays;
        double e2 = 0;
        const int runs = 48;
        for (int s = 0; s < runs; ++s) {
            double d = rig.gather(p, n, gs, static_cast<uint64_t>(s)).irradiance.y - exact.y;
            e2 += d * d;
        }
        return std::sqrt(e2 / runs);
    };
    double e64 = rms(64), e256 = rms(256), e1024 = rms(1024);
    EXPECT_GT(e64 / e256, 1.7);
    EXPECT_GT(e256 / e1024, 1.7);
    EXPECT_LT(e1024 / exact.y, 0.05);
}

/// A 4 x 4 floor of albedo 0.5 under a point light: the radiosity tests' scene.
json floor_under_a_point_light() {
    json j = test::base_scene();
    j["objects"] = test::floor_objects(2.0f);
    j["materials"] = {{"m", {{"color", 0.5}}}};
    j["objects"][0]["material"] = "m";
    j["lights"] = {{{"type", "point"}, {"position", {0.3, 0.8, -0.2}}, {"color", 1}}};
    return j;
}

/// The floor's baked radiosity against shadow-ray shading (albedo E / pi), mean absolute
/// difference over points inside every triangle.
double lattice_error(const Rig& rig) {
    const TriangleMesh& m = rig.scene.objects[0].coarse;
    double err = 0;
    int count = 0;
    for (uint32_t t = 0; t < m.triangle_count(); ++t)
        for (int i = 1; i < 20; ++i)
            for (int k = 1; i + k < 20; ++k) {
                const float u = static_cast<float>(i) / 20, v = static_cast<float>(k) / 20;
                const SurfacePoint sp = surface_point(m, t, u, v);
                Counters c;
                const Color exact = Color(0.5f) * rig.lighting.irradiance(sp.p, {0, 1, 0}, 0, RandomStream(0, 0), 1, c) * kInvPi;
                err += std::abs(rig.radiosity->object(0).lookup(t, u, v, sp.ng.y > 0).x - exact.x);
                ++count;
            }
    return err / count;
}

TEST(Radiosity, TexturesConvergeToShadowRayShading) {
    // The baked radiosity, interpolated linearly on the lattice, approaches albedo E / pi like
    // h^2 as the lattice spacing h halves.
    const json j = floor_under_a_point_light();
    double prev = 0;
    for (float h : {0.4f, 0.2f, 0.1f, 0.05f}) {
        RadiositySettings rs;
        rs.texel = h;
        const double err = lattice_error(Rig(test::scene_from(j), true, rs));
        if (prev > 0) {
            EXPECT_LT(err, prev / 2.5) << "h = " << h;  // second order: ~4x per halving
        }
        prev = err;
    }
    EXPECT_LT(prev, 2e-4);
}

TEST(Radiosity, DefaultLatticesFollowTheTexelOnLargeTriangles) {
    // The floor is most of the scene: its triangles are ~128 auto texels long. Their lattices
    // must be that fine (a cap of 32 left them 4x coarser, and the light they bake 10x further
    // from shadow-ray shading).
    const Rig rig(test::scene_from(floor_under_a_point_light()), true);
    const TriangleMesh& m = rig.scene.objects[0].coarse;
    const float texel = rig.scene.size() / 128.0f;
    for (uint32_t t = 0; t < m.triangle_count(); ++t) {
        const auto [a, b, c] = triangle_vertices(m, nullptr, t);
        const float longest = std::max({length(b - a), length(c - b), length(a - c)});
        EXPECT_EQ(rig.radiosity->object(0).level[t], radiosity_level(longest, texel, 255));
        EXPECT_GT(rig.radiosity->object(0).level[t], 100);
    }
    EXPECT_LT(lattice_error(rig), 2e-4);  // the convergence test's finest lattice (h = 0.05) reaches this
}

TEST(Radiosity, SaveAndLoadRoundTripAndRefuseOtherLights) {
    test::TempDir d;
    Scene s = load_scene(test::cornell_scene());
    Rig rig(load_scene(test::cornell_scene()), true);
    rig.radiosity->save(d.file("rt"));
    RadiosityTextures back;
    std::string why;
    ASSERT_TRUE(RadiosityTextures::load(d.file("rt"), s, RadiositySettings{}, rig.materials, rig.lighting, back, why)) << why;
    EXPECT_EQ(back.baked_sides(), back.sides());
    for (uint32_t o = 0; o < s.objects.size(); ++o) {
        EXPECT_TRUE(back.object(o).front == rig.radiosity->object(o).front);
        EXPECT_TRUE(back.object(o).back == rig.radiosity->object(o).back);
    }
    Scene brighter = load_scene(test::cornell_scene(), {"materials.light.emission=[20,12,4]"});
    EXPECT_FALSE(RadiosityTextures::load(d.file("rt"), brighter, RadiositySettings{}, rig.materials, rig.lighting, back, why));
    EXPECT_NE(why.find("baked for other"), std::string::npos);
}

TEST(Radiosity, LazyBakesEqualTheEagerBakeInAnyOrderAndPartialSavesResume) {
    Rig rig(load_scene(test::cornell_scene()), true);
    RadiosityTextures lazy = RadiosityTextures::lazy(rig.scene, rig.materials, rig.lighting, RadiositySettings{});
    EXPECT_EQ(lazy.baked_sides(), 0u);
    // Look up the sides of object 0 backwards, from two threads, then compare with the eager bake.
    const RadiosityMap& eager = rig.radiosity->object(0);
    const auto tris = static_cast<uint32_t>(eager.level.size());
    Counters c1, c2;
    std::thread other([&] {
        for (uint32_t t = tris; t-- > 0;) lazy.lookup(0, t, 0.2f, 0.3f, t % 2 == 0, c2);
    });
    for (uint32_t t = 0; t < tris; ++t) lazy.lookup(0, t, 0.2f, 0.3f, t % 2 == 0, c1);
    other.join();
    EXPECT_EQ(lazy.baked_sides(), static_cast<size_t>(tris));  // one side of each triangle
    for (uint32_t t = 0; t < tris; ++t) {
        const bool front = t % 2 == 0;
        for (uint32_t k = eager.offset[t]; k < eager.offset[t] + (eager.level[t] + 1u) * (eager.level[t] + 2u) / 2; ++k)
            ASSERT_EQ(front ? lazy.object(0).front.value(k) : lazy.object(0).back.value(k),
                      front ? eager.front.value(k) : eager.back.value(k));
    }
    // A partial save loads as partial; the rest bakes on demand to the same values.
    test::TempDir d;
    lazy.save(d.file("rt"));
    RadiosityTextures back;
    std::string why;
    ASSERT_TRUE(RadiosityTextures::load(d.file("rt"), rig.scene, RadiositySettings{}, rig.materials, rig.lighting, back, why)) << why;
    EXPECT_EQ(back.baked_sides(), static_cast<size_t>(tris));
    Counters c3;
    for (uint32_t t = 0; t < tris; ++t)
        EXPECT_EQ(back.lookup(0, t, 0.25f, 0.25f, t % 2 != 0, c3), rig.radiosity->lookup(0, t, 0.25f, 0.25f, t % 2 != 0, c3));
    // A gather through lazy textures is the gather through baked ones.
    RadiosityTextures lazy2 = RadiosityTextures::lazy(rig.scene, rig.materials, rig.lighting, RadiositySettings{});
    GatherSettings gs;
    gs.rays = 256;
    Gatherer with_lazy(rig.scene, rig.accel, rig.materials, rig.lighting, &lazy2, gs);
    Gatherer with_baked(rig.scene, rig.accel, rig.materials, rig.lighting, rig.radiosity.get(), gs);
    Counters c4;
    GatherResult a = with_lazy.gather({0, 0.5f, 0}, {0, 1, 0}, RandomStream(3, 9), c4);
    GatherResult b = with_baked.gather({0, 0.5f, 0}, {0, 1, 0}, RandomStream(3, 9), c4);
    EXPECT_EQ(a.irradiance, b.irradiance);
    EXPECT_GT(lazy2.baked_sides(), 0u);
    EXPECT_LT(lazy2.baked_sides(), lazy2.sides());
}

TEST(Radiosity, ABakeSplitInSharesAndExchangedEqualsTheWholeBake) {
    // An MPI job of 3 ranks (RadiosityStep::BakeSplit): each bakes every third triangle, then
    // takes the others' sides; every side is baked once, and the values are the whole bake's.
    Rig rig(load_scene(test::cornell_scene()), true);
    constexpr int kShares = 3;
    std::vector<RadiosityTextures> ranks;
    std::vector<std::string> bytes;
    size_t baked = 0;
    for (int r = 0; r < kShares; ++r) {
        ranks.push_back(RadiosityTextures::lazy(rig.scene, rig.materials, rig.lighting, RadiositySettings{}));
        Stats stats;
        ranks.back().bake_all(stats, nullptr, r, kShares);
        baked += ranks.back().baked_sides();
        EXPECT_GT(ranks.back().baked_sides(), 0u);
        EXPECT_LT(ranks.back().baked_sides(), ranks.back().sides() / 2);
        bytes.push_back(ranks.back().baked_bytes());
    }
    EXPECT_EQ(baked, rig.radiosity->sides());  // no side twice, none left out
    for (int r = 0; r < kShares; ++r) {
        for (int o = 0; o < kShares; ++o)
            if (o != r) ranks[r].take_baked(bytes[o]);
        ASSERT_EQ(ranks[r].baked_sides(), ranks[r].sides());
        for (uint32_t id = 0; id < rig.scene.objects.size(); ++id) {
            EXPECT_EQ(ranks[r].object(id).front, rig.radiosity->object(id).front) << "rank " << r << " object " << id;
            EXPECT_EQ(ranks[r].object(id).back, rig.radiosity->object(id).back) << "rank " << r << " object " << id;
        }
    }
}

}  // namespace
}  // namespace bounce

namespace bounce {
namespace {

TEST(Gather, NoiseEstimateMatchesTheSpreadOfIndependentGathers) {
    Rig rig(load_scene(test::cornell_scene()), true);
    for (bool ao : {false, true}) {
        GatherSettings gs;
        gs.rays = 256;
        gs.ao = ao;
        gs.ao_distance = ao ? 200.0f : 0.0f;
        Gatherer g(rig.scene, rig.accel, rig.materials, rig.lighting, rig.radiosity.get(), gs);
        // A floor point near the tall block: light and occlusion vary across the hemisphere.
        const Vec3 p{300, 0.5f, 300}, n{0, 1, 0};
        double sum = 0, sum2 = 0, est = 0;
        const int trials = 200;
        Counters c;
        for (int i = 0; i < trials; ++i) {
            GatherResult r = g.gather(p, n, RandomStream(11, static_cast<uint64_t>(i)), c);
            const double v = ao ? r.ao : luminance(r.irradiance);
            sum += v;
            sum2 += v * v;
            est += r.rel_stderr;
        }
        const double mean = sum / trials, rel = std::sqrt(std::max(0.0, sum2 / trials - mean * mean)) / mean;
        est /= trials;
        EXPECT_GT(rel, 0.0) << ao;
        // Adjacent-strata differences overestimate a little where the integrand has gradients.
        EXPECT_GT(est, 0.5 * rel) << ao << " estimated " << est << " measured " << rel;
        EXPECT_LT(est, 3.0 * rel) << ao << " estimated " << est << " measured " << rel;
    }
    // A constant sky over an open plane: no variance, none estimated.
    nlohmann::json j = test::base_scene();
    j["lights"] = {{{"type", "sky"}, {"color", 1.0}}};
    Rig open(test::scene_from(j));
    GatherSettings gs;
    gs.rays = 64;
    Gatherer g(open.scene, open.accel, open.materials, open.lighting, nullptr, gs);
    Counters c;
    EXPECT_EQ(g.gather({0, 0.01f, 0}, {0, 1, 0}, RandomStream(1, 2), c).rel_stderr, 0.0f);
}

}  // namespace
}  // namespace bounce

namespace bounce {
namespace {

/// The mean over `runs` streams of a gather at (p, n) and of one at (q, nq) reprojected from it,
/// with the rays the reprojection traced.
struct ReprojectMeans {
    double from = 0, reprojected = 0, rays = 0;
};
ReprojectMeans reproject_means(Rig& rig, int rays, const Vec3& p, const Vec3& n, const Vec3& q, const Vec3& nq, int runs) {
    GatherSettings gs;
    gs.rays = rays;
    Gatherer g(rig.scene, rig.accel, rig.materials, rig.lighting, rig.radiosity.get(), gs);
    ReprojectMeans out;
    for (int s = 0; s < runs; ++s) {
        Counters c;
        GatherHits hits;
        const RandomStream a(3, static_cast<uint64_t>(s)), b(4, static_cast<uint64_t>(s));
        out.from += static_cast<double>(g.gather(p, n, a, c, 0, &hits).irradiance.x) / runs;
        const GatherResult r = g.reproject(q, nq, b, {p, n, a, hits}, c);
        out.reprojected += static_cast<double>(r.irradiance.x) / runs, out.rays += r.rays / static_cast<double>(runs);
    }
    return out;
}

TEST(Reproject, FromItsOwnPointItIsTheGatherItReuses) {
    Rig rig(load_scene(test::cornell_scene()), true);
    const Vec3 p{300, 0, 150}, n{0, 1, 0};
    const ReprojectMeans m = reproject_means(rig, 512, p, n, p, n, 4);
    EXPECT_EQ(m.rays, 0);                               // nothing is nearer than 16 x 0
    EXPECT_NEAR(m.reprojected, m.from, 1e-5 * m.from);  // every hit seen again from where it was seen
    // AO mode: occlusion alone, as a gather gives it (no light shaded at the hits).
    GatherSettings ao;
    ao.rays = 512, ao.ao = true, ao.ao_distance = 200;
    Gatherer g(rig.scene, rig.accel, rig.materials, rig.lighting, nullptr, ao);
    Counters c;
    GatherHits hits;
    const RandomStream a(3, 1);
    const GatherResult own = g.gather(p, n, a, c, 0, &hits);
    const uint64_t shadow_rays = c.shadow_rays;
    const GatherResult r = g.reproject(p, n, a, {p, n, a, hits}, c);
    EXPECT_EQ(r.irradiance, Color(0));
    EXPECT_NEAR(r.ao, own.ao, 1e-5f);
    EXPECT_GT(own.ao, 0.0f);
    EXPECT_LT(own.ao, 1.0f);
    EXPECT_EQ(c.shadow_rays, shadow_rays);
}

TEST(Reproject, InsideAUniformlyLitSphereItKeepsTheClosedForm) {
    // Every wall point of the lit sphere has one-bounce irradiance rho I / R^2 (the test
    // above), and no point hides another: the reweighted hits of a gather up to 0.05 R away
    // estimate it without bias, tracing only the cells nearer than 16 times the move.
    const float rho = 0.6f, I = 2.0f;
    RadiositySettings rs;
    rs.texel = 0.02f;
    Rig rig(lit_sphere_interior(rho, I, 5), true, rs);
    const SurfacePoint a = surface_point(rig.scene.objects[0].coarse, 777, 0.3f, 0.3f);
    for (float d : {0.005f, 0.02f, 0.05f}) {
        const Vec3 q = normalize(a.p + Vec3(d, d / 2, 0)) * length(a.p);
        const ReprojectMeans m = reproject_means(rig, 512, a.p, -normalize(a.p), q, -normalize(q), 64);
        EXPECT_NEAR(m.reprojected, rho * I, 0.003 * rho * I) << "moved " << d;
        EXPECT_GT(m.rays, 0) << "moved " << d;
        EXPECT_LT(m.rays, 0.5 * 512) << "moved " << d;
    }
}

TEST(Reproject, InTheCornellBoxItEstimatesTheNewPointNotTheOld) {
    // Floor points beside the red wall 10 units apart (irradiance 17 % apart), and 5 units apart
    // by the tall block: the reprojection lands within 1.5 % of the new point's converged value.
    Rig rig(load_scene(test::cornell_scene()), true);
    const Vec3 n{0, 1, 0};
    GatherSettings ref;
    ref.rays = 65536;
    for (auto [p, q] : {std::pair{Vec3{530, 0, 300}, Vec3{520, 0, 300}}, std::pair{Vec3{300, 0, 150}, Vec3{296, 0, 153}}}) {
        const double Ep = rig.gather(p, n, ref, 999).irradiance.x, Eq = rig.gather(q, n, ref, 999).irradiance.x;
        const ReprojectMeans m = reproject_means(rig, 1024, p, n, q, n, 128);
        EXPECT_NEAR(m.from, Ep, 0.01 * Ep);
        EXPECT_NEAR(m.reprojected, Eq, 0.015 * Eq);
        EXPECT_LT(m.rays, 1024);
    }
}

}  // namespace
}  // namespace bounce
