// The lighting tool's web front end: a loopback-only HTTP server (cpp-httplib) with a JSON API
// over LightingSession and the page's static files (web/, three.js from node_modules).
// docs/lighting-tool.md lists the API.
#pragma once

#include <chrono>
#include <cstddef>
#include <memory>
#include <string>

#include "bounce/tool/guard.h"
#include "bounce/tool/session.h"

namespace httplib {
class Server;
}

namespace bounce {

struct ServerOptions {
    std::string host = "127.0.0.1";  ///< only loopback addresses are accepted
    int port = 0;                    ///< 0 = any free port
    std::string web_dir;             ///< the page (index.html, app.js, style.css)
    std::string three_dir;           ///< node_modules/three (served as /vendor/three)
    size_t max_body = 4u << 20;      ///< larger request bodies are refused (413)
    std::string token;               ///< the session token (empty: a new random one)
    /// A connection's headers must arrive whole within this (then 408; connections.h).
    std::chrono::milliseconds header_time{5000};
};

class LightingServer {
  public:
    /// InputError (exit 2) when the host is not a loopback address.
    LightingServer(LightingSession& session, ServerOptions options);
    ~LightingServer();
    /// Binds; returns the port. InputError when it cannot.
    int bind();
    void listen();  ///< serves until stop()
    void stop();
    /// The URL to open (with the session token), once bound.
    std::string url() const { return guard_.url(options_.host); }
    const std::string& token() const { return guard_.token(); }

  private:
    void routes();                           ///< guard, errors, static files
    void render_routes(httplib::Server& s);  ///< edits, renders, frames, status
    void view_routes(httplib::Server& s);    ///< image, records, scene, files
    LightingSession& session_;
    ServerOptions options_;
    RequestGuard guard_;  ///< every request passes it first (guard.h)
    std::unique_ptr<httplib::Server> http_;
};

/// True for 127.0.0.1 (any 127/8), ::1 and localhost.
bool is_loopback_host(const std::string& host);

}  // namespace bounce
