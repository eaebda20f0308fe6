#include "bounce/dist/mpi.h"

#include <mpi.h>
#include <fmt/format.h>

#include <algorithm>
#include <chrono>
#include <cstdlib>

#include "bounce/core/error.h"

namespace bounce {

MpiCommunicator::MpiCommunicator(int* argc, char*** argv) {
    int provided = 0;
    // Only the main thread calls MPI; TBB's workers never do.
    MPI_Init_thread(argc, argv, MPI_THREAD_FUNNELED, &provided);
    MPI_Comm_rank(MPI_COMM_WORLD, &rank_);
    MPI_Comm_size(MPI_COMM_WORLD, &size_);
}

MpiCommunicator::~MpiCommunicator() { MPI_Finalize(); }

std::vector<std::string> MpiCommunicator::allgather(const std::string& mine) { return exchange(mine, true); }

std::vector<std::string> MpiCommunicator::gather_to_first(const std::string& mine) { return exchange(mine, false); }

std::vector<std::string> MpiCommunicator::exchange(const std::string& mine, bool everyone) {
    const auto t0 = std::chrono::steady_clock::now();
    const auto n = static_cast<long long>(mine.size());
    std::vector<long long> sizes(static_cast<size_t>(size_));
    MPI_Allgather(&n, 1, MPI_LONG_LONG, sizes.data(), 1, MPI_LONG_LONG, MPI_COMM_WORLD);
    const bool receives = everyone || rank_ == 0;
    // MPI counts are ints: large exchanges go in chunks of at most 1 GiB per rank.
    constexpr long long kChunk = 1LL << 30;
    std::vector<std::string> out(receives ? static_cast<size_t>(size_) : 0);
    for (size_t r = 0; r < out.size(); ++r) out[r].resize(static_cast<size_t>(sizes[r]));
    const long long largest = *std::max_element(sizes.begin(), sizes.end());
    std::vector<int> counts(sizes.size()), displs(sizes.size());
    std::string recv;
    for (long long at = 0; at < largest; at += kChunk) {
        int total = 0;
        for (size_t r = 0; r < sizes.size(); ++r) {
            counts[r] = static_cast<int>(std::clamp(sizes[r] - at, 0LL, kChunk));
            displs[r] = total;
            total += counts[r];
        }
        recv.resize(receives ? static_cast<size_t>(total) : 0);
        const int mine_count = counts[static_cast<size_t>(rank_)];
        const char* send = mine.data() + std::min<long long>(at, n);
        if (everyone)
            MPI_Allgatherv(send, mine_count, MPI_BYTE, recv.data(), counts.data(), displs.data(), MPI_BYTE, MPI_COMM_WORLD);
        else
            MPI_Gatherv(send, mine_count, MPI_BYTE, recv.data(), counts.data(), displs.data(), MPI_BYTE, 0, MPI_COMM_WORLD);
        for (size_t r = 0; r < out.size(); ++r) std::copy_n(recv.data() + displs[r], counts[r], out[r].data() + at);
    }
    bytes_sent += mine.size();
    ++exchanges;
    wait_s += std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
    return out;
}

void MpiCommunicator::abort(int code) {
    MPI_Abort(MPI_COMM_WORLD, code);
    std::exit(code);  // not reached
}

void check_same_job(Communicator& comm, const std::string& identity) {
    const std::vector<std::string> all = comm.allgather(identity);
    for (size_t r = 1; r < all.size(); ++r)
        if (all[r] != all[0])
            throw InputError(fmt::format("rank {}", r), "",
                             fmt::format("runs another binary or reads another scene than rank 0 ({} against {})", all[r], all[0]));
}

}  // namespace bounce
