// Helpers of the lighting tool's tests (tool_test.cpp: the session; tool_http_test.cpp: its
// HTTP API): a small session on a copy of the Cornell box, and a server on a loopback port.
#pragma once

#include <httplib.h>

#include <array>
#include <filesystem>
#include <optional>
#include <string>
#include <thread>

#include "bounce/tool/server.h"
#include "test_util.h"

namespace bounce::test {

/// A copy of the Cornell box in `d` (saved scenes land beside it) and an output folder.
inline SessionOptions small_session(const test::TempDir& d) {
    std::filesystem::create_directories(d.path() / "scene");
    for (const auto& e : std::filesystem::directory_iterator(test::source_dir() + "/scenes/cornell"))
        std::filesystem::copy_file(e.path(), d.path() / "scene" / e.path().filename());
    SessionOptions o;
    o.scene = (d.path() / "scene" / "cornell.json").string();
    o.out_dir = d.file("out");
    o.threads = 2;
    o.sets = {"camera.resolution=[48,40]", "render.spp=1", "render.rays=64", "render.light_samples=2"};
    return o;
}

inline void render_and_wait(LightingSession& s, SessionAction a, std::optional<std::array<int, 4>> crop = std::nullopt) {
    s.start(a, crop);
    s.wait();
    ASSERT_EQ(s.status()["state"], "done") << s.status()["message"];
}

/// A small session served on a free loopback port, with a client that carries the token.
struct Served {
    test::TempDir dir;
    LightingSession session{small_session(dir)};
    LightingServer server{session, ServerOptions{}};
    int port = server.bind();
    std::thread thread{[this] { server.listen(); }};
    httplib::Client client{"127.0.0.1", port};
    Served() { client.set_default_headers({{"Authorization", "token " + server.token()}}); }
    ~Served() {
        server.stop();
        thread.join();
    }
};

}  // namespace bounce::test
