// hsnc_reduction_bench: what [reduction] costs as a structure grows (issue 37).
//
//   build/hsnc_reduction_bench [--quick] [--response]
//
// Clamped steel plates of hex8 bricks (tests/hex8_solid.h; 0.5 x 0.1 x 0.01 m,
// nx x ny x 2 bricks), from about 10^3 to 10^5 dofs, the free corner's z
// against a stop and forced. Per plate, wall time and peak memory of:
//   read     read_model with [reduction] modes = 20 (the sparse files read,
//            K_II factored, 20 fixed-interface modes, the reduced M, K, C):
//            what every simulate of the model pays;
//   again    read_model once more in the same process: the files read
//            again, the reduction remembered (reduce_memo), what each
//            point of a sweep pays;
//   check    the same plus the full structure's 10 lowest frequencies (what
//            `hsnc check` and `hsnc reduce` add);
//   run      simulate of the reduced model (interpreter) over 0.1 s;
// and the reduced model's error on the lowest three frequencies. Times are
// medians of 3 runs (1 with --quick, and for plates above 5*10^4 dofs).
//
// Then what the reduction costs in response and saves in work: a cantilever
// of 100 consistent-mass Euler-Bernoulli elements (200 dofs, omega up to
// 4e6 rad/s, Rayleigh beta = 1e-7), a friction pad on w75 and stops at the
// tip and mid-span, forced at 20 rad/s over 1 s, run in full and reduced to
// its three named dofs plus 10 ... 80 fixed-interface modes: how many of the
// full model's events the reduced one repeats in order (same kind, same
// element, within 1 ms), up to which instant, and how far their times are;
// evaluations per switch, and the run's time (medians of 3; the reduction's
// own cost is the table above). `--response` runs this part alone.
#include <sys/resource.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <string>
#include <utility>
#include <vector>

#include <Eigen/Sparse>

#include "bench_common.h"
#include "fe_beam.h"
#include "hex8_solid.h"
#include "hsnc/simulate.h"
#include "model_reader.h"
#include "reduction.h"

