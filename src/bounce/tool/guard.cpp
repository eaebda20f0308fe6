#include "bounce/tool/guard.h"

#include <fmt/format.h>

#include <algorithm>
#include <cctype>
#include <random>

#include "bounce/core/files.h"
#include "bounce/tool/server.h"

namespace bounce {

namespace {

std::string trim(const std::string& s) {
    const size_t a = s.find_first_not_of(" \t"), b = s.find_last_not_of(" \t");
    return a == std::string::npos ? std::string() : s.substr(a, b - a + 1);
}

/// Equal strings, in a time that does not depend on where they first differ.
bool same_secret(const std::string& a, const std::string& b) {
    if (a.size() != b.size() || a.empty()) return false;
    unsigned char diff = 0;
    for (size_t i = 0; i < a.size(); ++i) diff = static_cast<unsigned char>(diff | (a[i] ^ b[i]));
    return diff == 0;
}

/// "host", "host:port", "[v6]" or "[v6]:port" -> host (without brackets) and port (-1: none).
bool split_authority(const std::string& authority, std::string& host, int& port) {
    std::string rest;
    if (!authority.empty() && authority[0] == '[') {
        const size_t close = authority.find(']');
        if (close == std::string::npos) return false;
        host = authority.substr(1, close - 1);
        rest = authority.substr(close + 1);
    } else {
        const size_t colon = authority.find(':');
        host = authority.substr(0, colon);
        rest = colon == std::string::npos ? "" : authority.substr(colon);
    }
    port = -1;
    if (rest.empty()) return !host.empty();
    if (rest[0] != ':' || rest.size() < 2 || rest.size() > 6) return false;
    port = 0;
    for (size_t i = 1; i < rest.size(); ++i) {
        if (!std::isdigit(static_cast<unsigned char>(rest[i]))) return false;
        port = port * 10 + (rest[i] - '0');
    }
    return !host.empty();
}

/// `authority` names this machine's loopback at `port` (no port: 80).
bool loopback_at(const std::string& authority, int port) {
    std::string host;
    int p = -1;
    return split_authority(ascii_lower(authority), host, p) && is_loopback_host(host) && (p < 0 ? 80 : p) == port;
}

std::string cookie_value(const std::string& header, const std::string& name) {
    size_t at = 0;
    while (at <= header.size()) {
        const size_t end = std::min(header.find(';', at), header.size());
        const std::string pair = trim(header.substr(at, end - at));
        if (pair.size() > name.size() && pair.compare(0, name.size(), name) == 0 && pair[name.size()] == '=')
            return pair.substr(name.size() + 1);
        at = end + 1;
    }
    return {};
}

}  // namespace

RequestGuard::RequestGuard(std::string token) : token_(std::move(token)) {
    if (!token_.empty()) return;
    std::random_device entropy;
    for (int i = 0; i < 4; ++i) token_ += fmt::format("{:08x}", entropy());
}

std::string RequestGuard::url(const std::string& host) const {
    const std::string shown = host.find(':') != std::string::npos ? "[" + host + "]" : host;
    return fmt::format("http://{}:{}/?token={}", shown, port_, token_);
}

std::string RequestGuard::cookie_name() const { return fmt::format("bounce-token-{}", port_); }

std::string RequestGuard::cookie() const { return fmt::format("{}={}; Path=/; HttpOnly; SameSite=Strict", cookie_name(), token_); }

Verdict RequestGuard::check(const RequestFacts& r) const {
    Verdict v;
    const auto refuse = [&](Refusal why, std::string message) {
        v.refusal = why, v.message = std::move(message);
        return v;
    };
    if (!loopback_at(r.host, port_))
        return refuse(Refusal::Host, fmt::format("Host '{}' is not this machine's loopback address at port {} (the tool serves "
                                                 "only the URL it printed)",
                                                 r.host, port_));
    if (!r.origin.empty() && !(ascii_lower(r.origin).rfind("http://", 0) == 0 && loopback_at(r.origin.substr(7), port_)))
        return refuse(Refusal::Origin, fmt::format("a page of origin '{}' may not use the lighting tool", r.origin));
    const std::string auth = trim(r.authorization);
    const bool by_header = ascii_lower(auth.substr(0, 6)) == "token " && same_secret(trim(auth.substr(6)), token_);
    const bool by_url = same_secret(r.query_token, token_);
    if (!by_header && !by_url && !same_secret(cookie_value(r.cookie, cookie_name()), token_))
        return refuse(Refusal::Token, r.query_token.empty() && auth.empty()
                                          ? "no session token: open the URL bounce light printed (it ends in ?token=...)"
                                          : "wrong session token");
    const std::string type = ascii_lower(trim(r.content_type.substr(0, r.content_type.find(';'))));
    if (r.method != "GET" && r.method != "HEAD" && type != "application/json")
        return refuse(Refusal::ContentType, fmt::format("{} needs a JSON body (Content-Type: application/json)", r.method));
    v.set_cookie = by_url;
    return v;
}

}  // namespace bounce
