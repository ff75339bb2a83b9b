// hsnc_reduction_bench: what [reduction] costs as a structure grows (issue 37).
//
//   build/hsnc_reduction_bench [--quick]
//
// Clamped steel plates of hex8 bricks (tests/hex8_solid.h; 0.5 x 0.1 x 0.01 m,
// nx x ny x 2 bricks), from about 10^3 to 10^5 dofs, the free corner's z
// against a stop and forced. Per plate, wall time and peak memory of:
//   read     read_model with [reduction] modes = 20 (the sparse files read,
//            K_II factored, 20 fixed-interface modes, the reduced M, K, C):
//            what every simulate of the model pays;
//   check    the same plus the full structure's 10 lowest frequencies (what
//            `hsnc check` and `hsnc reduce` add);
//   run      simulate of the reduced model (interpreter) over 0.1 s;
// and the reduced model's error on the lowest three frequencies. Times are
// medians of 3 runs (1 with --quick, and for plates above 5*10^4 dofs).
#include <sys/resource.h>

#include <chrono>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <string>
#include <vector>

#include "bench_common.h"
#include "hex8_solid.h"
#include "hsnc/simulate.h"
#include "model_reader.h"

namespace {

using namespace hsnc;
using bench::median;
using bench::seconds_since;

double peak_mb() {
    rusage u{};
    getrusage(RUSAGE_SELF, &u);
    return static_cast<double>(u.ru_maxrss) / 1024.0;
}

}  // namespace

int main(int argc, char** argv) {
    const bool quick = argc > 1 && std::strcmp(argv[1], "--quick") == 0;
    const std::filesystem::path dir = std::filesystem::temp_directory_path() / "hsnc_reduction_bench";
    std::filesystem::create_directories(dir);
    const int sizes[][2] = {{20, 4}, {60, 12}, {120, 24}, {200, 40}};  // nx, ny (nz = 2)
    std::printf("%8s %10s %10s %10s %9s %12s\n", "dofs", "read s", "check s", "run s", "peak MB", "freq error");
    for (const auto& size : sizes) {
        const fe::Solid s = fe::hex8_plate(size[0], size[1], 2, 0.5, 0.1, 0.01);
        fe::write_market((dir / "M.mtx").string(), s.M);
        fe::write_market((dir / "K.mtx").string(), s.K);
        const std::string tip = s.dofs[s.tip];
        const std::string model = (dir / "plate.toml").string();
        if (std::FILE* f = std::fopen(model.c_str(), "w")) {
            const std::string text = fe::solid_structure("hex8-plate", s) +
                                     "[damping]\nalpha = 1.0\nbeta = 1e-5\n[[forcing]]\nomega = 350.0\namplitude = { " +
                                     tip + " = 100.0 }\n[[contact]]\nname = \"stop\"\nbetween = [\"" + tip +
                                     "\", \"ground\"]\ngap = 0.002\nk = 1e6\n[simulate]\nt_end = 0.1\n"
                                     "[reduction]\nmodes = 20\n";
            std::fputs(text.c_str(), f);
            std::fclose(f);
        }
        const int runs = quick || s.dofs.size() > 50000 ? 1 : 3;
        std::vector<double> read, check, run;
        double error = 0.0;
        for (int r = 0; r < runs; ++r) {
            auto t0 = bench::Clock::now();
            const Model m = read_model(model);
            read.push_back(seconds_since(t0));
            t0 = bench::Clock::now();
            ModelOverrides o;
            o.full_frequencies = true;
            const Model c = read_model(model, o);
            check.push_back(seconds_since(t0));
            for (std::size_t k = 0; k < 3 && k < c.reduction.open.full.size(); ++k)
                error = std::max(error, (c.reduction.open.reduced[k] - c.reduction.open.full[k]) / c.reduction.open.full[k]);
            t0 = bench::Clock::now();
            SimulateOptions opt;
            opt.kernels = KernelChoice::interp;
            opt.samples = false;
            bench::Counter events;
            simulate(m, opt, events);
            run.push_back(seconds_since(t0));
        }
        std::printf("%8zu %10.3f %10.3f %10.3f %9.0f %12.3g\n", s.dofs.size(), median(read), median(check), median(run),
                    peak_mb(), error);
        std::fflush(stdout);
    }
    std::filesystem::remove_all(dir);
    return 0;
}
