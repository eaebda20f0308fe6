#include "bounce/core/progress.h"

#include <fmt/format.h>

#include <cstdio>

namespace bounce {

namespace {

std::string clock_text(double s) {
    int t = static_cast<int>(s + 0.5);
    return fmt::format("{}:{:02}", t / 60, t % 60);
}

class TerminalProgress : public ProgressSink {
  public:
    void update(const std::string& name, uint64_t done, uint64_t total, double elapsed) override {
        double f = total ? static_cast<double>(done) / static_cast<double>(total) : 1.0;
        int width = 30, filled = static_cast<int>(f * width);
        double remaining = f > 0 ? elapsed * (1 - f) / f : 0;
        std::fprintf(stderr, "\r%-10s [%s%s] %5.1f%%  %s | %s ", name.c_str(), std::string(static_cast<size_t>(filled), '=').c_str(),
                     std::string(static_cast<size_t>(width - filled), ' ').c_str(), 100 * f, clock_text(elapsed).c_str(),
                     clock_text(remaining).c_str());
        std::fflush(stderr);
    }
    void finish(const std::string& name, uint64_t total, double elapsed) override {
        update(name, total, total, elapsed);
        std::fprintf(stderr, "\n");
    }
};

class LogProgress : public ProgressSink {
  public:
    void update(const std::string& name, uint64_t done, uint64_t total, double elapsed) override {
        int quarter = total ? static_cast<int>(4 * done / total) : 4;
        if (name != name_) name_ = name, last_quarter_ = 0;
        if (quarter > last_quarter_ && quarter < 4) {
            last_quarter_ = quarter;
            std::fprintf(stderr, "%s: %d%% (%s elapsed)\n", name.c_str(), quarter * 25, clock_text(elapsed).c_str());
        }
    }
    void finish(const std::string& name, uint64_t, double elapsed) override {
        std::fprintf(stderr, "%s: done in %.2f s\n", name.c_str(), elapsed);
        name_.clear();
    }

  private:
    std::string name_;
    int last_quarter_ = 0;
};

class NullProgress : public ProgressSink {
  public:
    void update(const std::string&, uint64_t, uint64_t, double) override {}
    void finish(const std::string&, uint64_t, double) override {}
};

}  // namespace

std::unique_ptr<ProgressSink> make_terminal_progress() { return std::make_unique<TerminalProgress>(); }
std::unique_ptr<ProgressSink> make_log_progress() { return std::make_unique<LogProgress>(); }
std::unique_ptr<ProgressSink> make_null_progress() { return std::make_unique<NullProgress>(); }

Progress::Progress(ProgressSink* sink, std::string name, uint64_t total)
    : sink_(sink), name_(std::move(name)), total_(total), start_(std::chrono::steady_clock::now()) {}

Progress::~Progress() {
    if (!sink_) return;
    std::lock_guard lock(mutex_);
    sink_->finish(name_, total_, std::chrono::duration<double>(std::chrono::steady_clock::now() - start_).count());
}

void Progress::add(uint64_t n) {
    uint64_t done = done_.fetch_add(n) + n;
    if (!sink_) return;
    sink_->check_cancel();
    double t = std::chrono::duration<double>(std::chrono::steady_clock::now() - start_).count();
    if (t - last_report_.load(std::memory_order_relaxed) < 0.2 && done < total_) return;
    std::unique_lock lock(mutex_, std::try_to_lock);
    if (!lock.owns_lock()) return;
    last_report_.store(t, std::memory_order_relaxed);
    sink_->update(name_, done, total_, t);
}

}  // namespace bounce
