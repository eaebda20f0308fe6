// The beauty's components for compositing (render.layers = components): they sum to the
// beauty, the per-light layers sum to their totals, the beauty is the standard render's bit
// for bit, and the id layer names what each pixel sees.
#include <gtest/gtest.h>

#include <fmt/format.h>

#include "bounce/core/image.h"
#include "bounce/render/render.h"
#include "test_util.h"

namespace bounce {
namespace {

using nlohmann::json;

Image render_image(const Scene& s) {
    Stats stats;
    return render(s, {}, stats, nullptr).image;
}

/// The glossy Cornell box (emitter, coloured walls, a specular lobe) with the cache, two extra
/// lights (`key` and `rim` their intensities), and `more` settings.
Scene glossy_cornell(const std::string& layers, std::vector<Override> more = {}, float key = 30000, float rim = 20000) {
    std::vector<Override> set = {"camera.resolution=[32,32]",
                                 "render.spp=2",
                                 "render.rays=64",
                                 "render.gi=cache",
                                 "render.layers=" + layers,
                                 "materials.white.specular=[0.3,0.3,0.3]",
                                 "materials.white.roughness=0.3",
                                 fmt::format(R"(lights=[{{"type": "point", "name": "key", "position": [278, 400, 100], "intensity": {}}},
                               {{"type": "spot", "name": "rim light", "position": [100, 500, 278], "direction": [1, -1, 0], "intensity": {}}}])",
                                             key, rim)};
    set.insert(set.end(), more.begin(), more.end());
    return load_scene(test::cornell_scene(), set);
}

/// Sum over `names` of layer channel c at pixel i.
float sum_of(const Image& img, const std::vector<std::string>& names, size_t i, size_t c) {
    float s = 0;
    for (const std::string& n : names) {
        const Layer* l = img.find(n);
        EXPECT_TRUE(l) << n;
        if (l) s += l->data[i * l->channels.size() + c];
    }
    return s;
}

void expect_sums(const Image& img, const std::string& total, const std::vector<std::string>& parts) {
    const Layer* t = img.find(total);
    ASSERT_TRUE(t) << total;
    float worst = 0;
    for (size_t i = 0; i < static_cast<size_t>(img.width) * img.height; ++i)
        for (size_t c = 0; c < 3; ++c) {
            const float want = t->data[i * t->channels.size() + c];
            worst = std::max(worst, std::abs(sum_of(img, parts, i, c) - want) / std::max(1.0f, std::abs(want)));
        }
    EXPECT_LT(worst, 1e-5f) << total;
}

TEST(ComponentLayers, SumToTheBeautyAndPerLightLayersToTheirTotals) {
    const Image img = render_image(glossy_cornell("components"));
    expect_sums(img, "beauty",
                {"emission", "diffuse_direct", "specular_direct", "diffuse_indirect", "specular_indirect", "background", "reflection",
                 "refraction"});
    // Lights: the two named ones (a space becomes '_') and the emissive quad (its object's name).
    expect_sums(img, "diffuse_direct", {"diffuse_direct_key", "diffuse_direct_rim_light", "diffuse_direct_light"});
    expect_sums(img, "specular_direct", {"specular_direct_key", "specular_direct_rim_light", "specular_direct_light"});
    // Every part is there to be seen in this frame.
    for (const char* l : {"emission", "diffuse_direct_key", "specular_direct_rim_light", "diffuse_indirect", "specular_indirect"}) {
        const Layer* layer = img.find(l);
        ASSERT_TRUE(layer) << l;
        EXPECT_GT(*std::max_element(layer->data.begin(), layer->data.end()), 0.0f) << l;
    }
}

TEST(ComponentLayers, PerLightIndirectLayersComeFromTheRecordsLightParts) {
    const Image img = render_image(glossy_cornell("components", {"render.light_parts=true"}));
    const std::vector<std::string> lights = {"key", "rim_light", "light"};
    std::vector<std::string> diffuse, specular;
    for (const std::string& l : lights) diffuse.push_back("diffuse_indirect_" + l), specular.push_back("specular_indirect_" + l);
    expect_sums(img, "diffuse_indirect", diffuse);
    expect_sums(img, "specular_indirect", specular);
    for (const std::string& l : diffuse) {
        const Layer* layer = img.find(l);
        ASSERT_TRUE(layer) << l;
        EXPECT_GT(*std::max_element(layer->data.begin(), layer->data.end()), 0.0f) << l;
    }
    // Records without parts cannot split their light: no per-light indirect layers.
    EXPECT_EQ(render_image(glossy_cornell("components")).find("diffuse_indirect_key"), nullptr);
}

