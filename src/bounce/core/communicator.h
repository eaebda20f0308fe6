// The processes a frame is spread over: an MPI job's ranks (dist/mpi.h), or this process alone.
// Passes ask it which share of the work is theirs and exchange what they made; every process
// calls the collective calls in the same order. Results never depend on the number of
// processes: work is merged in one canonical order whoever made it (docs/parallel.md).
#pragma once

#include <algorithm>
#include <array>
#include <cstdint>
#include <string>
#include <vector>

namespace bounce {

class Communicator {
public:
    virtual ~Communicator() = default;
    virtual int rank() const = 0;
    virtual int size() const = 0;
    /// Every process's bytes, in rank order (collective).
    virtual std::vector<std::string> allgather(const std::string& mine) = 0;
    /// Every process's bytes on process 0, in rank order; nothing elsewhere (collective).
    virtual std::vector<std::string> gather_to_first(const std::string& mine) = 0;
    /// Whether work item `index` (a tile, a row band, a record) is this process's: round robin.
    bool owns(size_t index) const { return static_cast<int>(index % static_cast<size_t>(size())) == rank(); }
    /// What the exchanges cost so far (reported in stats).
    uint64_t bytes_sent = 0, exchanges = 0;
    double wait_s = 0;
};

/// This process alone: owns everything, exchanges with nobody.
class SingleProcess : public Communicator {
public:
    int rank() const override { return 0; }
    int size() const override { return 1; }
    std::vector<std::string> allgather(const std::string& mine) override { return {mine}; }
    std::vector<std::string> gather_to_first(const std::string& mine) override { return {mine}; }
};

/// How the rows of a window are shared among processes: `count` bands of whole tile rows
/// (a tile never straddles two bands), band i belonging to process i % size. Visibility,
/// gathering, refinement and shading all use these bands, so a process needs the fragments of
/// its own bands only.
struct RowBands {
    RowBands(int height, int tile, int processes, int per_process = 4)
        : height_(height), tile_(tile), tile_rows_((height + tile - 1) / tile),
          count_(std::max(1, std::min(tile_rows_, per_process * processes))) {}
    int count() const { return count_; }
    /// Window rows [first, last) of band `b`.
    std::array<int, 2> rows(int b) const {
        return {std::min(height_, tile_ * first_tile_row(b)), std::min(height_, tile_ * first_tile_row(b + 1))};
    }
    int band_of_row(int y) const {
        const int r = y / tile_;
        int b = static_cast<int>(static_cast<int64_t>(r) * count_ / tile_rows_);
        while (b + 1 < count_ && first_tile_row(b + 1) <= r) ++b;  // integer rounding of the split
        while (b > 0 && first_tile_row(b) > r) --b;
        return b;
    }

private:
    int first_tile_row(int b) const { return static_cast<int>(static_cast<int64_t>(tile_rows_) * b / count_); }
    int height_, tile_, tile_rows_, count_;
};

}  // namespace bounce
