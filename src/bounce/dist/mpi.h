// Open MPI as the engine of many machines (docs/parallel.md): `mpirun -np N bounce render ...`
// with the command line of one process. The binary still runs alone: without mpirun, or under
// mpirun with one rank, it behaves as a single process.
#pragma once

#include <memory>
#include <string>
#include <vector>

#include "bounce/core/communicator.h"

namespace bounce {

/// The job's ranks over MPI_COMM_WORLD. MPI is initialised on construction and finalised on
/// destruction; one per process.
class MpiCommunicator : public Communicator {
  public:
    MpiCommunicator(int* argc, char*** argv);
    ~MpiCommunicator() override;
    MpiCommunicator(const MpiCommunicator&) = delete;
    MpiCommunicator& operator=(const MpiCommunicator&) = delete;
    int rank() const override { return rank_; }
    int size() const override { return size_; }
    std::vector<std::string> allgather(const std::string& mine) override;
    std::vector<std::string> gather_to_first(const std::string& mine) override;
    /// Ends every rank of the job with `code` (a rank that failed says why first).
    [[noreturn]] static void abort(int code);

  private:
    std::vector<std::string> exchange(const std::string& mine, bool everyone);
    int rank_ = 0, size_ = 1;
};

/// Refuses a job whose ranks run another binary or read another scene: every rank's `identity`
/// (version, git revision, scene fingerprint) is compared with rank 0's; InputError naming the
/// first rank that differs and how.
void check_same_job(Communicator& comm, const std::string& identity);

}  // namespace bounce
