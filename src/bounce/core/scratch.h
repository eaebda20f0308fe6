// Scratch memory for the hot loops, handed down explicitly (pbrt-v4's ScratchBuffer): an arena
// per thread that an object doing parallel work owns (`PerThread<ScratchBuffer>`), takes once at
// the top of a piece of work and passes down as an argument. Nothing below reaches for scratch
// of its own: no thread_local, no function-static buffers.
#pragma once

#include <tbb/enumerable_thread_specific.h>

#include <cstddef>
#include <memory>
#include <span>
#include <type_traits>
#include <vector>

namespace bounce {

/// One value per thread (TBB's, or a std::thread's under ThreadSanitizer alike).
template <class T>
using PerThread = tbb::enumerable_thread_specific<T>;

class ScratchBuffer {
  public:
    ScratchBuffer() = default;
    ScratchBuffer(const ScratchBuffer&) = delete;
    ScratchBuffer& operator=(const ScratchBuffer&) = delete;
    ScratchBuffer(ScratchBuffer&&) = default;
    ScratchBuffer& operator=(ScratchBuffer&&) = default;

    /// While a Scope is open, what is taken stays valid; when the outermost one closes,
    /// everything taken is given back (a callee may open its own inside its caller's).
    class [[nodiscard]] Scope {
      public:
        explicit Scope(ScratchBuffer& s) : s_(s) { ++s_.depth_; }
        ~Scope() {
            if (--s_.depth_ == 0) s_.reset();
        }
        Scope(const Scope&) = delete;
        Scope& operator=(const Scope&) = delete;

      private:
        ScratchBuffer& s_;
    };
    Scope scope() { return Scope(*this); }

    /// n values of T, each `fill`, valid while the scope is open (growing never moves them).
    template <class T>
    std::span<T> take(size_t n, const T& fill = T()) {
        static_assert(std::is_trivially_destructible_v<T> && std::is_copy_constructible_v<T>);
        T* first = reinterpret_cast<T*>(bytes(n * sizeof(T), alignof(T)));
        std::uninitialized_fill_n(first, n, fill);
        return {first, n};
    }
    /// Bytes held (the largest piece of work so far, once a scope has closed).
    size_t capacity() const;

  private:
    std::byte* bytes(size_t size, size_t align);
    /// Everything taken given back; blocks outgrown are merged into one as large as them all,
    /// so the next piece of the same size takes its memory without allocating.
    void reset();

    std::vector<std::unique_ptr<std::byte[]>> outgrown_;  ///< blocks filled since the last reset
    size_t outgrown_bytes_ = 0;
    std::unique_ptr<std::byte[]> block_;
    size_t capacity_ = 0, used_ = 0;
    int depth_ = 0;
};

}  // namespace bounce
