// Every parallel loop of bounce goes through here. Normally TBB's parallel_for. Under
// ThreadSanitizer the loop runs on plain std::threads instead: libtbb is not instrumented, so
// TSan cannot see TBB's fork-join ordering and reports TBB's own task hand-offs as races.
// std::threads (intercepted by TSan) keep the check about our code: two bodies of one loop
// that touch the same data unsynchronised are still reported.
#pragma once

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>
#include <tbb/task_arena.h>

#if defined(__SANITIZE_THREAD__)
#define BOUNCE_TSAN 1
#elif defined(__has_feature)
#if __has_feature(thread_sanitizer)
#define BOUNCE_TSAN 1
#endif
#endif

#ifdef BOUNCE_TSAN
#include <algorithm>
#include <atomic>
#include <exception>
#include <mutex>
#include <thread>
#include <vector>
#endif

namespace bounce {

/// fn(lo, hi) over sub-ranges of [begin, end) of at least `grain` items (TBB's auto
/// partitioner), or of exactly `grain` items when `simple` (one range = one task).
template <typename Index, typename Fn>
void parallel_ranges(Index begin, Index end, Index grain, Fn&& fn, bool simple = false) {
#ifdef BOUNCE_TSAN
    (void)simple;
    std::atomic<Index> next{begin};
    std::mutex failed_mutex;
    std::exception_ptr failed;  // the first exception, rethrown after the join (as TBB does)
    auto worker = [&] {
        try {
            for (Index lo = next.fetch_add(grain); lo < end; lo = next.fetch_add(grain)) fn(lo, std::min<Index>(end, lo + grain));
        } catch (...) {
            next.store(end);
            std::lock_guard lock(failed_mutex);
            if (!failed) failed = std::current_exception();
        }
    };
    std::vector<std::thread> threads;
    for (int i = 1; i < tbb::this_task_arena::max_concurrency(); ++i) threads.emplace_back(worker);
    worker();
    for (auto& t : threads) t.join();
    if (failed) std::rethrow_exception(failed);
#else
    auto body = [&](const tbb::blocked_range<Index>& r) { fn(r.begin(), r.end()); };
    if (simple)
        tbb::parallel_for(tbb::blocked_range<Index>(begin, end, grain), body, tbb::simple_partitioner());
    else
        tbb::parallel_for(tbb::blocked_range<Index>(begin, end, grain), body);
#endif
}

/// fn(i) for every i in [begin, end), in parallel.
template <typename Index, typename Fn>
void parallel_for_each_index(Index begin, Index end, Fn&& fn) {
    parallel_ranges(begin, end, Index(1), [&](Index lo, Index hi) {
        for (Index i = lo; i < hi; ++i) fn(i);
    });
}

}  // namespace bounce
