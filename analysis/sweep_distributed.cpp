#include "sweep_distributed.h"

#include <cstdlib>
#include <map>

#include "error.h"
#include "plugin_module.h"
#include "sweep_detail.h"

namespace hsnc {
namespace {

class MpiCommunicator : public Communicator {
public:
    explicit MpiCommunicator(const HsncMpiApi* api) : api_(api) {
        if (api_->init(&rank_, &size_) != 0) throw RunError("MPI: MPI_Init failed");
    }
    ~MpiCommunicator() override { api_->finalize(); }
    int rank() const override { return rank_; }
    int size() const override { return size_; }
    std::vector<std::string> gather(const std::string& mine) override {
        char* all = nullptr;
        unsigned long long* sizes = nullptr;
        if (api_->gather(mine.data(), mine.size(), &all, &sizes) != 0)
            throw RunError("MPI: gathering the results on rank 0 failed (more than 2 GB from one rank?)");
        std::vector<std::string> out;
        if (rank_ == 0) {
            std::size_t at = 0;
            for (int r = 0; r < size_; ++r) {
                out.emplace_back(all + at, sizes[r]);
                at += sizes[r];
            }
            api_->release(all);
            api_->release(sizes);
        }
        return out;
    }
    int broadcast(int value) override {
        if (api_->broadcast(&value) != 0) throw RunError("MPI: broadcast failed");
        return value;
    }
    bool send_progress(int points) override { return api_->send_progress(points) == 0; }
    bool poll_progress(long long& points, int& finished) override {
        return api_->poll_progress(&points, &finished) == 0;
    }

private:
    const HsncMpiApi* api_;
    int rank_ = 0, size_ = 1;
};

}  // namespace

bool launched_by_mpi() {
    for (const char* v : {"OMPI_COMM_WORLD_SIZE", "PMIX_RANK", "PMI_RANK"})
        if (std::getenv(v)) return true;
    return false;
}

#ifdef HSNC_MPI_MODULE
std::string mpi_module_path() { return api::plugin_module_path(HSNC_MPI_MODULE); }

std::unique_ptr<Communicator> mpi_communicator() {
    const std::string path = mpi_module_path();
    // Global scope: Open MPI's own plugins, which it dlopens, resolve symbols
    // of libmpi against it.
    std::string problem;
    auto api = reinterpret_cast<HsncMpiApiFunction>(
        api::plugin_module_symbol(path, "hsnc_mpi_api", api::SymbolScope::kGlobal, problem));
    if (!api) throw RunError("MPI: cannot load the MPI module: " + problem);
    return std::make_unique<MpiCommunicator>(api());
}
#else
std::string mpi_module_path() { return ""; }
std::unique_ptr<Communicator> mpi_communicator() {
    throw RunError("started by an MPI launcher, but this hsnc was built without MPI (configure with -DHSNC_WITH_MPI=ON)");
}
#endif

std::vector<std::vector<SweepPoint>> run_tasks_distributed(const SweepPlan& plan, const std::vector<std::size_t>& which,
                                                           Communicator& comm, const std::function<void()>& finished) {
    const int rank = comm.rank(), size = comm.size();
    std::vector<std::size_t> mine;
    for (std::size_t k = static_cast<std::size_t>(rank); k < which.size(); k += static_cast<std::size_t>(size))
        mine.push_back(which[k]);
    const std::size_t n = plan.model().dof();
    std::string payload;
    try {
        payload = "ok\n" + sweep_detail::write_tasks(mine, plan.run_tasks(mine), n);
    } catch (const RunError& e) {
        payload = std::string("error\n") + e.what();
    }
    if (finished) finished();
    const std::vector<std::string> all = comm.gather(payload);
    // Rank 0 decides; everyone learns whether it failed.
    std::string failure;
    std::map<std::size_t, std::vector<SweepPoint>> tasks;
    if (rank == 0) {
        for (int r = 0; r < size && failure.empty(); ++r) {
            const std::string& p = all[static_cast<std::size_t>(r)];
            if (p.compare(0, 6, "error\n") == 0) failure = p.substr(6);
        }
        if (failure.empty())
            for (int r = 0; r < size; ++r) {
                const std::vector<std::string> lines = sweep_detail::split_lines(all[static_cast<std::size_t>(r)]);
                sweep_detail::read_tasks(lines, 1, n, "MPI rank " + std::to_string(r), tasks);
            }
    }
    if (comm.broadcast(failure.empty() ? 0 : 1) != 0) throw RunError(rank == 0 ? failure : "failed on another rank");
    std::vector<std::vector<SweepPoint>> out;
    if (rank != 0) return out;
    for (std::size_t i : which) {
        auto it = tasks.find(i);
        if (it == tasks.end()) throw RunError("MPI: task " + std::to_string(i) + " missing from the ranks' results");
        out.push_back(std::move(it->second));
    }
    return out;
}

}  // namespace hsnc
