// Issue 65, the lighting tool's connections: every answer forbids framing (clickjacking), a
// chunked body is refused before it is read, a burst of POSTs is answered (200 or 503, never a
// reset), slow clients that trickle their headers neither hold a worker nor stop the tool
// serving others, and a request body's unknown keys are refused by name.
#include <arpa/inet.h>
#include <netinet/in.h>
#include <poll.h>
#include <sys/socket.h>
#include <unistd.h>

#include <atomic>
#include <chrono>
#include <vector>

#include "tool_util.h"

namespace bounce {
namespace {

using nlohmann::json;
using Clock = std::chrono::steady_clock;

/// A raw loopback connection to `port` (-1 when it cannot connect).
int connect_to(int port) {
    const int s = ::socket(AF_INET, SOCK_STREAM, 0);
    sockaddr_in a{};
    a.sin_family = AF_INET;
    a.sin_port = htons(static_cast<uint16_t>(port));
    a.sin_addr.s_addr = htonl(INADDR_LOOPBACK);
    if (::connect(s, reinterpret_cast<sockaddr*>(&a), sizeof a) != 0) {
        ::close(s);
        return -1;
    }
    return s;
}

bool send_all(int s, const std::string& bytes) {
    return ::send(s, bytes.data(), bytes.size(), MSG_NOSIGNAL) == static_cast<ssize_t>(bytes.size());
}

/// What the server sends until it closes (or `seconds` pass); "RESET" when the connection was reset.
std::string read_answer(int s, double seconds = 20) {
    std::string got;
    const auto until = Clock::now() + std::chrono::duration<double>(seconds);
    char buf[4096];
    while (Clock::now() < until) {
        pollfd p{s, POLLIN, 0};
        if (::poll(&p, 1, 100) <= 0) continue;
        const ssize_t n = ::recv(s, buf, sizeof buf, 0);
        if (n < 0) return errno == ECONNRESET ? "RESET" : "ERROR";
        if (n == 0) break;
        got.append(buf, static_cast<size_t>(n));
    }
    return got;
}

/// What the server sends on each socket until it closes it, all read together until `seconds`
/// pass; "RESET" for a connection that was reset. Closes the sockets.
std::vector<std::string> read_answers(const std::vector<int>& sockets, double seconds) {
    std::vector<std::string> got(sockets.size());
    std::vector<bool> open(sockets.size(), true);
    const auto until = Clock::now() + std::chrono::duration<double>(seconds);
    char buf[4096];
    for (size_t left = sockets.size(); left > 0 && Clock::now() < until;) {
        std::vector<pollfd> fds;
        std::vector<size_t> which;
        for (size_t i = 0; i < sockets.size(); ++i)
            if (open[i]) fds.push_back({sockets[i], POLLIN, 0}), which.push_back(i);
        if (::poll(fds.data(), fds.size(), 100) <= 0) continue;
        for (size_t k = 0; k < fds.size(); ++k) {
            if (!fds[k].revents) continue;
            const size_t i = which[k];
            const ssize_t n = ::recv(sockets[i], buf, sizeof buf, 0);
            if (n > 0) {
                got[i].append(buf, static_cast<size_t>(n));
                continue;
            }
            if (n < 0) got[i] = errno == ECONNRESET ? "RESET" : "ERROR";
            open[i] = false, --left;
        }
    }
    for (const int s : sockets) ::close(s);
    return got;
}

std::string request_head(const test::Served& s, const std::string& method, const std::string& path) {
    return fmt::format("{} {} HTTP/1.1\r\nHost: 127.0.0.1:{}\r\nAuthorization: token {}\r\n", method, path, s.port, s.server.token());
}

TEST(LightingToolConnections, EveryAnswerForbidsFramingByAnotherOrigin) {
    test::Served s;
    httplib::Client bare("127.0.0.1", s.port);  // no token: refused
    std::vector<httplib::Result> answers;
    answers.push_back(s.client.Get("/api/params?token=" + s.server.token()));
    answers.push_back(s.client.Get("/api/status"));
    answers.push_back(s.client.Get("/api/nothing"));
    answers.push_back(bare.Get("/"));
    answers.push_back(s.client.Post("/api/edit", "{}", "application/json"));
    const int statuses[] = {200, 200, 404, 403, 400};
    for (size_t i = 0; i < answers.size(); ++i) {
        ASSERT_TRUE(answers[i]) << i;
        EXPECT_EQ(answers[i]->status, statuses[i]) << i;
        EXPECT_EQ(answers[i]->get_header_value("X-Frame-Options"), "DENY") << i;
        EXPECT_EQ(answers[i]->get_header_value("Content-Security-Policy"), "frame-ancestors 'none'") << i;
    }
}

TEST(LightingToolConnections, AChunkedBodyIsRefusedBeforeItIsRead) {
    test::Served s;
    const json edits = s.session.status()["edits"];
    const int c = connect_to(s.port);
    ASSERT_GE(c, 0);
    ASSERT_TRUE(send_all(c, request_head(s, "POST", "/api/edit") +
                                "Content-Type: application/json\r\nTransfer-Encoding: chunked\r\n\r\n100000\r\n" +
                                std::string(1 << 20, ' ')));
    // Refused at once, although 300 MB more could follow.
    const std::string answer = read_answer(c, 10);
    ::close(c);
    EXPECT_EQ(answer.rfind("HTTP/1.1 411", 0), 0u) << answer.substr(0, 200);
    EXPECT_NE(answer.find("Content-Length"), std::string::npos);
    EXPECT_EQ(s.session.status()["edits"], edits);
}

TEST(LightingToolConnections, ABurstOfPostsIsAnsweredNeverReset) {
    test::Served s;
    constexpr int kBurst = 96;
    std::vector<int> sockets;
    const std::string body = R"({"key":"render.min_spacing","value":2.0})";
    // All connected before any is answered: far past httplib's backlog of 5.
    for (int i = 0; i < kBurst; ++i) sockets.push_back(connect_to(s.port));
    for (const int c : sockets) {
        ASSERT_GE(c, 0);
        ASSERT_TRUE(send_all(c, request_head(s, "POST", "/api/edit") +
                                    fmt::format("Content-Type: application/json\r\nContent-Length: {}\r\n\r\n{}", body.size(), body)));
    }
    // Read all at once under one deadline: the edits run one at a time, and a socket whose edit
    // waits for the other 95 (under TSan on a loaded CI machine, 20 s) is still answered.
    const std::vector<std::string> answers = read_answers(sockets, 180);
    int ok = 0, busy = 0;
    for (const std::string& a : answers) {
        if (a.rfind("HTTP/1.1 200", 0) == 0)
            ++ok;
        else if (a.rfind("HTTP/1.1 503", 0) == 0 && a.find("Retry-After: 1") != std::string::npos)
            ++busy;
        else
            ADD_FAILURE() << "not answered: " << a.substr(0, 80);
    }
    EXPECT_EQ(ok + busy, kBurst);
    EXPECT_GT(ok, 0);
}

TEST(LightingToolConnections, SlowHeadersHoldNoWorkerAndAreTimedOut) {
    test::TempDir dir;
    LightingSession session(test::small_session(dir));
    ServerOptions options;
    options.header_time = std::chrono::milliseconds(3000);
    LightingServer server(session, options);
    const int port = server.bind();
    std::thread listening([&] { server.listen(); });
    // 80 clients that send half a request (more than the 32 workers), and never the rest.
    std::vector<int> slow;
    for (int i = 0; i < 80; ++i) {
        slow.push_back(connect_to(port));
        ASSERT_TRUE(send_all(slow.back(), fmt::format("GET /api/status HTTP/1.1\r\nHost: 127.0.0.1:{}\r\nX-Slow: ", port)));
    }
    // Anyone else is served at once meanwhile.
    httplib::Client client("127.0.0.1", port);
    client.set_default_headers({{"Authorization", "token " + server.token()}});
    for (int i = 0; i < 5; ++i) {
        const auto r = client.Get("/api/status");
        ASSERT_TRUE(r);
        EXPECT_EQ(r->status, 200);
    }
    // ... while the slow ones still wait: none has been answered yet.
    int answered = 0;
    for (const int c : slow) {
        pollfd p{c, POLLIN, 0};
        answered += ::poll(&p, 1, 0) > 0;
    }
    EXPECT_EQ(answered, 0) << "the 80 slow clients were timed out before the others were served";
    // The slow ones are answered 408 once their time is up, and closed.
    for (const int c : slow) {
        const std::string a = read_answer(c, 10);
        EXPECT_EQ(a.rfind("HTTP/1.1 408", 0), 0u) << a.substr(0, 80);
        ::close(c);
    }
    server.stop();
    listening.join();
}

TEST(LightingToolConnections, UnknownKeysAndEmptyRegionsAreRefusedByName) {
    test::Served s;
    const json edits = s.session.status()["edits"];
    auto r = s.client.Post("/api/edit", R"({"key":"render.min_spacing","value":2.5,"pad":"x"})", "application/json");
    ASSERT_TRUE(r);
    EXPECT_EQ(r->status, 400);
    EXPECT_NE(r->body.find("pad: error: unknown key"), std::string::npos) << r->body;
    EXPECT_EQ(s.session.status()["edits"], edits);  // nothing changed
    r = s.client.Post("/api/render", R"({"action":"reshade","region":[0,1,0,1]})", "application/json");
    EXPECT_EQ(r->status, 400);
    EXPECT_NE(r->body.find("region"), std::string::npos) << r->body;
    for (const char* region : {"10,0,0,10", "4,4,4,4", "-1,3,0,3"}) {
        r = s.client.Get(std::string("/api/records?region=") + region);
        ASSERT_TRUE(r);
        EXPECT_EQ(r->status, 400) << region;
        EXPECT_NE(r->body.find("empty region"), std::string::npos) << r->body;
    }
}

}  // namespace
}  // namespace bounce
