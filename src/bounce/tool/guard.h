// Who may drive the lighting tool: the one page its URL opens (docs/lighting-tool.md,
// "Security"). The model is Jupyter's server: a random token per session in the printed URL,
// kept by the page as a cookie; a Host that names this machine and the bound port (DNS
// rebinding); an Origin, when a browser sends one, that is the tool's own (a page elsewhere,
// even another port of this machine, posting to it); and JSON for every request that changes
// something (a "simple" cross-origin POST needs no preflight). Plain strings in, a typed
// verdict out: the server (server.cpp) reads the headers, tests read nothing else.
#pragma once

#include <string>

namespace bounce {

/// What the guard reads of a request.
struct RequestFacts {
    std::string method;         ///< "GET", "POST" ...
    std::string host;           ///< the Host header ("" when absent)
    std::string origin;         ///< the Origin header ("" when absent)
    std::string content_type;   ///< the Content-Type header
    std::string authorization;  ///< the Authorization header ("token T")
    std::string cookie;         ///< the Cookie header
    std::string query_token;    ///< the URL's ?token= ("" when absent)
};

enum class Refusal {
    None,         ///< served
    Host,         ///< Host is not this machine's loopback name at the bound port
    Origin,       ///< a page of another origin sent it
    Token,        ///< no token, or another one
    ContentType,  ///< a request that changes state without application/json
};

struct Verdict {
    Refusal refusal = Refusal::None;
    std::string message;      ///< why, for the 403 body (empty when served)
    bool set_cookie = false;  ///< the token came in the URL: give the page its cookie
};

class RequestGuard {
  public:
    /// A new random token (128 bits from the system's entropy source) unless `token` is given.
    explicit RequestGuard(std::string token = {});
    void bind(int port) { port_ = port; }
    const std::string& token() const { return token_; }
    /// The URL to open: http://HOST:PORT/?token=T (IPv6 hosts in brackets).
    std::string url(const std::string& host) const;
    /// The cookie's name: one per port, so two tools on one machine keep their own.
    std::string cookie_name() const;
    /// The Set-Cookie value for a page that came with the token in its URL: HttpOnly,
    /// SameSite=Strict (never sent by another site's page).
    std::string cookie() const;
    Verdict check(const RequestFacts& r) const;

  private:
    std::string token_;
    int port_ = 0;
};

}  // namespace bounce
