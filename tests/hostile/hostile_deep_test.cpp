// Hostile deep files and EXR headers: every field checked before shading, headers that would
// abort OpenImageIO refused wherever an EXR is read.
#include <gtest/gtest.h>

#include "hostile/hostile_util.h"

namespace bounce {
namespace {

using namespace hostile;  // json, fs, expect_refused and the shared scenes

TEST(HostileDeep, EveryFieldOfACraftedDeepFileIsCheckedBeforeShading) {
    test::TempDir d;
    const Scene s =
        load_scene(test::cornell_scene(), {"camera.resolution=[12,12]", "render.spp=1", "render.gi=\"cache\"", "render.rays=16"});
    RenderRequest req;
    req.deep_out = d.file("f.deep.exr");
    Stats stats;
    render(s, req, stats, nullptr);
    const DeepBuffer good = read_deep(req.deep_out);
    // The crafted files: Pref 3e38 or 1e19 everywhere (segfault), Nref NaN, N 1e30, P 3e38
    // on one fragment (abort in Embree), N = 0 everywhere (NaN pixels).
    struct Case {
        const char* name;
        std::function<void(Fragment&)> edit;
        bool all;
        const char* channel;
    };
    const std::vector<Case> cases = {
        {"pref3e38", [](Fragment& f) { f.p_base.x = 3e38f; }, true, "Pref"},
        {"pref1e19", [](Fragment& f) { f.p_base.x = 1e19f; }, true, "Pref"},
        {"nrefnan", [](Fragment& f) { f.n_base.x = NAN; }, false, "Nref"},
        {"n1e30", [](Fragment& f) { f.n.x = 1e30f; }, false, "N"},
        {"p3e38", [](Fragment& f) { f.p.x = 3e38f; }, false, "P"},
        {"nzero", [](Fragment& f) { f.n = Vec3(0); }, true, "N"},
        {"footprint", [](Fragment& f) { f.footprint = -1; }, false, "footprint"},
        {"far", [](Fragment& f) { f.p.x = 1e17f; }, false, "outside the scene"},
    };
    for (const Case& c : cases) {
        DeepBuffer bad = good;
        for (Fragment& f : bad.fragments) {
            c.edit(f);
            if (!c.all) break;
        }
        const std::string file = d.file(std::string(c.name) + ".deep.exr");
        write_deep(file, bad);
        RenderRequest in;
        in.deep_in = file;
        try {
            render(s, in, stats, nullptr);
            ADD_FAILURE() << c.name << " was shaded";
        } catch (const InputError& e) {
            EXPECT_EQ(e.file(), file);
            EXPECT_NE(std::string(e.what()).find(c.channel), std::string::npos) << e.what();
        }
    }
}

TEST(HostileExr, AHeaderOpenImageIoAbortsOnIsRefusedWhereverAnExrIsRead) {
    // A deep file the fuzzer damaged: OpenImageIO 2.4 aborts the process on its channel list
    // ("Unknown Imf::PixelType 3"); OpenEXR's core library names the bad pixel type.
    const std::string bad = test::source_dir() + "/tests/data/hostile/oiio-abort-pixel-type.exr";
    test::TempDir d;
    const Scene s = load_scene(test::cornell_scene(), {"camera.resolution=[8,8]", "render.spp=1"});
    RenderRequest in;
    in.deep_in = bad;
    Stats stats;
    try {
        render(s, in, stats, nullptr);
        ADD_FAILURE() << "a damaged deep file was read";
    } catch (const InputError& e) {
        EXPECT_EQ(e.file(), bad);
        EXPECT_NE(std::string(e.what()).find("damaged OpenEXR header: Invalid pixel type"), std::string::npos) << e.what();
    }
    std::filesystem::copy_file(bad, d.file("t.exr"));
    json j = test::base_scene();
    j["materials"] = {{"m", {{"color_texture", "t.exr"}}}};
    j["objects"][0]["material"] = "m";
    d.write("m.json", j.dump());
    test::expect_refused(render_cmd(d.file("m.json"), d.file("o.exr")), {"m.json", "/materials/m/color_texture", "damaged OpenEXR header"});
    j = test::base_scene();
    j["lights"] = {{{"type", "sky"}, {"texture", "t.exr"}}};
    d.write("sky.json", j.dump());
    test::expect_refused(render_cmd(d.file("sky.json"), d.file("o.exr")), {"sky.json", "/lights/0/texture", "damaged OpenEXR header"});
}

}  // namespace
}  // namespace bounce
