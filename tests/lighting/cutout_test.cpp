// Cutout opacity (issue 61): a masked card is the same shape as its opaque parts modelled as
// geometry for the camera, shadows and bounce light; a blended card covers its share of each
// pixel (composited front to back) and lets that share of light through; hostile cutouts are
// refused naming the file and the key.
#include <gtest/gtest.h>

#include <OpenImageIO/imageio.h>

#include <cmath>

#include "bounce/render/render.h"
#include "bounce/scene/mesh_cache.h"
#include "bounce/tool/session.h"
#include "material_scenes.h"
#include "test_util.h"
#include "tool/tool_util.h"

namespace bounce {
namespace {

using nlohmann::json;
using namespace test_scenes;

TEST(Cutouts, AMaskedCardIsItsOpaquePartsModelledAsGeometry) {
    test::TempDir dir;
    // Stripes: opaque where u is in [0, 0.25] and [0.5, 0.75] (bilinear between texel centres
    // crosses the cutoff 0.5 at the texel edges), i.e. x in [-1, -0.5] and [0, 0.5].
    const std::string stripes = dir.file("stripes.png");
    write_grey(stripes, 4, 1, {255, 0, 255, 0});
    json masked = kLeaf;
    masked.update({{"alpha_mode", "mask"}, {"opacity_texture", stripes}});
    const json cut = stage(json::array({quad("card", "leaf", -1, 1, 0.2, 2.2, 0)}), masked);
    const json geometry =
        stage(json::array({quad("card", "leaf", -1, -0.5, 0.2, 2.2, 0), quad("card2", "leaf", 0, 0.5, 0.2, 2.2, 0)}), kLeaf);
    // Without radiosity textures a gather hit is lit by shadow rays: the lattice of a card of two
    // triangles is not the lattice of two cards of two, and would differ within noise.
    for (const std::string gi : {"none", "brute"}) {
        const Image a = render_with(cut, gi, {Override("render.radiosity=false")});
        const Image b = render_with(geometry, gi, {Override("render.radiosity=false")});
        const Layer *la = a.find("beauty"), *lb = b.find("beauty");
        ASSERT_TRUE(la && lb);
        size_t differ = 0, leaf = 0, through = 0;
        double sa = 0, sb = 0;
        for (size_t i = 0; i < la->data.size(); ++i) {
            sa += la->data[i], sb += lb->data[i];
            differ += std::abs(la->data[i] - lb->data[i]) > 1e-4f * (1 + std::abs(lb->data[i]));
        }
        const Layer* albedo = a.find("albedo");
        for (int y = 0; y < a.height; ++y)
            for (int x = 0; x < a.width; ++x) {
                const float* c = a.at(*albedo, x, y);
                leaf += c[1] > 0.55f && c[0] < 0.25f;
                through += y > 8 && y < 24 && x > 12 && x < 36 && c[0] > 0.65f;  // the wall between the stripes
            }
        // The same pixels, shadows and bounce light: equal where the same rays are traced (the
        // stripes' edges are the quads' edges only to float rounding).
        EXPECT_LE(differ, la->data.size() / 100) << "--gi " << gi;
        EXPECT_NEAR(sa / sb, 1.0, 2e-3) << "--gi " << gi;
        EXPECT_GT(leaf, 60u) << "--gi " << gi;
        EXPECT_GT(through, 60u) << "--gi " << gi;
    }
}

TEST(Cutouts, ABlendedCardCoversItsShareOfEachPixelAndLetsTheRestOfTheLightThrough) {
    const json card = json::array({quad("card", "leaf", -1, 1, 0.2, 2.2, 0)});
    const Image opaque = render_with(stage(card, kLeaf), "none");
    const Image none = render_with(stage(json::array(), kLeaf), "none");
    const Layer *ao = opaque.find("albedo"), *an = none.find("albedo");
    for (const float alpha : {0.25f, 0.5f, 0.75f}) {
        json blend = kLeaf;
        blend.update({{"opacity", alpha}});  // alpha_mode blend when only an opacity is given
        const Image img = render_with(stage(card, blend), "none", {Override("render.light_samples=64")});
        const Layer* a = img.find("albedo");
        ASSERT_TRUE(a && ao && an);
        // Coverage composited front to back: alpha of the card over what is behind it, per pixel.
        double worst = 0;
        for (size_t i = 0; i < a->data.size(); ++i)
            worst = std::max(worst, static_cast<double>(std::abs(a->data[i] - (alpha * ao->data[i] + (1 - alpha) * an->data[i]))));
        EXPECT_LT(worst, 1e-5) << alpha;
        // The card's shadow on the floor lets 1 - alpha of the light through (shadow rays stop
        // with probability alpha): its mean over the pixels the opaque card darkens.
        const Layer *d = img.find("direct"), *dop = opaque.find("direct"), *dn = none.find("direct");
        double lit = 0, open = 0, shut = 0;
        size_t n = 0;
        for (int y = 0; y < img.height; ++y)
            for (int x = 0; x < img.width; ++x) {
                const float *c = img.at(*d, x, y), *co = opaque.at(*dop, x, y), *cn = none.at(*dn, x, y);
                const float* alb_o = opaque.at(*ao, x, y);
                // Floor pixels (white in both) that the opaque card shadows.
                if (!(alb_o[0] > 0.65f && cn[1] > 0 && co[1] < 0.05f * cn[1])) continue;
                lit += c[1], open += cn[1], shut += co[1];
                ++n;
            }
        ASSERT_GT(n, 20u);
        EXPECT_NEAR(lit / open, (1 - alpha) + alpha * shut / open, 0.04) << alpha;
    }
}

TEST(Cutouts, AGltfMaskOrBlendIsTheSameCutoutWrittenInTheSceneFile) {
    test::TempDir dir;
    // White stripes, their alpha the mask test's stripes.
    const std::string leaf = dir.file("leaf.png");
    write_png(leaf, 4, 1, 4, {255, 255, 255, 255, 255, 255, 255, 0, 255, 255, 255, 255, 255, 255, 255, 0});
    for (const std::string mode : {"MASK", "BLEND"}) {
        json m = {
            {"pbrMetallicRoughness",
             {{"baseColorTexture", {{"index", 0}}}, {"baseColorFactor", {1, 1, 1, 0.8}}, {"metallicFactor", 0}, {"roughnessFactor", 1}}},
            {"alphaMode", mode}};
        if (mode == "MASK") m["alphaCutoff"] = 0.7;
        const std::string file = gltf_card(dir, m);
        json from_file = stage(json::array({{{"name", "card"}, {"type", "mesh"}, {"file", file}}}), kLeaf);
        json same = {{"color", 1},
                     {"color_texture", leaf},
                     {"specular", 0.04},
                     {"roughness", 1},
                     {"opacity", 0.8},
                     {"alpha_mode", mode == "MASK" ? "mask" : "blend"},
                     {"opacity_texture", leaf}};
        if (mode == "MASK") same["alpha_cutoff"] = 0.7;
        const json written = stage(json::array({quad("card", "leaf", -1, 1, 0.2, 2.2, 0)}), same);
        const Image a = render_with(from_file, "brute"), b = render_with(written, "brute");
        EXPECT_EQ(test::differing_values(a, b), 0u) << mode;
        // Not vacuous: the card is seen (the colour texture, filtered over the pixel, is not the
        // wall's grey 0.7).
        const Layer* albedo = a.find("albedo");
        size_t card = 0;
        for (int y = 0; y < a.height; ++y)
            for (int x = 0; x < a.width; ++x) card += std::abs(a.at(*albedo, x, y)[0] - 0.7f) > 0.01f;
        EXPECT_GT(card, 30u) << mode;
    }
}

TEST(Cutouts, AnMtlsDissolveAndMapDAreBlendedOpacity) {
    test::TempDir dir;
    const std::string stripes = dir.file("stripes.png");
    write_grey(stripes, 4, 1, {255, 0, 255, 0});
    // The stage's card as an OBJ quad (u along x, v along y), MTL's d = 1 - Tr and map_d.
    const std::string obj = dir.write("card.obj",
                                      "mtllib card.mtl\nv -1 0.2 0\nv 1 0.2 0\nv 1 2.2 0\nv -1 2.2 0\n"
                                      "vt 0 0\nvt 1 0\nvt 1 1\nvt 0 1\nusemtl leaf\nf 1/1 2/2 3/3 4/4\n");
    for (const std::string dissolve : {"d 0.6", "Tr 0.4"}) {
        dir.write("card.mtl", "newmtl leaf\nKd 0.2 0.6 0.1\n" + dissolve + "\nmap_d stripes.png\n");
        const json from_file = stage(json::array({{{"name", "card"}, {"type", "mesh"}, {"file", obj}}}), kLeaf);
        json same = kLeaf;
        same.update({{"opacity", 0.6}, {"opacity_texture", stripes}});
        const json written = stage(json::array({quad("card", "leaf", -1, 1, 0.2, 2.2, 0)}), same);
        const Image a = render_with(from_file, "none"), b = render_with(written, "none");
        // Coverage is exact; shading only to the normals' rounding (Assimp's from the face).
        const Layer *la = a.find("albedo"), *lb = b.find("albedo");
        size_t card = 0;
        for (size_t i = 0; i < la->data.size(); ++i) {
            EXPECT_NEAR(la->data[i], lb->data[i], 1e-6f) << dissolve << " value " << i;
            card += std::abs(la->data[i] - 0.7f) > 0.01f;
        }
        EXPECT_GT(card, 60u) << dissolve;
    }
}

TEST(Cutouts, SurviveInstancingAndTheMeshCache) {
    test::TempDir dir;
    const std::string leaf = dir.file("leaf.png");
    write_png(leaf, 4, 1, 4, {255, 255, 255, 255, 255, 255, 255, 0, 255, 255, 255, 255, 255, 255, 255, 0});
    json masked = kLeaf;
    masked.update({{"alpha_mode", "mask"}, {"opacity_texture", leaf}});
    // Placements that round nothing (identity, mirrors) render as the flat scene bit for bit.
    const json transforms = json::array({json::object(), {{"scale", {-1, 1, 1}}}, {{"scale", {-1, 1, -1}}}});
    json proto = quad("card", "leaf", 0.2, 1.6, 0.2, 2.2, 0.5);
    proto["prototype"] = true;
    json instanced = stage(json::array({proto, {{"name", "cards"}, {"instances", {{"of", "card"}, {"transforms", transforms}}}}}), masked);
    json flat = stage(json::array({proto}), masked);  // the prototype is an object of both, unseen
    for (size_t k = 0; k < transforms.size(); ++k) {
        json o = quad("cards/" + std::to_string(k), "leaf", 0.2, 1.6, 0.2, 2.2, 0.5);
        o["transform"] = transforms[k];
        flat["objects"].push_back(o);
    }
    for (const std::string gi : {"none", "brute"})
        EXPECT_EQ(test::differing_values(render_with(instanced, gi), render_with(flat, gi)), 0u) << "--gi " << gi;
    // A glTF card read once, then from the mesh cache: the same cutout.
    json m = {{"pbrMetallicRoughness", {{"baseColorTexture", {{"index", 0}}}, {"metallicFactor", 0}}}, {"alphaMode", "MASK"}};
    const json from_file = stage(json::array({{{"name", "card"}, {"type", "mesh"}, {"file", gltf_card(dir, m)}}}), kLeaf);
    const Image parsed = render_with(from_file, "none");
    setenv("BOUNCE_MESH_CACHE", dir.file("meshes").c_str(), 1);
    const MeshCacheCounts before = mesh_cache_counts();
    const Image stored = render_with(from_file, "none"), cached = render_with(from_file, "none");
    unsetenv("BOUNCE_MESH_CACHE");
    EXPECT_EQ(mesh_cache_counts().hits, before.hits + 1);
    EXPECT_EQ(test::differing_values(parsed, stored), 0u);
    EXPECT_EQ(test::differing_values(parsed, cached), 0u);
}

// Item 4: what a file's materials carry that bounce does not read is named once per file.
TEST(UnreadMaterials, EveryUnreadFeatureIsNamedOnStderrOncePerFile) {
    test::TempDir dir;
    write_png(dir.file("leaf.png"), 4, 1, 4, {255, 255, 255, 255, 255, 255, 255, 0, 255, 255, 255, 255, 255, 255, 255, 0});
    const json tex = {{"index", 0}};
    json m = {{"pbrMetallicRoughness",
               {{"baseColorTexture", {{"index", 0}, {"extensions", {{"KHR_texture_transform", {{"scale", {2, 2}}}}}}}},
                {"metallicRoughnessTexture", tex}}},
              {"emissiveTexture", tex},
              {"occlusionTexture", {{"index", 0}, {"texCoord", 1}}},
              {"extensions", {{"KHR_materials_clearcoat", {{"clearcoatFactor", 1}}}}}};
    const std::string file = gltf_card(dir, m);
    json g = json::parse(test::bytes_of(file));
    g["materials"].push_back(g["materials"][0]);  // two materials carry them
    g["extensionsUsed"] = {"KHR_materials_clearcoat", "KHR_texture_transform", "KHR_materials_variants"};
    dir.write("card.gltf", g.dump());
    // The same file twice (two objects) is named once.
    json scene = stage(json::array({{{"name", "card"}, {"type", "mesh"}, {"file", file}},
                                    {{"name", "again"}, {"type", "mesh"}, {"file", file}, {"transform", {{"translate", {0, 0, 1}}}}}}),
                       kLeaf);
    const std::string path = dir.write("scene.json", scene.dump());
    std::string err;
    ASSERT_EQ(test::run_bounce("render " + path + " -o " + dir.file("out.exr"), &err), 0) << err;
    // The base colour's transform and uv set are read; the textures on another set or without its
    // transform are not read, and named.
    for (const std::string want :
         {"metallicRoughnessTexture on another uv set or transform than the material's first texture on 2 materials",
          "emissiveTexture on another uv set or transform than the material's first texture on 2 materials",
          "occlusionTexture on another uv set or transform than the material's first texture on 2 materials",
          "KHR_materials_clearcoat on 2 materials", "KHR_materials_variants on 1 file"}) {
        const std::string line = "card.gltf: ignored: " + want;
        const size_t at = err.find(line);
        EXPECT_NE(at, std::string::npos) << line << " in:\n" << err;
        EXPECT_EQ(err.find(line, at + 1), std::string::npos) << line << " twice";
    }
    // bounce info: per material, what was read and what was not.
    ASSERT_EQ(test::run_bounce_shell(std::string(BOUNCE_BINARY) + " info " + path + " > " + dir.file("info.txt"), &err), 0) << err;
    const std::string info = test::bytes_of(dir.file("info.txt"));
    // (glTF's default metallic factor is 1: without its texture, a black diffuse.)
    EXPECT_NE(info.find("material card/0: colour 0 x leaf.png; specular 1, roughness 1; uv transform scale 2 2; not read: "
                        "metallicRoughnessTexture on another uv set or transform than the material's first texture, "
                        "emissiveTexture on another uv set or transform than the material's first texture, "
                        "occlusionTexture on another uv set or transform than the material's first texture, KHR_materials_clearcoat\n"),
              std::string::npos)
        << info;
    EXPECT_NE(info.find("material again/1:"), std::string::npos) << info;
    EXPECT_NE(info.find("card.gltf: ignored: KHR_materials_variants on 1 file"), std::string::npos) << info;
    // An MTL's statements bounce does not read, once per material that has them.
    dir.write("card.mtl",
              "newmtl a\nKd 0.5 0.5 0.5\nKa 1 1 1\nillum 2\nmap_Ks s.png\nNi 1.5\nd 0.5\nnewmtl b\nNi 1.4\nillum 7\nPr 0.3\n"
              "newmtl c\nNi 1.5\nillum 2\n");  // c's Ni (opaque) means nothing
    const std::string obj = dir.write("card.obj", "mtllib card.mtl\nv -1 0.2 0\nv 1 0.2 0\nv 1 2.2 0\nusemtl a\nf 1 2 3\n");
    scene = stage(json::array({{{"name", "card"}, {"type", "mesh"}, {"file", obj}}}), kLeaf);
    ASSERT_EQ(test::run_bounce("render " + dir.write("obj.json", scene.dump()) + " -o " + dir.file("obj.exr"), &err), 0) << err;
    for (const std::string want : {"MTL map_Ks on 1 material", "MTL Ni on 2 materials", "MTL Pr on 1 material"})
        EXPECT_NE(err.find("card.obj: ignored: " + want), std::string::npos) << want << " in:\n" << err;
    EXPECT_EQ(err.find("MTL Ka"), std::string::npos) << err;  // ambient colour means nothing here: not named
    // The lighting tool's status carries them (the page shows them).
    SessionOptions o;
    o.scene = dir.file("obj.json"), o.out_dir = dir.file("tool");
    LightingSession session(o);
    const json unread = session.status()["unread"];
    ASSERT_TRUE(unread.is_array());
    EXPECT_NE(std::find(unread.begin(), unread.end(), obj + ": ignored: MTL Ni on 2 materials"), unread.end()) << unread.dump();
}

// Item 2: glTF's occlusionTexture is baked occlusion, as the scene file's ao_texture.
TEST(GltfMaterials, AnOcclusionTextureIsTheSceneFilesAoTexture) {
    test::TempDir dir;
    write_png(dir.file("leaf.png"), 4, 1, 4, std::vector<unsigned char>(16, 255));
    const std::string ao = dir.file("ao.png");
    write_grey(ao, 4, 1, {40, 255, 120, 200});
    json m = {{"pbrMetallicRoughness", {{"baseColorTexture", {{"index", 0}}}, {"metallicFactor", 0}, {"roughnessFactor", 1}}},
              {"occlusionTexture", {{"index", 1}}}};
    const std::string file = gltf_card(dir, m);
    json g = json::parse(test::bytes_of(file));
    g["images"].push_back({{"uri", "ao.png"}});
    g["textures"].push_back({{"source", 1}});
    dir.write("card.gltf", g.dump());
    const json from_file = stage(json::array({{{"name", "card"}, {"type", "mesh"}, {"file", file}}}), kLeaf);
    const json same = {{"color", 1}, {"color_texture", dir.file("leaf.png")}, {"specular", 0.04}, {"roughness", 1}, {"ao_texture", ao}};
    const json written = stage(json::array({quad("card", "leaf", -1, 1, 0.2, 2.2, 0)}), same);
    const Image a = render_with(from_file, "brute"), b = render_with(written, "brute");
    EXPECT_EQ(test::differing_values(a, b), 0u);
    // Not vacuous: without it the card's indirect light is brighter.
    json plain = same;
    plain.erase("ao_texture");
    const Image c = render_with(stage(json::array({quad("card", "leaf", -1, 1, 0.2, 2.2, 0)}), plain), "brute");
    const Layer *ia = a.find("indirect"), *ic = c.find("indirect");
    double sa = 0, sc = 0;
    for (size_t i = 0; i < ia->data.size(); ++i) sa += ia->data[i], sc += ic->data[i];
    EXPECT_LT(sa, 0.98 * sc);
}

// A lighter's opacity edit changes what the camera sees: the tool asks for a new deep file, and
// its frame is the scene rendered with that opacity.
TEST(Cutouts, AnOpacityEditInTheLightingToolRendersAsTheSceneWithThatOpacity) {
    test::TempDir dir;
    json blend = kLeaf;
    blend.update({{"opacity", 0.6}});
    const json card = json::array({quad("card", "leaf", -1, 1, 0.2, 2.2, 0)});
    SessionOptions o;
    o.scene = dir.write("scene.json", stage(card, blend).dump());
    o.out_dir = dir.file("tool");
    o.threads = 2;
    o.sets = {"render.gi=\"brute\"", "render.light_parts=false"};
    LightingSession session(o);
    test::render_and_wait(session, SessionAction::Rasterize);
    const json answer = session.edit("materials.leaf.opacity", 0.3);
    EXPECT_EQ(answer["needs"], "rasterize");
    test::render_and_wait(session, SessionAction::Rasterize);
    blend["opacity"] = 0.3;
    const Image want = render_with(stage(card, blend), "brute", {Override("render.light_parts=false")});
    EXPECT_EQ(test::differing_values(session.image(), want), 0u);
    const Image before = render_with(stage(card, kLeaf), "brute");
    EXPECT_GT(test::differing_values(want, before), 100u);  // not vacuous: the card is another card
}

// KHR_materials_emissive_strength multiplies emissiveFactor (Assimp reads it; material_report
// does not name it as unread).
TEST(GltfMaterials, EmissiveStrengthMultipliesTheEmissiveFactor) {
    test::TempDir dir;
    write_png(dir.file("leaf.png"), 4, 1, 4, std::vector<unsigned char>(16, 255));
    json m = {{"emissiveFactor", {1, 0.5, 0.25}}, {"extensions", {{"KHR_materials_emissive_strength", {{"emissiveStrength", 6}}}}}};
    const std::string file = gltf_card(dir, m);
    const Scene s = test::scene_from(stage(json::array({{{"name", "card"}, {"type", "mesh"}, {"file", file}}}), kLeaf));
    const auto it = std::find_if(s.materials.begin(), s.materials.end(), [](const Material& x) { return x.name.starts_with("card/"); });
    ASSERT_NE(it, s.materials.end());
    EXPECT_EQ(it->emission, Color(6, 3, 1.5));
    EXPECT_TRUE(s.unread.empty()) << s.unread.front();
    for (const json& bad : {json(-1), json("bright"), json(1e39)}) {
        m["extensions"]["KHR_materials_emissive_strength"]["emissiveStrength"] = bad;
        const std::string hostile = gltf_card(dir, m);
        test::expect_input_error(
            [&] {
                test::scene_from(stage(json::array({{{"name", "card"}, {"type", "mesh"}, {"file", hostile}}}), kLeaf));
            },
            {"card.gltf", "KHR_materials_emissive_strength", "emissiveStrength"});
    }
}

TEST(Cutouts, HostileCutoutsAreRefusedNamingTheKey) {
    test::TempDir dir;
    const json card = json::array({quad("card", "leaf", -1, 1, 0.2, 2.2, 0)});
    const auto refused = [&](const json& material, const std::vector<std::string>& parts) {
        json m = kLeaf;
        m.update(material);
        test::expect_input_error([&] { test::scene_from(stage(card, m)); }, parts);
    };
    refused({{"alpha_mode", "mask"}, {"alpha_cutoff", 2}}, {"/materials/leaf/alpha_cutoff"});
    refused({{"alpha_mode", "mask"}, {"alpha_cutoff", "NaN"}}, {"/materials/leaf/alpha_cutoff"});
    refused({{"opacity", -0.5}}, {"/materials/leaf/opacity"});
    refused({{"opacity", 1e39}}, {"/materials/leaf/opacity"});
    refused({{"alpha_mode", "opaque"}, {"opacity", 0.5}}, {"/materials/leaf/alpha_mode", "reads no opacity"});
    refused({{"alpha_mode", "blend"}, {"alpha_cutoff", 0.3}}, {"/materials/leaf/alpha_cutoff", "mask"});
    refused({{"alpha_mode", "cutout"}}, {"/materials/leaf/alpha_mode"});
    refused({{"opacity_texture", dir.file("missing.png")}}, {"/materials/leaf/opacity_texture"});
    const std::string huge = write_huge_png(dir);
    refused({{"opacity_texture", huge}}, {"/materials/leaf/opacity_texture", "30000x30000", "8192x8192"});
    const std::string nan = dir.file("nan.exr");
    test::write_constant_image(nan, 2, 2, {NAN});
    refused({{"opacity_texture", nan}}, {"/materials/leaf/opacity_texture", "texel (0, 0)"});
}

}  // namespace
}  // namespace bounce
