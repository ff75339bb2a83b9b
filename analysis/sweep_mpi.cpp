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

int init(int* rank, int* size) {
    int ready = 0;
    MPI_Initialized(&ready);
    if (!ready && MPI_Init(nullptr, nullptr) != MPI_SUCCESS) return 1;
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

const HsncMpiApi kApi = {init, gather, release, broadcast, finalize, abort_all};

}  // namespace

extern "C" __attribute__((visibility("default"))) const HsncMpiApi* hsnc_mpi_api() { return &kApi; }
