#include "bounce/tool/server.h"

#include <fmt/format.h>
#include <httplib.h>

#include <netdb.h>
#include <poll.h>
#include <sys/socket.h>

#include <cstdlib>
#include <cstring>
#include <filesystem>

#include "bounce/core/error.h"
#include "bounce/core/files.h"
#include "bounce/core/json_limits.h"
#include "bounce/tool/connections.h"

namespace bounce {

using nlohmann::json;

bool is_loopback_host(const std::string& host) {
    if (host == "localhost" || host == "::1") return true;
    unsigned a, b, c, d;
    char tail;
    return std::sscanf(host.c_str(), "%u.%u.%u.%u%c", &a, &b, &c, &d, &tail) == 4 && a == 127 && b < 256 && c < 256 && d < 256;
}

namespace {

/// A connected socket as httplib reads and writes it (its own stream type is not public).
class SocketStream : public httplib::Stream {
  public:
    explicit SocketStream(int socket) : socket_(socket) {}
    bool is_readable() const override { return wait(POLLIN); }
    bool is_writable() const override { return wait(POLLOUT); }
    ssize_t read(char* ptr, size_t size) override {
        // httplib reads headers a byte at a time: small reads come from a buffer.
        if (at_ == end_ && size < sizeof buffer_) {
            const ssize_t n = is_readable() ? ::recv(socket_, buffer_, sizeof buffer_, 0) : -1;
            if (n <= 0) return n;
            at_ = 0, end_ = static_cast<size_t>(n);
        }
        if (at_ < end_) {
            const size_t n = std::min(size, end_ - at_);
            std::memcpy(ptr, buffer_ + at_, n);
            at_ += n;
            return static_cast<ssize_t>(n);
        }
        return is_readable() ? ::recv(socket_, ptr, size, 0) : -1;
    }
    ssize_t write(const char* ptr, size_t size) override { return is_writable() ? ::send(socket_, ptr, size, MSG_NOSIGNAL) : -1; }
    void get_remote_ip_and_port(std::string& ip, int& port) const override { address(::getpeername, ip, port); }
    void get_local_ip_and_port(std::string& ip, int& port) const override { address(::getsockname, ip, port); }
    socket_t socket() const override { return socket_; }

  private:
    /// A client (a token holder: the guard has run) gets this long for each read or write.
    bool wait(short events) const {
        pollfd p{socket_, events, 0};
        return ::poll(&p, 1, 5000) > 0 && (p.revents & events);
    }
    void address(int (*get)(int, sockaddr*, socklen_t*), std::string& ip, int& port) const {
        sockaddr_storage a{};
        socklen_t len = sizeof a;
        char host[NI_MAXHOST] = "", serv[NI_MAXSERV] = "";
        port = 0;
        if (get(socket_, reinterpret_cast<sockaddr*>(&a), &len) != 0 ||
            ::getnameinfo(reinterpret_cast<sockaddr*>(&a), len, host, sizeof host, serv, sizeof serv, NI_NUMERICHOST | NI_NUMERICSERV) != 0)
            return;
        ip = host, port = std::atoi(serv);
    }
    int socket_;
    char buffer_[4096];
    size_t at_ = 0, end_ = 0;
};

}  // namespace

/// httplib's server with its connections passed through a ConnectionGate (connections.h): a
/// worker takes a connection only once its headers are whole, and each serves one request.
class GatedHttpServer : public httplib::Server {
  public:
    explicit GatedHttpServer(GateLimits limits)
        : gate_(limits, [this](int socket) {
              SocketStream stream(socket);
              bool closed = false;
              process_request(stream, true, closed, nullptr);
              gate_.close_gently(socket);
          }) {
        new_task_queue = [] { return new httplib::ThreadPool(2); };  // they only hand sockets to the gate
    }
    /// httplib listens with a backlog of 5 (compiled in): a burst of POSTs overflowed it and
    /// was reset. Linux takes a second listen() as a new backlog.
    void raise_backlog() { ::listen(svr_sock_, SOMAXCONN); }

