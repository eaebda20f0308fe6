#include "bounce/tool/connections.h"

#include <fcntl.h>
#include <poll.h>
#include <sys/socket.h>
#include <unistd.h>

#include <fmt/format.h>

#include <algorithm>
#include <cerrno>
#include <stdexcept>
#include <string>

namespace bounce {

namespace {

using Clock = std::chrono::steady_clock;

constexpr const char* kBusy = "the lighting tool is busy: try again";

/// A whole HTTP response with a JSON error body (the server's own headers included: a refusal
/// is framed no more than an answer is).
std::string error_response(int status, const char* reason, const char* message) {
    const std::string body = fmt::format("{{\"error\":\"{}\"}}", message);
    std::string head = fmt::format(
        "HTTP/1.1 {} {}\r\nContent-Type: application/json; charset=utf-8\r\nContent-Length: {}\r\n"
        "Connection: close\r\n",
        status, reason, body.size());
    for (const auto& [name, value] : kNoFramingHeaders) head += fmt::format("{}: {}\r\n", name, value);
    if (status == 503) head += "Retry-After: 1\r\n";
    return head + "\r\n" + body;
}

void write_all(int socket, const std::string& bytes) {
    size_t at = 0;
    while (at < bytes.size()) {
        const ssize_t n = ::send(socket, bytes.data() + at, bytes.size() - at, MSG_NOSIGNAL | MSG_DONTWAIT);
        if (n <= 0) return;  // a tiny answer fits any socket buffer; a client that does not read loses it
        at += static_cast<size_t>(n);
    }
}

}  // namespace

ConnectionGate::ConnectionGate(GateLimits limits, Serve serve) : limits_(limits), serve_(std::move(serve)) {
    if (::pipe2(wake_pipe_, O_CLOEXEC | O_NONBLOCK) != 0) throw std::runtime_error("connection gate: cannot make a pipe");
    poller_ = std::thread([this] { poll_loop(); });
    for (size_t i = 0; i < limits_.workers; ++i) workers_.emplace_back([this] { work_loop(); });
}

ConnectionGate::~ConnectionGate() {
    {
        std::lock_guard lock(mutex_);
        quit_ = true;
    }
    wake();
    work_.notify_all();
    poller_.join();
    for (std::thread& t : workers_) t.join();
    for (const Waiting& w : admitted_) ::close(w.socket);
    for (const Waiting& w : waiting_) ::close(w.socket);
    for (int s : ready_) ::close(s);
    ::close(wake_pipe_[0]);
    ::close(wake_pipe_[1]);
}

void ConnectionGate::wake() {
    const char one = 1;
    [[maybe_unused]] const ssize_t n = ::write(wake_pipe_[1], &one, 1);  // a full pipe is already awake
}

void ConnectionGate::admit(int socket) {
    // Past the room for waiting connections the answer is written here and the socket still
    // goes to the poll loop, to be drained (held_ counts both, so a flood cannot grow it).
    const bool room = held_.load() < limits_.max_waiting;
    if (!room) write_all(socket, error_response(503, "Service Unavailable", kBusy)), ::shutdown(socket, SHUT_WR);
    {
        std::lock_guard lock(mutex_);
        if (quit_) return void(::close(socket));
        admitted_.push_back({socket, Clock::now() + (room ? limits_.header_time : std::chrono::milliseconds(1000)), !room});
        ++held_;
    }
    wake();
}

void ConnectionGate::refuse(int socket, int status, const char* reason, const char* message) {
    write_all(socket, error_response(status, reason, message));
    ::shutdown(socket, SHUT_WR);
    waiting_.push_back({socket, Clock::now() + std::chrono::milliseconds(1000), true});
    ++held_;
}

void ConnectionGate::close_gently(int socket) {
    ::shutdown(socket, SHUT_WR);
    {
        std::lock_guard lock(mutex_);
        if (quit_) return void(::close(socket));
        admitted_.push_back({socket, Clock::now() + std::chrono::milliseconds(1000), true});
        ++held_;
    }
    wake();
}

ConnectionGate::Headers ConnectionGate::peek(int socket) const {
    std::string buf(limits_.max_header_bytes, '\0');
    const ssize_t n = ::recv(socket, buf.data(), buf.size(), MSG_PEEK | MSG_DONTWAIT);
    if (n == 0) return Headers::Gone;
    if (n < 0) return errno == EAGAIN || errno == EWOULDBLOCK || errno == EINTR ? Headers::Partial : Headers::Gone;
    buf.resize(static_cast<size_t>(n));
    if (buf.find("\r\n\r\n") != std::string::npos || buf.find("\n\n") != std::string::npos) return Headers::Whole;
    return buf.size() >= limits_.max_header_bytes ? Headers::Whole : Headers::Partial;
}

void ConnectionGate::hand_over(int socket) {
    {
        std::lock_guard lock(mutex_);
        if (ready_.size() < limits_.max_queued) {
            ready_.push_back(socket);
            work_.notify_one();
            return;
        }
    }
    refuse(socket, 503, "Service Unavailable", kBusy);
}

void ConnectionGate::poll_loop() {
    std::vector<pollfd> fds;
    for (;;) {
        {
            std::lock_guard lock(mutex_);
            if (quit_) return;
            waiting_.insert(waiting_.end(), admitted_.begin(), admitted_.end());
            admitted_.clear();
        }
        fds.assign(1, pollfd{wake_pipe_[0], POLLIN, 0});
        for (const Waiting& w : waiting_) fds.push_back({w.socket, POLLIN, 0});
        ::poll(fds.data(), fds.size(), 200);
        if (fds[0].revents & POLLIN) {
            char drain[64];
            while (::read(wake_pipe_[0], drain, sizeof drain) > 0) {}
        }
        std::vector<Waiting> now_waiting;
        std::swap(now_waiting, waiting_);
        const auto now = Clock::now();
        for (size_t i = 0; i < now_waiting.size(); ++i) {
            const Waiting w = now_waiting[i];
            --held_;
            const bool readable = fds[i + 1].revents & (POLLIN | POLLHUP | POLLERR);
            if (w.closing) {  // drain what the refused client still sends; close at its end
                char sink[4096];
                const bool open = w.deadline > now && (!readable || ::recv(w.socket, sink, sizeof sink, MSG_DONTWAIT) > 0);
                if (open)
                    waiting_.push_back(w), ++held_;
                else
                    ::close(w.socket);
                continue;
            }
            const Headers h = readable ? peek(w.socket) : Headers::Partial;
            if (h == Headers::Whole)
                hand_over(w.socket);
            else if (h == Headers::Gone)
                ::close(w.socket);
            else if (w.deadline <= now)
                refuse(w.socket, 408, "Request Timeout", "the request's headers did not arrive in time");
            else
                waiting_.push_back(w), ++held_;
        }
    }
}

void ConnectionGate::work_loop() {
    for (;;) {
        int socket = -1;
        {
            std::unique_lock lock(mutex_);
            work_.wait(lock, [&] { return quit_ || !ready_.empty(); });
            if (quit_) return;
            socket = ready_.front();
            ready_.pop_front();
        }
        serve_(socket);
    }
}

}  // namespace bounce
