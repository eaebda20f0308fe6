// The lighting tool's HTTP API (in-process client on a loopback port): validation, an edit and a
// render through it, the arrays the page draws, loopback only, the token, Origin and Host guard.
#include <fmt/format.h>
#include <httplib.h>

#include <cstring>
#include <map>
#include <thread>

#include "bounce/cache/cache_file.h"
#include "bounce/core/error.h"
#include "bounce/config/params.h"
#include "bounce/tool/server.h"
#include "tool_util.h"

namespace bounce {
namespace {

using nlohmann::json;
using test::Served, test::small_session;

TEST(LightingToolHttp, BadRequestsGetAStatusAndAMessage) {
    Served s;
    auto post = [&](const std::string& path, const std::string& body) { return s.client.Post(path, body, "application/json"); };
    auto r = post("/api/edit", R"({"key": "render.rays", "value": 1e39})");
    ASSERT_TRUE(r);
    EXPECT_EQ(r->status, 400);
    EXPECT_NE(json::parse(r->body)["error"].get<std::string>().find("render.rays"), std::string::npos);
    r = post("/api/edit", R"({"key": "render.rays", "value": )");
    EXPECT_EQ(r->status, 400);
    EXPECT_NE(r->body.find("byte"), std::string::npos);
    EXPECT_EQ(post("/api/edit", "[1, 2]")->status, 400);
    // A number past a double is the client's fault (it was a 500).
    for (const char* path : {"/api/edit", "/api/frame"}) {
        r = post(path, R"({"key": "render.rays", "value": 1e999, "frame": 1e999})");
        EXPECT_EQ(r->status, 400) << path;
        EXPECT_NE(r->body.find("not finite"), std::string::npos) << r->body;
    }
    EXPECT_EQ(post("/api/render", R"({"action": "explode"})")->status, 400);
    EXPECT_EQ(post("/api/render", R"({"action": "reshade", "crop": [0, 10, 0, 10]})")->status, 400);  // nothing rendered yet
    EXPECT_EQ(post("/api/render", R"({"action": "reshade", "crop": [0, "a", 0, 10]})")->status, 400);
    for (const char* empty : {R"({"action": "regather", "crop": [10, 0, 0, 10]})", R"({"action": "regather", "crop": [4, 4, 4, 4]})"}) {
        r = post("/api/render", empty);
        EXPECT_EQ(r->status, 400) << empty;
        EXPECT_NE(r->body.find("empty region"), std::string::npos) << r->body;
    }
    for (const char* name : {"../secret.bic", "/etc/passwd", "a/../../b.bic"})
        EXPECT_EQ(s.client.Get("/api/records", httplib::Params{{"file", name}}, httplib::Headers{})->status, 400) << name;
    EXPECT_EQ(post("/api/save-scene", R"({"name": "../escape.json"})")->status, 400);
    // Path-valued keys set through an edit obey the same confinement as the file API.
    r = post("/api/edit", R"({"key": "render.radiosity_textures", "value": "/tmp/bounce-escape-folder"})");
    EXPECT_EQ(r->status, 400);
    EXPECT_NE(json::parse(r->body)["error"].get<std::string>().find("outside the scene's folder"), std::string::npos) << r->body;
    EXPECT_FALSE(std::filesystem::exists("/tmp/bounce-escape-folder"));
    EXPECT_EQ(post("/api/edit", R"({"key": "objects.6.file", "value": "/etc/hostname"})")->status, 400);
    EXPECT_EQ(s.client.Get("/api/image?layer=beauty&exposure=nan")->status, 400);
    EXPECT_EQ(s.client.Get("/api/scene?max_triangles=-4")->status, 400);
    EXPECT_EQ(post("/api/edit", std::string(5u << 20, ' '))->status, 413);
    EXPECT_EQ(s.client.Get("/api/nothing")->status, 404);
    // Still serving after all of that.
    r = s.client.Get("/api/status");
    ASSERT_TRUE(r);
    EXPECT_EQ(r->status, 200);
    EXPECT_EQ(json::parse(r->body)["state"], "idle");
}

TEST(LightingToolHttp, AnEditAndARenderThroughTheApi) {
    Served s;
    auto r = s.client.Post("/api/render", R"({"action": "rasterize"})", "application/json");
    ASSERT_TRUE(r);
    EXPECT_EQ(r->status, 202);
    s.session.wait();
    r = s.client.Get("/api/image?layer=indirect&exposure=1");
    ASSERT_TRUE(r);
    EXPECT_EQ(r->status, 200);
    EXPECT_EQ(r->get_header_value("X-Width"), "48");
    EXPECT_EQ(r->body.size(), 48u * 40u * 4u);
    const json rec = json::parse(s.client.Get("/api/records")->body);
    EXPECT_EQ(rec["count"].get<size_t>(), read_cache_file(s.session.cache_path().string()).records.size());
    EXPECT_EQ(rec["p"].size(), 3 * rec["shown"].get<size_t>());
    // A region keeps exactly the records the camera projects into it; all of them for the frame.
    const json whole = json::parse(s.client.Get("/api/records?region=0,48,0,40")->body);
    const json left = json::parse(s.client.Get("/api/records?region=0,24,0,40")->body);
    const json right = json::parse(s.client.Get("/api/records?region=24,48,0,40")->body);
    EXPECT_EQ(left["in_region"].get<size_t>() + right["in_region"].get<size_t>(), whole["in_region"].get<size_t>());
    EXPECT_GT(left["in_region"].get<size_t>(), 0u);
    EXPECT_EQ(s.client.Get("/api/records?region=1,2,3")->status, 400);
    // The page's binary form holds the same floats, bit for bit, laid out as X-Meta says; and
    // nothing is compressed, whatever the client accepts (docs/lighting-tool.md).
    r = s.client.Get("/api/records?format=binary", httplib::Headers{{"Accept-Encoding", "gzip, deflate, br"}});
    ASSERT_EQ(r->status, 200);
    EXPECT_EQ(r->get_header_value("Content-Encoding"), "");
    const json meta = json::parse(r->get_header_value("X-Meta"));
    EXPECT_EQ(meta["count"], rec["count"]);
    size_t at = 0;
    for (const json& a : meta["arrays"]) {
        const json& numbers = rec[a[0].get<std::string>()];
        ASSERT_EQ(a[1].get<size_t>(), numbers.size()) << a;
        for (size_t i = 0; i < numbers.size(); ++i, at += 4) {
            float v;
            std::memcpy(&v, r->body.data() + at, 4);
            EXPECT_EQ(v, numbers[i].get<float>()) << a[0] << " " << i;
        }
    }
    EXPECT_EQ(at, r->body.size());
    EXPECT_EQ(s.client.Get("/api/records", httplib::Headers{{"Accept-Encoding", "br"}})->get_header_value("Content-Encoding"), "");
    EXPECT_EQ(s.client.Get("/api/records?format=xml")->status, 400);
    const json view = json::parse(s.client.Get("/api/scene?max_triangles=10")->body);
    EXPECT_LE(view["triangles"].size(), 9u * 12u);
    EXPECT_EQ(view["camera"]["width"], 48);
    r = s.client.Get("/api/scene?max_triangles=10&format=binary");
    EXPECT_EQ(r->body.size(), 4 * view["triangles"].size());
    EXPECT_EQ(json::parse(r->get_header_value("X-Meta"))["arrays"], json::array({json::array({"triangles", view["triangles"].size()})}));
    r = s.client.Post("/api/save-scene", R"({"name": "edited-by-test.json"})", "application/json");
    ASSERT_EQ(r->status, 200) << r->body;
    const Scene back = load_scene(s.dir.file("scene/edited-by-test.json"));
    EXPECT_EQ(back.render.indirect.rays, 64);
    EXPECT_EQ(back.camera.width, 48);
}

TEST(LightingToolHttp, OnlyLoopbackAddressesAreServed) {
    test::TempDir d;
    LightingSession session(small_session(d));
    ServerOptions o;
    o.host = "0.0.0.0";
    EXPECT_THROW(LightingServer(session, o), InputError);
    EXPECT_TRUE(is_loopback_host("127.0.0.1"));
    EXPECT_TRUE(is_loopback_host("::1"));
    EXPECT_FALSE(is_loopback_host("127.0.0.1.evil.com"));
    EXPECT_FALSE(is_loopback_host("10.0.0.1"));
}

/// The attacker's requests of issue 50: each gets 403 with a message, and changes nothing.
TEST(LightingToolHttp, OnlyThePageOfThePrintedUrlDrivesTheTool) {
    Served s;
    const std::string edit = R"({"key": "render.min_spacing", "value": 2.5})";
    const auto spacing = [&] {
        for (const json& row : json::parse(s.client.Get("/api/params")->body))
            if (row["key"] == "render.min_spacing") return row["value"];
        return json();
    };
    const json before = spacing();
    ASSERT_FALSE(before.is_null());
    httplib::Client bare{"127.0.0.1", s.port};  // no token
    const std::string token = s.server.token();
    const auto refused = [&](const httplib::Result& r, const char* why) {
        ASSERT_TRUE(r) << why;
        EXPECT_EQ(r->status, 403) << why;
        EXPECT_FALSE(json::parse(r->body)["error"].get<std::string>().empty()) << why;
    };
    // A cross-origin "simple" POST (text/plain needs no preflight), with the right token even.
    refused(s.client.Post("/api/edit", httplib::Headers{{"Origin", "http://evil.example"}}, edit, "text/plain"), "foreign origin");
    refused(s.client.Post("/api/edit", httplib::Headers{{"Origin", "http://127.0.0.1:" + std::to_string(s.port + 1)}}, edit,
                          "application/json"),
            "another port of this machine");
    refused(s.client.Post("/api/edit", httplib::Headers{{"Origin", "null"}}, edit, "application/json"), "an opaque origin");
    refused(s.client.Post("/api/edit", edit, "text/plain"), "a state change without JSON");
    // DNS rebinding: a foreign Host, even with the token.
    refused(s.client.Get("/api/params", httplib::Headers{{"Host", "evil.example"}}), "foreign Host");
    refused(s.client.Get("/api/params", httplib::Headers{{"Host", "127.0.0.1.evil.example:" + std::to_string(s.port)}}), "look-alike Host");
    refused(s.client.Get("/api/params", httplib::Headers{{"Host", "127.0.0.1:1"}}), "another port in Host");
    // No token, a wrong one, the page itself without one.
    refused(bare.Post("/api/edit", edit, "application/json"), "no token");
    refused(bare.Get("/api/params"), "no token, reading");
    refused(bare.Get("/index.html"), "the page without a token");
    refused(bare.Post("/api/edit", httplib::Headers{{"Authorization", "token " + token + "x"}}, edit, "application/json"), "wrong token");
    refused(bare.Post("/api/edit", httplib::Headers{{"Cookie", "bounce-token-" + std::to_string(s.port + 1) + "=" + token}}, edit,
                      "application/json"),
            "another tool's cookie name");
    refused(bare.Post("/api/render", R"({"action": "rasterize"})", "application/json"), "a render without a token");
    EXPECT_EQ(spacing(), before);
    EXPECT_EQ(s.session.status()["state"], "idle");
    // The printed URL's token gives the page its cookie; the cookie (or the header) then serves.
    auto r = bare.Get("/api/params?token=" + token);
    ASSERT_TRUE(r);
    EXPECT_EQ(r->status, 200);
    const std::string cookie = r->get_header_value("Set-Cookie");
    EXPECT_NE(cookie.find("SameSite=Strict"), std::string::npos) << cookie;
    EXPECT_NE(cookie.find("HttpOnly"), std::string::npos) << cookie;
    const std::string pair = cookie.substr(0, cookie.find(';'));
    EXPECT_EQ(pair, "bounce-token-" + std::to_string(s.port) + "=" + token);
    r = bare.Post("/api/edit", httplib::Headers{{"Cookie", "other=1; " + pair}, {"Origin", "http://127.0.0.1:" + std::to_string(s.port)}},
                  edit, "application/json; charset=utf-8");
    ASSERT_TRUE(r);
    EXPECT_EQ(r->status, 200) << r->body;
    EXPECT_EQ(spacing(), 2.5);
    EXPECT_EQ(s.server.url(), "http://127.0.0.1:" + std::to_string(s.port) + "/?token=" + token);
}

TEST(LightingToolHttp, TheGuardReadsHostOriginTokenAndTypeAsAWholeHeader) {
    RequestGuard g("secret");
    g.bind(8123);
    RequestFacts ok{"POST", "127.0.0.1:8123", "", "application/json", "token secret", "", ""};
    EXPECT_EQ(g.check(ok).refusal, Refusal::None);
    const auto with = [&](auto change) {
        RequestFacts f = ok;
        change(f);
        return g.check(f).refusal;
    };
    EXPECT_EQ(with([](RequestFacts& f) { f.host = "localhost:8123"; }), Refusal::None);
    EXPECT_EQ(with([](RequestFacts& f) { f.host = "[::1]:8123"; }), Refusal::None);
    EXPECT_EQ(with([](RequestFacts& f) { f.host = "LOCALHOST:8123"; }), Refusal::None);
    EXPECT_EQ(with([](RequestFacts& f) { f.host = ""; }), Refusal::Host);
    EXPECT_EQ(with([](RequestFacts& f) { f.host = "localhost"; }), Refusal::Host);  // port 80
    EXPECT_EQ(with([](RequestFacts& f) { f.host = "localhost:81234"; }), Refusal::Host);
    EXPECT_EQ(with([](RequestFacts& f) { f.host = "[::1"; }), Refusal::Host);
    EXPECT_EQ(with([](RequestFacts& f) { f.host = "10.0.0.1:8123"; }), Refusal::Host);
    EXPECT_EQ(with([](RequestFacts& f) { f.origin = "http://localhost:8123"; }), Refusal::None);
    EXPECT_EQ(with([](RequestFacts& f) { f.origin = "https://127.0.0.1:8123"; }), Refusal::Origin);
    EXPECT_EQ(with([](RequestFacts& f) { f.origin = "http://127.0.0.1:8124"; }), Refusal::Origin);
    EXPECT_EQ(with([](RequestFacts& f) { f.authorization = ""; }), Refusal::Token);
    EXPECT_EQ(with([](RequestFacts& f) { f.authorization = "token secre"; }), Refusal::Token);
    EXPECT_EQ(with([](RequestFacts& f) { f.authorization = "token "; }), Refusal::Token);
    EXPECT_EQ(with([](RequestFacts& f) { f.authorization = "", f.cookie = "bounce-token-8123=secret"; }), Refusal::None);
    EXPECT_EQ(with([](RequestFacts& f) { f.authorization = "", f.cookie = "xbounce-token-8123=secret"; }), Refusal::Token);
    EXPECT_EQ(with([](RequestFacts& f) { f.authorization = "", f.query_token = "secret"; }), Refusal::None);
    EXPECT_EQ(with([](RequestFacts& f) { f.content_type = "text/plain"; }), Refusal::ContentType);
    EXPECT_EQ(with([](RequestFacts& f) { f.content_type = ""; }), Refusal::ContentType);
    EXPECT_EQ(with([](RequestFacts& f) { f.method = "GET", f.content_type = ""; }), Refusal::None);
    RequestFacts by_url = ok;
    by_url.authorization = "", by_url.query_token = "secret";
    EXPECT_TRUE(g.check(by_url).set_cookie);
    EXPECT_FALSE(g.check(ok).set_cookie);
    // Two sessions never share a token.
    EXPECT_NE(RequestGuard().token(), RequestGuard().token());
    EXPECT_EQ(RequestGuard().token().size(), 32u);
}

}  // namespace
}  // namespace bounce
