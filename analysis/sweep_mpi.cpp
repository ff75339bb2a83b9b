// hsnc -- libhsnc_mpi.so: the MPI operations of a distributed sweep
// (analysis/sweep_distributed.h), the only code that includes mpi.h. Loaded
// by hsnc with dlopen when it runs under an MPI launcher.
// The C interface only: Open MPI's deprecated C++ bindings would need libmpi_cxx.
#define OMPI_SKIP_MPICXX 1
#define MPICH_SKIP_MPICXX 1
#include <mpi.h>

#include <climits>
#include <cstdlib>
#include <cstring>
#include <vector>

#include "sweep_mpi_api.h"

namespace {

constexpr int kProgressTag = 7031;
int g_thread_level = MPI_THREAD_SINGLE;

int init(int* rank, int* size) {
    int ready = 0;
    MPI_Initialized(&ready);
    // Serialized: progress messages go out from the worker thread that
    // finished a point, one call at a time.
    if (!ready && MPI_Init_thread(nullptr, nullptr, MPI_THREAD_SERIALIZED, &g_thread_level) != MPI_SUCCESS) return 1;
    if (ready) MPI_Query_thread(&g_thread_level);
    MPI_Comm_rank(MPI_COMM_WORLD, rank);
    MPI_Comm_size(MPI_COMM_WORLD, size);
    return 0;
}

int gather(const char* data, unsigned long long size, char** all, unsigned long long** sizes) {
    int rank = 0, n = 1;
    MPI_Comm_rank(MPI_COMM_WORLD, &rank);
    MPI_Comm_size(MPI_COMM_WORLD, &n);
    // A count that does not fit an int is sent as -1: every rank then fails.
    const int mine = size > static_cast<unsigned long long>(INT_MAX) ? -1 : static_cast<int>(size);
    std::vector<int> counts(static_cast<std::size_t>(n));
    if (MPI_Gather(&mine, 1, MPI_INT, counts.data(), 1, MPI_INT, 0, MPI_COMM_WORLD) != MPI_SUCCESS) return 1;
    int bad = 0;
    std::vector<int> displs(static_cast<std::size_t>(n));
    long long total = 0;
    if (rank == 0)
        for (int r = 0; r < n; ++r) {
            if (counts[r] < 0 || total + counts[r] > INT_MAX) bad = 1;
            displs[r] = static_cast<int>(total);
            total += counts[r] < 0 ? 0 : counts[r];
        }
    MPI_Bcast(&bad, 1, MPI_INT, 0, MPI_COMM_WORLD);
    if (bad) return 1;
    char* buffer = nullptr;
    if (rank == 0) {
        buffer = static_cast<char*>(std::malloc(static_cast<std::size_t>(total) + 1));
        *sizes = static_cast<unsigned long long*>(std::malloc(sizeof(unsigned long long) * static_cast<std::size_t>(n)));
        for (int r = 0; r < n; ++r) (*sizes)[r] = static_cast<unsigned long long>(counts[r]);
        *all = buffer;
    }
    if (MPI_Gatherv(data, mine, MPI_CHAR, buffer, counts.data(), displs.data(), MPI_CHAR, 0, MPI_COMM_WORLD) !=
        MPI_SUCCESS)
        return 1;
    return 0;
}

void release(void* p) { std::free(p); }

int broadcast(int* value) { return MPI_Bcast(value, 1, MPI_INT, 0, MPI_COMM_WORLD) == MPI_SUCCESS ? 0 : 1; }

int finalize() {
    int done = 0;
    MPI_Finalized(&done);
    return done ? 0 : MPI_Finalize();
}

void abort_all(int code) { MPI_Abort(MPI_COMM_WORLD, code); }

int send_progress(int value) {
    if (g_thread_level < MPI_THREAD_SERIALIZED) return 1;
    return MPI_Send(&value, 1, MPI_INT, 0, kProgressTag, MPI_COMM_WORLD) == MPI_SUCCESS ? 0 : 1;
}

int poll_progress(long long* points, int* finished) {
    if (g_thread_level < MPI_THREAD_SERIALIZED) return 1;
    for (;;) {
        int flag = 0;
        MPI_Status status;
        if (MPI_Iprobe(MPI_ANY_SOURCE, kProgressTag, MPI_COMM_WORLD, &flag, &status) != MPI_SUCCESS) return 1;
        if (!flag) return 0;
        int value = 0;
        if (MPI_Recv(&value, 1, MPI_INT, status.MPI_SOURCE, kProgressTag, MPI_COMM_WORLD, MPI_STATUS_IGNORE) !=
            MPI_SUCCESS)
            return 1;
        if (value < 0) ++*finished;
        else *points += value;
    }
}

const HsncMpiApi kApi = {init, gather, release, broadcast, finalize, abort_all, send_progress, poll_progress};

}  // namespace

extern "C" __attribute__((visibility("default"))) const HsncMpiApi* hsnc_mpi_api() { return &kApi; }
