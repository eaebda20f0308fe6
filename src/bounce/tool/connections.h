// Every connection to the lighting tool gets an answer, however many arrive and however slowly.
// httplib (Debian's 0.11) hands each accepted socket to a worker that then waits for its
// headers with no deadline on the whole (a client trickling a byte a second holds the worker
// for good: 80 of them starve the tool), and listens with a backlog of 5 compiled in (a burst
// of POSTs overflows it and the kernel resets them). So the server raises the backlog, and a
// gate holds each new connection in one poll() loop until its headers have arrived whole (read
// with MSG_PEEK, so httplib reads them again as ever): only then does a worker take it. A
// connection whose headers do not arrive in time gets 408, one beyond the gate's room 503 with
// Retry-After; each is shut for writing and drained before it is closed, so no answer is lost
// to a reset. A connection serves one request (loopback connections cost nothing) so every
// request passes the gate.
#pragma once

#include <array>
#include <atomic>
#include <chrono>
#include <condition_variable>
#include <cstddef>
#include <deque>
#include <functional>
#include <mutex>
#include <thread>
#include <utility>
#include <vector>

namespace bounce {

/// What every answer says, the old way and the new: no page of another origin may frame the tool
/// (clickjacking: a click on an invisible frame would press its buttons).
inline constexpr std::array<std::pair<const char*, const char*>, 2> kNoFramingHeaders{
    {{"X-Frame-Options", "DENY"}, {"Content-Security-Policy", "frame-ancestors 'none'"}}};

struct GateLimits {
    std::chrono::milliseconds header_time{5000};  ///< from accept to the headers' blank line
    size_t max_waiting = 512;                     ///< connections whose headers are still arriving
    size_t max_queued = 256;                      ///< connections with whole headers that no worker has taken yet
    size_t workers = 32;                          ///< a browser keeps six connections a page; two tabs and a test
    size_t max_header_bytes = 16384;              ///< past this the request goes on as it is (httplib refuses it)
};

/// Holds connections until their headers are whole, then runs `serve(socket)` on a worker.
class ConnectionGate {
  public:
    using Serve = std::function<void(int socket)>;
    ConnectionGate(GateLimits limits, Serve serve);
    ~ConnectionGate();  ///< closes what waits, joins its threads
    ConnectionGate(const ConnectionGate&) = delete;
    ConnectionGate& operator=(const ConnectionGate&) = delete;

    /// Takes ownership of an accepted socket; returns at once.
    void admit(int socket);
    /// After an answer: shuts the socket for writing and drains it before closing (a close
    /// with unread bytes would reset the connection, and the client could lose the answer).
    void close_gently(int socket);

  private:
    struct Waiting {
        int socket;
        std::chrono::steady_clock::time_point deadline;
        bool closing = false;  ///< answered and shut for writing: drained until EOF or the deadline
    };
    void poll_loop();
    void work_loop();
    /// The socket's headers so far (peeked): whole, still arriving, or the peer has gone.
    enum class Headers { Whole, Partial, Gone };
    Headers peek(int socket) const;
    void hand_over(int socket);  ///< to the workers, or 503 when their queue is full
    /// Writes the answer, shuts the socket for writing and leaves it to the poll loop to drain
    /// (closing with unread bytes would reset the connection and could lose the answer).
    void refuse(int socket, int status, const char* reason, const char* message);
    void wake();

    GateLimits limits_;
    Serve serve_;
    int wake_pipe_[2] = {-1, -1};
    std::mutex mutex_;
    std::condition_variable work_;
    std::vector<Waiting> admitted_;  ///< new (or refused) sockets for the poll loop
    std::atomic<size_t> held_{0};    ///< sockets in admitted_ and waiting_
    std::vector<Waiting> waiting_;   ///< the poll loop's own
    std::deque<int> ready_;
    bool quit_ = false;
    std::thread poller_;
    std::vector<std::thread> workers_;
};

}  // namespace bounce
