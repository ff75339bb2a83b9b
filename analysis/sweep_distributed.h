// hsnc -- a sweep over MPI ranks (`mpirun -np K hsnc sweep ...`).
//
// The MPI code lives in a module of its own, libhsnc_mpi.so (analysis/sweep_mpi.cpp,
// built with -DHSNC_WITH_MPI=ON against Debian's OpenMPI), that hsnc loads with
// dlopen only when it was started by an MPI launcher: every other run of hsnc
// loads no MPI library, and a build without MPI works the same apart from
// that. The module offers a C interface (sweep_mpi_api.h) of the few collective
// operations the sweep needs; everything else (which rank runs which task,
// the text the ranks send, the assembly on rank 0) is here, and the result
// is the one a single process gives, byte for byte: each task is computed
// by one rank with the same code, and rank 0 puts the tasks back in order.
#pragma once

#include <cstddef>
#include <functional>
#include <memory>
#include <string>
#include <vector>

#include "hsnc/sweep.h"
#include "sweep_mpi_api.h"

namespace hsnc {

/// The ranks of an MPI run.
class Communicator {
public:
    virtual ~Communicator() = default;
    virtual int rank() const = 0;
    virtual int size() const = 0;
    /// Rank 0 gets every rank's `mine` in rank order; other ranks an empty list.
    virtual std::vector<std::string> gather(const std::string& mine) = 0;
    /// Rank 0's `value` on every rank.
    virtual int broadcast(int value) = 0;
    /// Progress to rank 0: `points` more done, or -1: this rank has finished.
    /// False when the MPI library cannot (no MPI_THREAD_SERIALIZED).
    virtual bool send_progress(int points) = 0;
    /// Rank 0: adds the progress that has arrived to `points` and `finished` (ranks), without waiting.
    virtual bool poll_progress(long long& points, int& finished) = 0;
};

/// True when this process was started by an MPI launcher (mpirun, srun with
/// PMIx/PMI: OMPI_COMM_WORLD_SIZE, PMIX_RANK or PMI_RANK set).
bool launched_by_mpi();

/// The communicator of this MPI run (MPI initialised here, finalised when it
/// is destroyed). RunError when libhsnc_mpi.so cannot be loaded (a build
/// without MPI) or MPI does not start.
std::unique_ptr<Communicator> mpi_communicator();

/// Where libhsnc_mpi.so is looked for ("" in a build without MPI).
std::string mpi_module_path();

/// Runs `which` (tasks of `plan`, in order) spread over the ranks of `comm`:
/// the k-th task of `which` on rank k % size, on options().threads threads
/// per rank. Rank 0 returns the points of every task of `which`, in order;
/// the other ranks an empty list. A RunError on any rank is thrown on every
/// rank (rank 0: with the message of the lowest rank that failed).
/// `finished`, when given, is called on every rank once its own tasks are
/// done (or failed), before the results are gathered (the progress protocol
/// of the command line: ranks say they are done, rank 0 waits for them).
std::vector<std::vector<SweepPoint>> run_tasks_distributed(const SweepPlan& plan, const std::vector<std::size_t>& which,
                                                           Communicator& comm,
                                                           const std::function<void()>& finished = nullptr);

}  // namespace hsnc
