#include "bounce/tool/server.h"

#include <fmt/format.h>
#include <httplib.h>

#include <filesystem>

#include "bounce/core/error.h"
#include "bounce/core/json_limits.h"

namespace bounce {

using nlohmann::json;

bool is_loopback_host(const std::string& host) {
    if (host == "localhost" || host == "::1") return true;
    unsigned a, b, c, d;
    char tail;
    return std::sscanf(host.c_str(), "%u.%u.%u.%u%c", &a, &b, &c, &d, &tail) == 4 && a == 127 && b < 256 && c < 256 && d < 256;
}

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

/// The request's JSON body, an object; InputError naming the byte of a syntax error.
json body_object(const httplib::Request& req) {
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
    } catch (const std::exception&) {
    }
    throw InputError("request", key, fmt::format("'{}' is not an integer in [{}, {}]", v, lo, hi));
}

float float_param(const httplib::Request& req, const char* key, float def) {
    if (!req.has_param(key)) return def;
    const std::string v = req.get_param_value(key);
    try {
        size_t used = 0;
        float x = std::stof(v, &used);
        if (used == v.size() && std::isfinite(x)) return x;
    } catch (const std::exception&) {
    }
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
        throw InputError("request", "region", fmt::format("'{}' is not x0,x1,y0,y1", v));
    return r;
}

}  // namespace

LightingServer::LightingServer(LightingSession& session, ServerOptions options)
    : session_(session), options_(std::move(options)), guard_(options_.token), http_(std::make_unique<httplib::Server>()) {
    if (!is_loopback_host(options_.host))
        throw InputError("command line", "--bind", fmt::format("'{}' is not a loopback address; the tool serves this machine only", options_.host));
    if (options_.port < 0 || options_.port > 65535) throw InputError("command line", "--port", "must be in [0, 65535]");
    // A browser keeps up to six idle connections per page: httplib's default 8 threads would
    // starve a second tab.
    http_->new_task_queue = [] { return new httplib::ThreadPool(32); };
    http_->set_keep_alive_timeout(2);
    routes();
}

LightingServer::~LightingServer() = default;

int LightingServer::bind() {
    const int port = options_.port == 0 ? http_->bind_to_any_port(options_.host)
                                        : (http_->bind_to_port(options_.host, options_.port) ? options_.port : -1);
    if (port <= 0) throw InputError("command line", "--port", fmt::format("cannot listen on {}:{}", options_.host, options_.port));
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
        if (v.set_cookie) res.set_header("Set-Cookie", guard_.cookie());
        return httplib::Server::HandlerResponse::Unhandled;
    });
    s.set_error_handler([](const httplib::Request& req, httplib::Response& res) {
        if (res.body.empty())
            reply(res, res.status, {{"error", res.status == 413 ? "request body too large" : fmt::format("{} {}: status {}", req.method, req.path, res.status)}});
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
        const json b = body_object(req);
        if (!b.contains("value")) throw InputError("request body", "value", "a value is required");
        reply(res, 200, session_.edit(string_field(b, "key"), b["value"]));
    });
    s.Post("/api/render", [this](const httplib::Request& req, httplib::Response& res) {
        const json b = body_object(req);
        const SessionAction action = b.contains("action") ? parse_session_action(string_field(b, "action")) : session_.pending();
        const std::optional<std::array<int, 4>> crop = crop_field(b);
        session_.start(action, crop);
        reply(res, 202, {{"started", session_action_name(action)}});
    });
    s.Post("/api/frame", [this](const httplib::Request& req, httplib::Response& res) {
        const json b = body_object(req);
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
        reply(res, 200, {{"saved", session_.save_scene(string_field(body_object(req), "name"))}});
    });
    s.Post("/api/save-cache", [this](const httplib::Request& req, httplib::Response& res) {
        reply(res, 200, {{"saved", session_.save_cache(string_field(body_object(req), "name"))}});
    });
    s.Post("/api/load-cache", [this](const httplib::Request& req, httplib::Response& res) {
        session_.load_cache(string_field(body_object(req), "file"));
        reply(res, 200, session_.status());
    });
}

}  // namespace bounce