  private:
    // httplib's accept loop hands each socket here (a private virtual may be overridden).
    bool process_and_close_socket(socket_t sock) override {
        gate_.admit(sock);
        return true;
    }
    ConnectionGate gate_;
};

namespace {

// Nothing is compressed: the tool answers on loopback, where compression is pure cost, and
// httplib (Debian's, built with Brotli) answers a browser's "br" at Brotli's slowest quality:
// 37 s for Sponza's 18.7 MB of record JSON, 3.7 s for three.js. httplib compresses only the
// content types it lists exactly (and text/*), so a charset parameter keeps JSON and scripts as they are.
constexpr const char* kJson = "application/json; charset=utf-8";

void reply(httplib::Response& res, int status, const json& body) {
    res.status = status;
    res.set_content(body.dump(), kJson);
}

/// View arrays as one JSON object, or with `format=binary` as float32 bytes (4.1 MB for
/// Sponza's 92 608 records against 18.7 MB of JSON) with their layout in the X-Meta header.
void reply_arrays(const httplib::Request& req, httplib::Response& res, const ViewArrays& v) {
    const std::string format = req.has_param("format") ? req.get_param_value("format") : "json";
    if (format == "json") return reply(res, 200, v.to_json());
    if (format != "binary") throw InputError("request", "format", fmt::format("'{}' is json or binary", format.substr(0, 40)));
    res.set_header("X-Meta", v.layout().dump());
    res.set_content(v.bytes(), "application/octet-stream");
}

/// The request's JSON body, an object of `keys` only; InputError naming the byte of a syntax
/// error or the first key the route does not take (a misspelt key is not ignored).
json body_object(const httplib::Request& req, std::initializer_list<const char*> keys) {
    json j;
    check_json_nesting(req.body, "request body");
    try {
        j = json::parse(req.body);
    } catch (const json::parse_error& e) {
        throw InputError("request body", fmt::format("byte {}", e.byte), "malformed JSON");
    } catch (const json::out_of_range&) {  // a number past a double (1e999): HTTP 400, not 500
        throw InputError("request body", "", "a number is not finite");
    }
    if (!j.is_object()) throw InputError("request body", "", "a JSON object is expected");
    for (auto it = j.begin(); it != j.end(); ++it)  // (clang 14 cannot capture a structured binding)
        if (const std::string& key = it.key(); std::none_of(keys.begin(), keys.end(), [&](const char* k) { return key == k; })) {
            std::string known;
            for (const char* k : keys) known += fmt::format("{}\"{}\"", known.empty() ? "" : ", ", k);
            throw InputError("request body", key.substr(0, 40), fmt::format("unknown key (this request takes {})", known));
        }
    return j;
}

std::string string_field(const json& j, const char* key) {
    if (!j.contains(key) || !j[key].is_string()) throw InputError("request body", key, "a string is required");
    return j[key].get<std::string>();
}

/// A query parameter as an integer in [lo, hi] (default when absent).
long long int_param(const httplib::Request& req, const char* key, long long def, long long lo, long long hi) {
    if (!req.has_param(key)) return def;
    const std::string v = req.get_param_value(key);
    try {
        size_t used = 0;
        long long x = std::stoll(v, &used);
        if (used == v.size() && x >= lo && x <= hi) return x;
    } catch (const std::exception&) {}
    throw InputError("request", key, fmt::format("'{}' is not an integer in [{}, {}]", v, lo, hi));
}

float float_param(const httplib::Request& req, const char* key, float def) {
    if (!req.has_param(key)) return def;
    const std::string v = req.get_param_value(key);
    try {
        size_t used = 0;
        float x = std::stof(v, &used);
        if (used == v.size() && std::isfinite(x)) return x;
    } catch (const std::exception&) {}
    throw InputError("request", key, fmt::format("'{}' is not a finite number", v));
}

/// The body's "crop" [x0, x1, y0, y1] (absent or null: none); InputError when it is not a
/// non-empty rectangle of integers in range.
std::optional<std::array<int, 4>> crop_field(const json& b) {
    if (!b.contains("crop") || b["crop"].is_null()) return std::nullopt;
    const json& c = b["crop"];
    if (!c.is_array() || c.size() != 4 || !std::all_of(c.begin(), c.end(), [](const json& v) { return v.is_number_integer(); }))
        throw InputError("request body", "crop", "four integers [x0, x1, y0, y1] are required");
    std::array<int, 4> crop{};
    for (size_t i = 0; i < 4; ++i) {
        const auto v = c[i].get<long long>();
        if (v < 0 || v > 1 << 20) throw InputError("request body", fmt::format("crop/{}", i), "out of range");
        crop[i] = static_cast<int>(v);
    }
    if (crop[0] >= crop[1] || crop[2] >= crop[3])
        throw InputError("request body", "crop", "an empty region: x0 < x1 and y0 < y1 are required");
    return crop;
}

/// The query's region=x0,x1,y0,y1 (absent: none); InputError when it is not four integers.
std::optional<std::array<int, 4>> region_param(const httplib::Request& req) {
    if (!req.has_param("region")) return std::nullopt;
    std::array<int, 4> r{};
    const std::string v = req.get_param_value("region");
    int used = 0;
    if (std::sscanf(v.c_str(), "%d,%d,%d,%d%n", &r[0], &r[1], &r[2], &r[3], &used) != 4 || used != static_cast<int>(v.size()))
        throw InputError("request", "region", fmt::format("'{}' is not x0,x1,y0,y1", v.substr(0, 40)));
    if (r[0] < 0 || r[2] < 0 || r[0] >= r[1] || r[2] >= r[3])
        throw InputError("request", "region", fmt::format("'{}' is an empty region: 0 <= x0 < x1 and 0 <= y0 < y1 are required", v));
    return r;
}

}  // namespace

LightingServer::LightingServer(LightingSession& session, ServerOptions options)
    : session_(session),
      options_(std::move(options)),
      guard_(options_.token),
      http_(std::make_unique<GatedHttpServer>(GateLimits{options_.header_time})) {
    if (!is_loopback_host(options_.host))
        throw InputError("command line", "--bind",
                         fmt::format("'{}' is not a loopback address; the tool serves this machine only", options_.host));
    if (options_.port < 0 || options_.port > 65535) throw InputError("command line", "--port", "must be in [0, 65535]");
    routes();
}

LightingServer::~LightingServer() = default;

int LightingServer::bind() {
    const int port = options_.port == 0 ? http_->bind_to_any_port(options_.host)
                                        : (http_->bind_to_port(options_.host, options_.port) ? options_.port : -1);
    if (port <= 0) throw InputError("command line", "--port", fmt::format("cannot listen on {}:{}", options_.host, options_.port));
    static_cast<GatedHttpServer&>(*http_).raise_backlog();  // httplib's is 5: a burst of POSTs overflowed it
    guard_.bind(port);
    return port;
}

void LightingServer::listen() { http_->listen_after_bind(); }

void LightingServer::stop() { http_->stop(); }

void LightingServer::routes() {
    httplib::Server& s = *http_;
    s.set_payload_max_length(options_.max_body);
    // Every handler's errors become a status and a one-line message; the server never dies.
    s.set_exception_handler([](const httplib::Request&, httplib::Response& res, std::exception_ptr ep) {
        try {
            std::rethrow_exception(ep);
        } catch (const InputError& e) {
            reply(res, 400, {{"error", e.what()}});
        } catch (const std::exception& e) {
            reply(res, 500, {{"error", e.what()}});
        } catch (...) {
            reply(res, 500, {{"error", "unknown error"}});
        }
    });
    // Before any route or file: only the page the printed URL opened (guard.h). A refused
    // request changes nothing and learns nothing but why.
    s.set_pre_routing_handler([this](const httplib::Request& req, httplib::Response& res) {
        const Verdict v = guard_.check({req.method, req.get_header_value("Host"), req.get_header_value("Origin"),
                                        req.get_header_value("Content-Type"), req.get_header_value("Authorization"),
                                        req.get_header_value("Cookie"), req.has_param("token") ? req.get_param_value("token") : ""});
        if (v.refusal != Refusal::None) {
            reply(res, 403, {{"error", v.message}});
            return httplib::Server::HandlerResponse::Handled;
        }
        // httplib reads a chunked body whole, past the payload limit: only a body of known
        // length is read (a browser's fetch always sends one).
        if (ascii_lower(req.get_header_value("Transfer-Encoding")).find("chunked") != std::string::npos) {
            reply(res, 411, {{"error", "a request body needs a Content-Length (chunked bodies are refused)"}});
            return httplib::Server::HandlerResponse::Handled;
        }
        if (v.set_cookie) res.set_header("Set-Cookie", guard_.cookie());
        return httplib::Server::HandlerResponse::Unhandled;
    });
    // No page of another origin may frame the tool: every answer says so (connections.h).
    s.set_post_routing_handler([](const httplib::Request&, httplib::Response& res) {
        for (const auto& [name, value] : kNoFramingHeaders) res.set_header(name, value);
    });
    s.set_error_handler([](const httplib::Request& req, httplib::Response& res) {
        if (res.body.empty())
            reply(res, res.status,
                  {{"error",
                    res.status == 413 ? "request body too large" : fmt::format("{} {}: status {}", req.method, req.path, res.status)}});
    });
    render_routes(s);
    view_routes(s);
    // httplib compresses every text/* type: scripts go as application/javascript (a JavaScript
    // MIME type browsers take for modules) with a charset, which it leaves alone.
    for (const char* ext : {"js", "mjs"}) s.set_file_extension_and_mimetype_mapping(ext, "application/javascript; charset=utf-8");
    if (!options_.web_dir.empty()) s.set_mount_point("/", options_.web_dir);
    if (!options_.three_dir.empty() && std::filesystem::is_directory(options_.three_dir))
        s.set_mount_point("/vendor/three", options_.three_dir);
}

void LightingServer::render_routes(httplib::Server& s) {
    s.Get("/api/params", [this](const httplib::Request&, httplib::Response& res) { reply(res, 200, session_.params()); });
    s.Post("/api/edit", [this](const httplib::Request& req, httplib::Response& res) {
        const json b = body_object(req, {"key", "value"});
        if (!b.contains("value")) throw InputError("request body", "value", "a value is required");
        reply(res, 200, session_.edit(string_field(b, "key"), b["value"]));
    });
    s.Post("/api/render", [this](const httplib::Request& req, httplib::Response& res) {
        const json b = body_object(req, {"action", "crop"});
        const SessionAction action = b.contains("action") ? parse_session_action(string_field(b, "action")) : session_.pending();
        const std::optional<std::array<int, 4>> crop = crop_field(b);
        session_.start(action, crop);
        reply(res, 202, {{"started", session_action_name(action)}});
    });
    s.Post("/api/frame", [this](const httplib::Request& req, httplib::Response& res) {
        const json b = body_object(req, {"frame"});
        if (!b.contains("frame") || !b["frame"].is_number()) throw InputError("request body", "frame", "a frame number is required");
        reply(res, 202, session_.set_frame(b["frame"].get<double>()));
    });
    s.Post("/api/stop", [this](const httplib::Request&, httplib::Response& res) {
        session_.stop();
        reply(res, 200, session_.status());
    });
    s.Get("/api/status", [this](const httplib::Request&, httplib::Response& res) { reply(res, 200, session_.status()); });
}

void LightingServer::view_routes(httplib::Server& s) {
    s.Get("/api/image", [this](const httplib::Request& req, httplib::Response& res) {
        const std::string layer = req.has_param("layer") ? req.get_param_value("layer") : "beauty";
        LightingSession::Pixels p = session_.pixels(layer, float_param(req, "exposure", 0));
        res.set_header("X-Width", std::to_string(p.width));
        res.set_header("X-Height", std::to_string(p.height));
        res.set_header("X-Version", std::to_string(p.version));
        res.set_content(std::move(p.rgba), "application/octet-stream");
    });
    s.Get("/api/records", [this](const httplib::Request& req, httplib::Response& res) {
        const std::string file = req.has_param("file") ? req.get_param_value("file") : "";
        const std::optional<std::array<int, 4>> region = region_param(req);
        reply_arrays(req, res, session_.records(file, static_cast<size_t>(int_param(req, "limit", 200000, 0, 10000000)), region));
    });
    s.Get("/api/caches", [this](const httplib::Request&, httplib::Response& res) { reply(res, 200, session_.cache_files()); });
    s.Get("/api/scene", [this](const httplib::Request& req, httplib::Response& res) {
        reply_arrays(req, res, session_.scene_view(static_cast<size_t>(int_param(req, "max_triangles", 100000, 1, 10000000))));
    });
    s.Post("/api/save-scene", [this](const httplib::Request& req, httplib::Response& res) {
        reply(res, 200, {{"saved", session_.save_scene(string_field(body_object(req, {"name"}), "name"))}});
    });
    s.Post("/api/save-cache", [this](const httplib::Request& req, httplib::Response& res) {
        reply(res, 200, {{"saved", session_.save_cache(string_field(body_object(req, {"name"}), "name"))}});
    });
    s.Post("/api/load-cache", [this](const httplib::Request& req, httplib::Response& res) {
        session_.load_cache(string_field(body_object(req, {"file"}), "file"));
        reply(res, 200, session_.status());
    });
}

}  // namespace bounce