TEST(ComponentLayers, APerLightIndirectLayerIsWhatThatLightAloneBounces) {
    // With light parts, records sit where they sit whatever the lights' intensities: the
    // emitter's own layer equals the indirect light of a render where the other two are off.
    const Image all = render_image(glossy_cornell("components", {"render.light_parts=true"}));
    const Image alone = render_image(glossy_cornell("components", {"render.light_parts=true"}, 0, 0));
    const Layer *part = all.find("diffuse_indirect_light"), *whole = alone.find("diffuse_indirect");
    ASSERT_TRUE(part && whole);
    double err = 0, ref = 0;
    for (size_t i = 0; i < part->data.size(); ++i) {
        err += std::pow(part->data[i] - whole->data[i], 2);
        ref += std::pow(whole->data[i], 2);
    }
    EXPECT_GT(ref, 0);
    EXPECT_LT(std::sqrt(err / ref), 1e-5);
}

TEST(ComponentLayers, MirrorsAndGlassAddReflectionAndRefractionThatStillSumToTheBeauty) {
    const Scene s =
        load_scene(test::source_dir() + "/scenes/cornell/mirror-glass.json",
                   {"camera.resolution=[32,32]", "render.spp=2", "render.rays=64", "render.gi=cache", "render.layers=components"});
    const Image img = render_image(s);
    expect_sums(img, "beauty",
                {"emission", "diffuse_direct", "specular_direct", "diffuse_indirect", "specular_indirect", "background", "reflection",
                 "refraction"});
    for (const char* l : {"reflection", "refraction"}) {
        const Layer* layer = img.find(l);
        ASSERT_TRUE(layer) << l;
        EXPECT_GT(*std::max_element(layer->data.begin(), layer->data.end()), 0.0f) << l;
    }
}

TEST(ComponentLayers, LeaveTheStandardLayersBitForBit) {
    const Image a = render_image(glossy_cornell("components")), b = render_image(glossy_cornell("standard"));
    EXPECT_EQ(b.find("emission"), nullptr);
    for (const Layer& l : b.layers) {
        const Layer* same = a.find(l.name);
        ASSERT_TRUE(same) << l.name;
        EXPECT_EQ(same->data, l.data) << l.name;
    }
}

TEST(ComponentLayers, TheIdLayerNamesTheObjectAndMaterialThePixelSees) {
    json j = test::base_scene();
    j["materials"] = {{"a", {{"color", 0.5}}}, {"b", {{"color", 0.2}}}};
    j["objects"][0]["name"] = "floor", j["objects"][0]["material"] = "b";
    j["objects"].push_back(
        {{"name", "card"}, {"type", "quad"}, {"material", "a"}, {"vertices", {{-1, 1, -1}, {-1, 1, 1}, {1, 1, 1}, {1, 1, -1}}}});
    j["render"] = {{"layers", "components"}};
    const Image img = render_image(test::scene_from(j));
    const Layer* id = img.find("id");
    ASSERT_TRUE(id);
    ASSERT_EQ(id->channels, std::vector<std::string>({"id.object", "id.material"}));
    EXPECT_EQ(img.at(*id, 8, 8)[0], 2.0f);  // objects[1] + 1: the card
    EXPECT_EQ(img.at(*id, 1, 1)[0], 1.0f);  // the floor
    EXPECT_EQ(json::parse(img.metadata.at("object_ids")), json({"floor", "card"}));
    const json materials = json::parse(img.metadata.at("material_ids"));
    EXPECT_EQ(materials[static_cast<size_t>(img.at(*id, 8, 8)[1]) - 1], "a");
    EXPECT_EQ(materials[static_cast<size_t>(img.at(*id, 1, 1)[1]) - 1], "b");
}

}  // namespace
}  // namespace bounce
