// Progress reporting through one interface; the front end chooses how it is shown:
// a bar with ETA on a terminal, a few plain lines in a log, or nothing.
#pragma once

#include <atomic>
#include <chrono>
#include <cstdint>
#include <exception>
#include <memory>
#include <mutex>
#include <string>

namespace bounce {

/// Thrown by a pass when its CancelToken is set; the render leaves no output behind.
struct Cancelled : std::exception {
    const char* what() const noexcept override { return "cancelled"; }
};

/// Set from any thread to stop a running render; passes check it per row, tile and gather.
class CancelToken {
  public:
    void cancel() { flag_.store(true, std::memory_order_relaxed); }
    bool cancelled() const { return flag_.load(std::memory_order_relaxed); }
    void check() const {
        if (cancelled()) throw Cancelled();
    }

  private:
    std::atomic<bool> flag_{false};
};

class ProgressSink {
  public:
    virtual ~ProgressSink() = default;
    /// `done` of `total` units of phase `name`, `elapsed` seconds in. Called under a lock.
    virtual void update(const std::string& name, uint64_t done, uint64_t total, double elapsed) = 0;
    virtual void finish(const std::string& name, uint64_t total, double elapsed) = 0;
    /// Checked by every pass as it goes; null = never cancelled.
    const CancelToken* cancel = nullptr;
    void check_cancel() const {
        if (cancel) cancel->check();
    }
};

/// A bar redrawn in place with elapsed | remaining (for terminals).
std::unique_ptr<ProgressSink> make_terminal_progress();
/// One line per 25% (for logs).
std::unique_ptr<ProgressSink> make_log_progress();
/// Reports nothing.
std::unique_ptr<ProgressSink> make_null_progress();

/// Thread-safe counter for one phase; throttles calls into the sink.
class Progress {
  public:
    Progress(ProgressSink* sink, std::string name, uint64_t total);
    ~Progress();
    void add(uint64_t n = 1);
    Progress(const Progress&) = delete;
    Progress& operator=(const Progress&) = delete;

  private:
    ProgressSink* sink_;
    std::string name_;
    uint64_t total_;
    std::atomic<uint64_t> done_{0};
    std::chrono::steady_clock::time_point start_;
    std::mutex mutex_;
    std::atomic<double> last_report_{-1};  ///< relaxed: only throttles reports
};

}  // namespace bounce
