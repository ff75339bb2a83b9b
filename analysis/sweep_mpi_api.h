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
};
/// The module exports `const HsncMpiApi* hsnc_mpi_api(void)`.
typedef const HsncMpiApi* (*HsncMpiApiFunction)();
}
