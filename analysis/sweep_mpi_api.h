// hsnc -- the C interface of libhsnc_mpi.so (analysis/sweep_mpi.cpp): the
// few collective operations a distributed sweep needs
// (analysis/sweep_distributed.h). Each function returns 0 on success.
#pragma once

extern "C" {
struct HsncMpiApi {
    int (*init)(int* rank, int* size);
    /// Rank 0 receives every rank's bytes in rank order (buffers it frees with release).
    int (*gather)(const char* data, unsigned long long size, char** all, unsigned long long** sizes);
    void (*release)(void* p);
    /// The value of rank 0, on every rank.
    int (*broadcast)(int* value);
    int (*finalize)();
    void (*abort)(int code);
    /// Progress to rank 0 (point-to-point, tag of its own): `value` points
    /// done, or -1 when this rank has finished its tasks. Callable from any
    /// thread, one call at a time (MPI_THREAD_SERIALIZED).
    int (*send_progress)(int value);
    /// Rank 0: adds what has arrived without waiting (points done, ranks finished).
    int (*poll_progress)(long long* points, int* finished);
};
/// The module exports `const HsncMpiApi* hsnc_mpi_api(void)`.
typedef const HsncMpiApi* (*HsncMpiApiFunction)();
}