namespace {

using namespace hsnc;
using bench::median;
using bench::seconds_since;

double peak_mb() {
    rusage u{};
    getrusage(RUSAGE_SELF, &u);
    return static_cast<double>(u.ru_maxrss) / 1024.0;
}

/// The events of one run, a mass named (the reduction renumbers dofs).
class Events : public Observer {
public:
    explicit Events(const Model& m) : model_(m) {}
    void on_sample(double, const double*, const double*) override {}
    void on_event(double t, EventKind kind, int element, const double*, const double*) override {
        const bool contact = kind == EventKind::contact_close || kind == EventKind::contact_open;
        const auto i = static_cast<std::size_t>(element);
        list.push_back({t, std::to_string(static_cast<int>(kind)) + ":" +
                               (contact || i >= model_.masses.size() ? std::to_string(element) : model_.masses[i].name)});
    }
    std::vector<std::pair<double, std::string>> list;

private:
    const Model& model_;
};

/// The cantilever of tests/fe_beam.h (1 m, EI = 100 N m^2, 2 kg/m, consistent
/// mass; dofs w1, t1, ..., wN, tN) as M.mtx and K.mtx in dir.
void write_cantilever(const std::filesystem::path& dir, int elements) {
    const fe::Beam b = fe::cantilever(elements);
    fe::write_market((dir / "M.mtx").string(), b.M.sparseView());
    fe::write_market((dir / "K.mtx").string(), b.K.sparseView());
}

void response(const std::filesystem::path& dir, bool quick) {
    const int elements = 100;
    write_cantilever(dir, elements);
    std::string dofs = "[";
    for (int k = 1; k <= elements; ++k)
        dofs += (k > 1 ? ", " : "") + ("\"w" + std::to_string(k) + "\", \"t" + std::to_string(k) + "\"");
    dofs += "]";
    const std::string base =
        "name = \"beam-pad\"\n[structure]\ndofs = " + dofs +
        "\nmass = \"M.mtx\"\nstiffness = \"K.mtx\"\n[damping]\nalpha = 0.0\nbeta = 1e-7\n"
        "[[forcing]]\nomega = 20.0\namplitude = { w100 = 2.0 }\n"
        "[[contact]]\nname = \"tip\"\nbetween = [\"w100\", \"ground\"]\ngap = 0.004\nk = 2000.0\n"
        "[[contact]]\nname = \"mid\"\nbetween = [\"ground\", \"w50\"]\ngap = 0.002\nk = 5000.0\n"
        "[[friction]]\nname = \"pad\"\nbetween = [\"w75\", \"ground\"]\nmu_k = 0.3\nmu_s = 0.4\nnormal = 2.0\n"
        "[simulate]\nt_end = 1.0\n";
    std::printf("\nresponse: 200-dof cantilever, friction pad and two stops, 1 s\n");
    std::printf("%8s %6s %8s %14s %9s %12s %12s %10s\n", "modes", "dofs", "events", "same events", "until s",
                "worst dt s", "evals/switch", "run s");
    std::vector<std::pair<double, std::string>> full;
    for (const int modes : {0, 10, 20, 40, 80}) {  // 0: the full model
        const std::string model = (dir / "beam.toml").string();
        if (std::FILE* f = std::fopen(model.c_str(), "w")) {
            const std::string text = base + (modes ? "[reduction]\nmodes = " + std::to_string(modes) + "\n" : "");
            std::fputs(text.c_str(), f);
            std::fclose(f);
        }
        const Model m = read_model(model);
        SimulateOptions opt;
        opt.kernels = KernelChoice::interp;
        opt.samples = false;
        std::vector<double> run;
        Events events(m);
        SimulateSummary sum;
        for (int r = 0; r < (quick ? 1 : 3); ++r) {
            events.list.clear();
            const auto t0 = bench::Clock::now();
            sum = simulate(m, opt, events);
            run.push_back(seconds_since(t0));
        }
        if (modes == 0) full = events.list;
        // The full model's events repeated in order: same kind and element,
        // within a millisecond (stick and release alternate, so a pair the
        // reduced model adds or drops would otherwise shift into agreement).
        std::size_t same = 0;
        double worst = 0.0;
        while (same < full.size() && same < events.list.size() && full[same].second == events.list[same].second &&
               std::fabs(full[same].first - events.list[same].first) < 1e-3) {
            worst = std::max(worst, std::fabs(full[same].first - events.list[same].first));
            ++same;
        }
        const double until = same < full.size() ? full[same].first : 1.0;
        const std::string label = modes ? std::to_string(modes) : "full";
        std::printf("%8s %6zu %8zu %9zu/%-4zu %9.3f %12.2g %12.1f %10.4f\n", label.c_str(), m.dof(), events.list.size(),
                    same, full.size(), until, worst,
                    static_cast<double>(sum.evaluations) / static_cast<double>(std::max<std::size_t>(1, sum.events)),
                    median(run));
        std::fflush(stdout);
    }
}

}  // namespace

int main(int argc, char** argv) {
    bool quick = false, response_only = false;
    for (int a = 1; a < argc; ++a) {
        quick = quick || std::strcmp(argv[a], "--quick") == 0;
        response_only = response_only || std::strcmp(argv[a], "--response") == 0;
    }
    const std::filesystem::path dir = std::filesystem::temp_directory_path() / "hsnc_reduction_bench";
    std::filesystem::create_directories(dir);
    if (response_only) {
        response(dir, quick);
        std::filesystem::remove_all(dir);
        return 0;
    }
    const int sizes[][2] = {{20, 4}, {60, 12}, {120, 24}, {200, 40}};  // nx, ny (nz = 2)
    std::printf("%8s %10s %10s %10s %10s %9s %12s\n", "dofs", "read s", "again s", "check s", "run s", "peak MB",
                "freq error");
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
        std::vector<double> again;
        for (int r = 0; r < runs; ++r) {
            reduction_memo_clear();  // each read and check as a new process makes them
            auto t0 = bench::Clock::now();
            const Model m = read_model(model);
            read.push_back(seconds_since(t0));
            t0 = bench::Clock::now();
            (void)read_model(model);  // the reduction remembered: what a sweep's next point pays
            again.push_back(seconds_since(t0));
            reduction_memo_clear();
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
        std::printf("%8zu %10.3f %10.3f %10.3f %10.3f %9.0f %12.3g\n", s.dofs.size(), median(read), median(again),
                    median(check), median(run), peak_mb(), error);
        std::fflush(stdout);
    }
    response(dir, quick);
    std::filesystem::remove_all(dir);
    return 0;
}
