// Many machines (docs/parallel.md): a frame or a shot over an Open MPI job of 1 to 4 ranks
// (oversubscribed on this machine) against one process: every EXR layer and the cache file
// byte-identical; a killed rank ends the job and leaves the previous outputs; ranks of another
// scene, or that cannot read it, are refused naming the rank; --distribute frames and --resume.
#include <fmt/format.h>
#include <nlohmann/json.hpp>
#include <signal.h>

#include <chrono>
#include <cstring>
#include <fstream>
#include <map>
#include <thread>

#include "bounce/core/image.h"
#include "test_util.h"

namespace bounce {
namespace {

/// mpirun of `np` ranks of bounce on this machine. As root (CI's containers) Open MPI must be
/// told that is allowed; more ranks than cores need --oversubscribe.
std::string mpirun(int np) {
    return fmt::format("OMPI_ALLOW_RUN_AS_ROOT=1 OMPI_ALLOW_RUN_AS_ROOT_CONFIRM=1 mpirun --oversubscribe --bind-to none -np {} {}", np,
                       BOUNCE_BINARY);
}

int run_mpi(int np, const std::string& args, std::string* err = nullptr) { return test::run_bounce_shell(mpirun(np) + " " + args, err); }

// Open MPI is not built with the sanitizers (its own threads would be reported): the plain
// build runs these tests; the sanitized build checks the threads of one process.
#if defined(__SANITIZE_THREAD__) || defined(__SANITIZE_ADDRESS__)
#define SKIP_UNDER_SANITIZER() GTEST_SKIP() << "Open MPI is not instrumented"
#else
#define SKIP_UNDER_SANITIZER() (void)0
#endif

/// Every layer of two EXRs holds the same bytes (metadata such as the render time may differ).
void expect_same_layers(const std::string& a, const std::string& b) {
    const Image x = read_exr(a), y = read_exr(b);
    ASSERT_EQ(x.layers.size(), y.layers.size()) << b;
    ASSERT_EQ(x.width, y.width);
    ASSERT_EQ(x.height, y.height);
    for (size_t i = 0; i < x.layers.size(); ++i) {
        EXPECT_EQ(x.layers[i].name, y.layers[i].name);
        ASSERT_EQ(x.layers[i].data.size(), y.layers[i].data.size());
        EXPECT_EQ(std::memcmp(x.layers[i].data.data(), y.layers[i].data.data(), x.layers[i].data.size() * sizeof(float)), 0)
            << b << ": layer " << x.layers[i].name << " differs from " << a;
    }
}

/// One process with 2 threads, then jobs of 1..4 ranks of 1 thread: same layers, same cache bytes.
void expect_identical_at_any_rank_count(const std::string& scene, const std::string& extra) {
    test::TempDir d;
    const std::string common = scene + " --res 64x48 --gi cache -q " + extra;
    ASSERT_EQ(test::run_bounce(fmt::format("render {} -o {} --cache-out {} --threads 2", common, d.file("one.exr"), d.file("one.bic"))), 0);
    for (int np = 1; np <= 4; ++np) {
        const std::string exr = d.file(fmt::format("np{}.exr", np)), bic = d.file(fmt::format("np{}.bic", np));
        std::string err;
        ASSERT_EQ(run_mpi(np, fmt::format("render {} -o {} --cache-out {} --threads 1", common, exr, bic), &err), 0) << err;
        expect_same_layers(d.file("one.exr"), exr);
        EXPECT_EQ(test::bytes_of(d.file("one.bic")), test::bytes_of(bic)) << scene << " at -np " << np;
    }
}

TEST(Mpi, TheCornellBoxIsByteIdenticalAtAnyRankCount) {
    SKIP_UNDER_SANITIZER();
    expect_identical_at_any_rank_count(test::cornell_scene(), "--set render.refine=0.05");
}

TEST(Mpi, AStillBakesEveryRadiositySideOnceAShareEachRank) {
    SKIP_UNDER_SANITIZER();
    // Rank 0 bakes every third triangle's two sides (counted over all objects) and takes the rest.
    test::TempDir d;
    const auto stats_at = [&](int np) {  // rank 0's stats of a render over np ranks
        const std::string json = d.file(fmt::format("np{}.json", np));
        std::string err;
        EXPECT_EQ(run_mpi(np,
                          fmt::format("render {} --res 48x48 --gi cache -q --threads 1 -o {} --stats-json {}", test::cornell_scene(),
                                      d.file(fmt::format("np{}.exr", np)), json),
                          &err),
                  0)
            << err;
        return nlohmann::json::parse(test::bytes_of(json));
    };
    const auto radiosity_from = [](const nlohmann::json& stats) {
        for (const nlohmann::json& step : stats["plan"]["steps"])
            if (step["step"] == "radiosity") return step["from"].get<std::string>();
        return std::string("none");
    };
    const auto stats = stats_at(3);
    EXPECT_EQ(radiosity_from(stats), "bake all, a share per rank, exchanged");
    const auto triangles = static_cast<size_t>(stats["radiosity_sides"].get<double>()) / 2;
    EXPECT_EQ(static_cast<size_t>(stats["radiosity_sides_split_here"].get<double>()), 2 * ((triangles + 2) / 3));
    EXPECT_EQ(stats["radiosity_sides_baked"].get<double>(), 0.0);  // nothing left for the gathers to bake
    // One rank bakes as its gathers hit, as a process alone does.
    EXPECT_EQ(radiosity_from(stats_at(1)), "bake as hit");
}

TEST(Mpi, SavedRadiosityTexturesHoldEverySideAnyRankBaked) {
    SKIP_UNDER_SANITIZER();
    // Each rank bakes the sides its own gathers hit; rank 0 saves them all, as one process would.
    test::TempDir d;
    const std::string common = test::cornell_scene() + " --res 48x48 --gi cache -q --threads 1 -o ";
    ASSERT_EQ(test::run_bounce(fmt::format("render {} {} --radiosity-textures {}", common, d.file("a.exr"), d.file("one"))), 0);
    std::string err;
    ASSERT_EQ(run_mpi(3, fmt::format("render {} {} --radiosity-textures {}", common, d.file("b.exr"), d.file("three")), &err), 0) << err;
    size_t files = 0;
    for (const auto& e : std::filesystem::directory_iterator(d.file("one"))) {
        expect_same_layers(e.path().string(), d.file("three/" + e.path().filename().string()));  // (the header holds a date)
        ++files;
    }
    EXPECT_GT(files, 0u);
}

TEST(Mpi, FurIsByteIdenticalAtAnyRankCount) {
    SKIP_UNDER_SANITIZER();
    expect_identical_at_any_rank_count(test::source_dir() + "/scenes/fur/furball.json", "");
}

TEST(Mpi, DisplacementWithRefinedFragmentsIsByteIdenticalAtAnyRankCount) {
    SKIP_UNDER_SANITIZER();
    expect_identical_at_any_rank_count(test::source_dir() + "/scenes/displaced/displaced.json", "");
}

TEST(Mpi, MirrorsAndGlassAreByteIdenticalAtAnyRankCount) {
    SKIP_UNDER_SANITIZER();
    // The sites of the specular paths get records in the gathering pass, split by tiles like fragments.
    expect_identical_at_any_rank_count(test::source_dir() + "/scenes/cornell/mirror-glass.json", "--rays 64");
}

TEST(Mpi, ADeepFileWithColourAndLightPartsAreRefusedBeforeAnyWork) {
    SKIP_UNDER_SANITIZER();
    test::TempDir d;
    // What one process makes and the exchange does not carry: a deep file's colour, records' light parts.
    for (const auto& [args, key] : {std::pair{fmt::format("--deep-out {} --deep-colour", d.file("o.deep.exr")), "render.deep_colour"},
                                    std::pair{std::string("--gi cache --set render.light_parts=true"), "render.light_parts"}}) {
        std::string err;
        EXPECT_EQ(run_mpi(2, fmt::format("render {} -o {} --res 16x16 -q {}", test::cornell_scene(), d.file("o.exr"), args), &err), 2)
            << err;
        EXPECT_NE(err.find(key), std::string::npos) << err;
        EXPECT_FALSE(std::filesystem::exists(d.file("o.exr")));
    }
}

TEST(Mpi, BruteForceAndTheFramesOfAShotAreByteIdentical) {
    SKIP_UNDER_SANITIZER();
    test::TempDir d;
    const std::string cornell = test::cornell_scene() + " --res 40x40 -q --gi brute --rays 32";
    ASSERT_EQ(test::run_bounce(fmt::format("render {} -o {} --threads 2", cornell, d.file("b1.exr"))), 0);
    ASSERT_EQ(run_mpi(3, fmt::format("render {} -o {} --threads 1", cornell, d.file("b3.exr"))), 0);
    expect_same_layers(d.file("b1.exr"), d.file("b3.exr"));
    // A shot: records kept, moved and redone from frame to frame (docs/animation.md).
    const std::string shot = test::source_dir() + "/scenes/shots/cornell-rolling.json --res 48x48 --gi cache -q --frames 1-3";
    ASSERT_EQ(
        test::run_bounce(fmt::format("render {} -o {} --cache-out {} --threads 2", shot, d.file("s1.####.exr"), d.file("s1.####.bic"))), 0);
    std::string err;
    ASSERT_EQ(
        run_mpi(3, fmt::format("render {} -o {} --cache-out {} --threads 1", shot, d.file("s3.####.exr"), d.file("s3.####.bic")), &err), 0)
        << err;
    for (int f = 1; f <= 3; ++f) {
        expect_same_layers(d.file(fmt::format("s1.{:04d}.exr", f)), d.file(fmt::format("s3.{:04d}.exr", f)));
        EXPECT_EQ(test::bytes_of(d.file(fmt::format("s1.{:04d}.bic", f))), test::bytes_of(d.file(fmt::format("s3.{:04d}.bic", f)))) << f;
    }
}

TEST(Mpi, GuidedBruteForceIsByteIdenticalAndTilesOffThePilotsGridAreRefused) {
    SKIP_UNDER_SANITIZER();
    test::TempDir d;
    // Tiles of 32 (a 40x40 image: windows at 0 and 32) follow the pilots' 8-pixel grid.
    const std::string cornell = test::cornell_scene() + " --res 40x40 -q --gi brute --rays 64 --guided 0.5";
    ASSERT_EQ(test::run_bounce(fmt::format("render {} -o {} --threads 2", cornell, d.file("g1.exr"))), 0);
    std::string err;
    ASSERT_EQ(run_mpi(3, fmt::format("render {} -o {} --threads 1", cornell, d.file("g3.exr")), &err), 0) << err;
    expect_same_layers(d.file("g1.exr"), d.file("g3.exr"));
    EXPECT_EQ(run_mpi(2, fmt::format("render {} -o {} --tile-size 12", cornell, d.file("g12.exr")), &err), 2) << err;
    EXPECT_NE(err.find("render.tile_size"), std::string::npos) << err;
    EXPECT_FALSE(std::filesystem::exists(d.file("g12.exr")));
}

TEST(Mpi, AMovingCamerasShotReprojectsTheSameGathersAtAnyRankCount) {
    SKIP_UNDER_SANITIZER();
    // The Cornell box as a shot with a dollying camera: refinement's fragments reuse earlier
    // frames' gathers (render.temporal_refine_reuse) and keep the hold near the points refined
    // the frame before (render.refine_hold_reach); every process holds every gather's hits, so
    // each reuses what one process would.
    test::TempDir d;
    const std::string dir = test::source_dir() + "/scenes/cornell/";
    nlohmann::json j = nlohmann::json::parse(test::bytes_of(dir + "cornell.json"));
    for (auto& o : j["objects"])
        if (o.contains("file")) o["file"] = dir + o["file"].get<std::string>();
    j["animation"] = {{"fps", 24}, {"frames", {1, 48}}};
    j["camera"]["position"] = {{"keys", {{1, {278, 273, -800}}, {48, {258, 283, -560}}}}};
    std::ofstream(d.file("dolly.json")) << j.dump();
    const std::string shot = d.file("dolly.json") + " --res 48x48 --gi cache -q --frames 1-4 --refine 0.02";
    ASSERT_EQ(
        test::run_bounce(fmt::format("render {} -o {} --stats-json {} --threads 2", shot, d.file("s1.####.exr"), d.file("s1.####.json"))),
        0);
    std::string err;
    ASSERT_EQ(run_mpi(2, fmt::format("render {} -o {} --threads 1", shot, d.file("s2.####.exr")), &err), 0) << err;
    double reprojected = 0;
    for (int f = 1; f <= 4; ++f) {
        expect_same_layers(d.file(fmt::format("s1.{:04d}.exr", f)), d.file(fmt::format("s2.{:04d}.exr", f)));
        reprojected +=
            nlohmann::json::parse(test::bytes_of(d.file(fmt::format("s1.{:04d}.json", f))))["refined_from_earlier_gathers"].get<double>();
    }
    EXPECT_GT(reprojected, 10);  // the case is tested, not skipped
}

/// The pid of rank `rank` of a running job whose command line contains `marker`, or 0.
int find_rank(const std::string& marker, int rank) {
    for (const auto& e : std::filesystem::directory_iterator("/proc")) {
        const std::string pid = e.path().filename().string();
        if (pid.find_first_not_of("0123456789") != std::string::npos) continue;
        std::string cmd = test::bytes_of("/proc/" + pid + "/cmdline"), env = test::bytes_of("/proc/" + pid + "/environ");
        std::replace(cmd.begin(), cmd.end(), '\0', ' ');
        if (cmd.find(marker) == std::string::npos || cmd.find("mpirun") != std::string::npos) continue;
        if (env.find(fmt::format("OMPI_COMM_WORLD_RANK={}", rank) + '\0') != std::string::npos) return std::stoi(pid);
    }
    return 0;
}

TEST(Mpi, AKilledRankEndsTheJobWithinSecondsAndThePreviousOutputsStay) {
    SKIP_UNDER_SANITIZER();
    test::TempDir d;
    const std::string out = d.file("killed.exr");
    const std::string args = fmt::format("render {} -o {} --cache-out {} --res 384x384 --gi cache --threads 1 -q", test::cornell_scene(),
                                         out, d.file("killed.bic"));
    ASSERT_EQ(test::run_bounce(args + " --set render.rays=16"), 0);  // the previous run's outputs
    const std::string before = test::bytes_of(out), cache_before = test::bytes_of(d.file("killed.bic"));
    std::thread killer([&] {
        // Mid-frame: once rank 1 is up, and a moment later (the gathering pass runs seconds).
        for (int tries = 0; tries < 200; ++tries) {
            if (const int pid = find_rank(out, 1)) {
                std::this_thread::sleep_for(std::chrono::milliseconds(1500));
                kill(pid, SIGKILL);
                return;
            }
            std::this_thread::sleep_for(std::chrono::milliseconds(50));
        }
    });
    const auto t0 = std::chrono::steady_clock::now();
    std::string err;
    const int rc = run_mpi(3, args, &err);
    const double seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
    killer.join();
    EXPECT_NE(rc, 0) << err;
    EXPECT_NE(err.find("rank 1"), std::string::npos) << err;
    EXPECT_LT(seconds, 30) << "the job must not hang at a collective call";
    EXPECT_EQ(test::bytes_of(out), before);
    EXPECT_EQ(test::bytes_of(d.file("killed.bic")), cache_before);
}

TEST(Mpi, AShotKilledMidwayResumesWhereItStopped) {
    SKIP_UNDER_SANITIZER();
    test::TempDir d;
    const std::string args = fmt::format(
        "render {}/scenes/shots/cornell-rolling.json --res 96x96 --gi cache --threads 1 -q "
        "--frames 1-9 --distribute frames -o {} --cache-out {}",
        test::source_dir(), d.file("k.####.exr"), d.file("k.####.bic"));
    std::thread killer([&] {
        // Once rank 0 has written its first frame, rank 2 dies in the middle of its chunk.
        for (int tries = 0; tries < 600 && !std::filesystem::exists(d.file("k.0001.exr")); ++tries)
            std::this_thread::sleep_for(std::chrono::milliseconds(50));
        if (const int pid = find_rank(d.file("k.####.exr"), 2)) kill(pid, SIGKILL);
    });
    std::string err;
    const int rc = run_mpi(3, args, &err);
    killer.join();
    ASSERT_NE(rc, 0) << "the kill came too late: " << err;
    std::map<int, std::string> done;  // frames whose outputs are complete, and their bytes
    for (int f = 1; f <= 9; ++f)
        if (std::filesystem::exists(d.file(fmt::format("k.{:04d}.bic", f))))
            done[f] = test::bytes_of(d.file(fmt::format("k.{:04d}.exr", f)));
    EXPECT_LT(done.size(), 9u);
    ASSERT_EQ(run_mpi(3, args + " --resume", &err), 0) << err;
    for (int f = 1; f <= 9; ++f) {
        EXPECT_TRUE(std::filesystem::exists(d.file(fmt::format("k.{:04d}.bic", f)))) << f;
        if (done.count(f)) {
            EXPECT_TRUE(test::bytes_of(d.file(fmt::format("k.{:04d}.exr", f))) == done[f]) << "frame " << f << " was redone";
        }
    }
}

TEST(Mpi, RanksOfAnotherSceneOrThatCannotReadItAreRefusedNamingTheRank) {
    SKIP_UNDER_SANITIZER();
    test::TempDir d;
    const std::string one = fmt::format("render {} -o {} --res 16x16 -q", test::cornell_scene(), d.file("o.exr"));
    // Multiple programs, multiple data: rank 1 runs another command line.
    const std::string mpmd = std::string("OMPI_ALLOW_RUN_AS_ROOT=1 OMPI_ALLOW_RUN_AS_ROOT_CONFIRM=1 mpirun --oversubscribe --bind-to none");
    std::string err;
    EXPECT_EQ(test::run_bounce_shell(
                  fmt::format("{} -np 1 {} {} : -np 1 {} {} --set camera.fov=30", mpmd, BOUNCE_BINARY, one, BOUNCE_BINARY, one), &err),
              2)
        << err;
    EXPECT_NE(err.find("rank 1: error: runs another binary or reads another scene"), std::string::npos) << err;
    EXPECT_NE(err.find("camera.fov=30"), std::string::npos) << err;
    const std::string missing = d.file("nowhere.json");
    EXPECT_EQ(test::run_bounce_shell(fmt::format("{} -np 1 {} {} : -np 1 {} render {} -o {} -q", mpmd, BOUNCE_BINARY, one, BOUNCE_BINARY,
                                                 missing, d.file("o.exr")),
                                     &err),
              2)
        << err;
    EXPECT_NE(err.find("bounce: rank 1: " + missing), std::string::npos) << err;
    EXPECT_FALSE(std::filesystem::exists(d.file("o.exr")));
    // Only render runs as a job of many ranks (the tools would write their outputs N times).
    EXPECT_EQ(run_mpi(2, "params", &err), 2);
    EXPECT_NE(err.find("only render runs as an MPI job"), std::string::npos) << err;
}

TEST(Mpi, FramesAreDistributedInChunksAndAResumedJobRendersOnlyWhatIsMissing) {
    SKIP_UNDER_SANITIZER();
    test::TempDir d;
    const std::string shot = test::source_dir() + "/scenes/shots/cornell-rolling.json --res 40x40 --gi cache --threads 1 -q";
    const auto files = [&](const std::string& tag) { return fmt::format("-o {0}.####.exr --cache-out {0}.####.bic", d.file(tag)); };
    std::string err;
    ASSERT_EQ(run_mpi(3, fmt::format("render {} --frames 1-6 --distribute frames {}", shot, files("job")), &err), 0) << err;
    // Rank 0 rendered frames 1-2 as one process renders that range; rank 1 started frame 3
    // afresh (frame 2's cache was not there when the job began).
    ASSERT_EQ(test::run_bounce(fmt::format("render {} --frames 1-2 {}", shot, files("alone"))), 0);
    ASSERT_EQ(test::run_bounce(fmt::format("render {} --frame 3 {}", shot, files("alone"))), 0);
    for (int f = 1; f <= 3; ++f)
        EXPECT_EQ(test::bytes_of(d.file(fmt::format("job.{:04d}.bic", f))), test::bytes_of(d.file(fmt::format("alone.{:04d}.bic", f))))
            << f;
    for (int f = 4; f <= 6; ++f) EXPECT_TRUE(std::filesystem::exists(d.file(fmt::format("job.{:04d}.exr", f)))) << f;
    // A job killed before frames 5 and 6 were written: the resumed job renders only those,
    // frame 5 starting from frame 4's cache.
    std::filesystem::remove(d.file("job.0005.exr")), std::filesystem::remove(d.file("job.0006.bic"));
    const std::string kept = test::bytes_of(d.file("job.0004.exr"));
    ASSERT_EQ(run_mpi(3, fmt::format("render {} --frames 1-6 --distribute frames --resume {}", shot, files("job")), &err), 0) << err;
    EXPECT_EQ(test::bytes_of(d.file("job.0004.exr")), kept);
    EXPECT_TRUE(std::filesystem::exists(d.file("job.0005.exr")));
    EXPECT_TRUE(std::filesystem::exists(d.file("job.0006.bic")));
    test::expect_refused(fmt::format("render {} --frames 1-2 --distribute rows {}", shot, files("x")),
                         {"--distribute rows", "tiles or frames"});
}

/// docs/parallel.md's Slurm batch script, run as sbatch would on 2 tasks of 1 CPU: srun is
/// stood in for by mpirun with Slurm's task count. Its frames equal one process's, and a
/// resubmitted job renders only what is missing.
TEST(Mpi, TheSlurmBatchScriptRendersAShotAsOneProcessDoes) {
    SKIP_UNDER_SANITIZER();
    test::TempDir d;
    std::filesystem::create_directories(d.file("bin"));
    d.write("bin/srun",
            "#!/bin/sh\nwhile [ \"${1#--}\" != \"$1\" ]; do shift; done\n"
            "OMPI_ALLOW_RUN_AS_ROOT=1 OMPI_ALLOW_RUN_AS_ROOT_CONFIRM=1 exec mpirun --oversubscribe --bind-to none "
            "-np \"$SLURM_NTASKS\" \"$@\"\n");
    std::filesystem::permissions(d.file("bin/srun"), std::filesystem::perms::owner_all);
    const std::string shot = test::source_dir() + "/scenes/shots/cornell-rolling.json";
    const std::string extra = " --res 40x40 --gi cache --rays 64";
    ASSERT_EQ(test::run_bounce(fmt::format("render {} -o {} --frames 1-3 --threads 2 -q {}", shot, d.file("one.####.exr"), extra)), 0);
    const std::string sbatch =
        fmt::format("PATH={}:$PATH SLURM_NTASKS=2 SLURM_CPUS_PER_TASK=1 BOUNCE={} bash {}/scripts/farm/shot.sbatch {} {} 1-3 {}",
                    d.file("bin"), BOUNCE_BINARY, test::source_dir(), shot, d.file("job.####.exr"), extra);
    std::string err;
    ASSERT_EQ(test::run_bounce_shell(sbatch, &err), 0) << err;
    for (int f = 1; f <= 3; ++f) {
        expect_same_layers(d.file(fmt::format("one.{:04d}.exr", f)), d.file(fmt::format("job.{:04d}.exr", f)));
        EXPECT_TRUE(std::filesystem::exists(d.file(fmt::format("job.{:04d}.bic", f))));
        EXPECT_EQ(nlohmann::json::parse(test::bytes_of(d.file(fmt::format("job.{:04d}.json", f))))["ranks"], 2) << f;
    }
    // Requeued after frame 1: frames 2 and 3 are rendered again (from frame 1's cache), frame 1 stays.
    std::filesystem::remove(d.file("job.0002.exr"));
    std::filesystem::remove(d.file("job.0003.exr"));
    std::filesystem::last_write_time(d.file("job.0001.exr"), std::filesystem::file_time_type{});
    ASSERT_EQ(test::run_bounce_shell(sbatch, &err), 0) << err;
    EXPECT_EQ(std::filesystem::last_write_time(d.file("job.0001.exr")), std::filesystem::file_time_type{});
    EXPECT_TRUE(std::filesystem::exists(d.file("job.0002.exr")) && std::filesystem::exists(d.file("job.0003.exr")));
}

}  // namespace
}  // namespace bounce
