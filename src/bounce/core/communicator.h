// The processes a frame is spread over: an MPI job's ranks (dist/mpi.h), or this process alone.
// Passes ask it which share of the work is theirs and exchange what they made; every process
// calls the collective calls in the same order. Results never depend on the number of
// processes: work is merged in one canonical order whoever made it (docs/parallel.md).
#pragma once

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
    /// Whether work item `index` (a tile of the image, by its row-major index) is this
    /// process's: round robin, so neighbouring tiles go to different processes.
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

}  // namespace bounce
