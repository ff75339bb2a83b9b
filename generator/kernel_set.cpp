#include "kernel_set.h"

#include <algorithm>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <set>
#include <sstream>

#include "assembly.h"
#include "derivation.h"
#include "emitter.h"
#include "engine.h"
#include "param_emitter.h"
#include "error.h"
#include "sample_models.h"
#include "kernel_mode.h"
#include "transitions.h"

namespace hsnc {

namespace {

/// Records every configuration the engine asks a solver for, and hands the
/// request on to the Eigen solver.
class RecordingProvider : public SolverProvider {
public:
    explicit RecordingProvider(const Model& model) : generic_(model) {}
    SegmentSolver& solver(const Configuration& cfg) override {
        visited.insert(cfg);
        return generic_.solver(cfg);
    }
    std::set<Configuration> visited;

private:
    GenericSolverProvider generic_;
};

class NullObserver : public Observer {
public:
    void on_sample(double, const double*, const double*) override {}
    void on_event(double, EventKind, int, const double*, const double*) override {}
};

/// log2 of the number of configurations, rounded up (a Jenkins element has 3 states: 2 bits).
std::size_t switch_bits(const Model& model) {
    std::size_t bits = model.contacts.size() + 2 * model.jenkins.size();
    for (const FrictionSlot& f : model.friction_slots) bits += f.active ? 1 : 0;
    return bits;
}

}  // namespace

Configuration initial_configuration(const Model& model) {
    std::vector<signed char> sgn;
    return entered_configuration(model, model.t0, model.x0.data(), model.v0.data(), sgn);
}

std::vector<Configuration> configurations_to_generate(const Model& model, std::string* note) {
    const std::size_t bits = switch_bits(model);
    if (bits < 7) {  // 2^bits <= 64
        if (note) note->clear();
        return all_configurations(model);
    }
    // The configurations of the model's own default run (Eigen solver, to
    // [simulate].t_end), then the initial one and its single-flip neighbours.
    const Configuration initial = initial_configuration(model);
    RecordingProvider recorder(model);
    std::string run_note = "no [simulate].t_end: no run";
    if (model.t_end) {
        EngineOptions options;
        options.t_end = *model.t_end;
        options.samples = false;
        NullObserver observer;
        const RunSummary summary = Engine(model, recorder).run(options, observer);
        char t_end[32];
        std::snprintf(t_end, sizeof t_end, "%.17g", *model.t_end);
        run_note = std::string("default run to t_end = ") + t_end + " (" + run_status_name(summary.status) +
                   ", " + std::to_string(summary.events) + " switch events)";
    }
    std::set<Configuration> chosen = recorder.visited;
    const std::size_t visited = chosen.size();
    chosen.insert(initial);
    auto add_neighbour = [&](Configuration next) {
        if (chosen.size() < kMaxManifestConfigurations) chosen.insert(std::move(next));
    };
    for (std::size_t c = 0; c < initial.closed.size(); ++c) {
        Configuration next = initial;
        next.closed[c] = !next.closed[c];
        add_neighbour(next);
    }
    for (std::size_t i = 0; i < initial.stuck.size(); ++i) {
        if (!model.has_friction(i)) continue;
        Configuration next = initial;
        next.stuck[i] = !next.stuck[i];
        add_neighbour(next);
    }
    for (std::size_t j = 0; j < initial.slip.size(); ++j)
        for (signed char state : {0, 1, -1}) {
            if (state == initial.slip[j]) continue;
            Configuration next = initial;
            next.slip[j] = state;
            add_neighbour(next);
        }
    if (note) {
        const std::size_t two = bits - 2 * model.jenkins.size();
        std::ostringstream s;
        s << "model '" << model.name << "' has 2^" << two
          << (model.jenkins.empty() ? std::string() : " x 3^" + std::to_string(model.jenkins.size()))
          << " configurations, more than "
          << kMaxGeneratedConfigurations << ": generated the " << chosen.size() << " listed in its manifest ("
          << visited << " visited by its " << run_note << ", plus the initial configuration and its single-switch "
          << "neighbours, at most " << kMaxManifestConfigurations
          << " in all); the others are solved by the generic solver at run time";
        *note = s.str();
    }
    return {chosen.begin(), chosen.end()};
}

std::string manifest_text(const Model& model, const std::vector<Configuration>& configurations, const std::string& note) {
    std::vector<std::string> specs;
    for (const Configuration& cfg : configurations) specs.push_back(cfg.spec(model));
    std::sort(specs.begin(), specs.end());
    std::string out = "# hsnc manifest: the configurations of model '" + model.name + "' with generated kernels\n";
    out += "# generator version " + std::string(HSNC_VERSION) + "; one configuration spec per line, sorted\n";
    out += "# " + (note.empty() ? "all " + std::to_string(configurations.size()) + " configurations" : note) + "\n";
    for (const std::string& s : specs) out += s + "\n";
    return out;
}

KernelSet generate_kernel_set(const Model& model, const std::vector<std::string>& kept) {
    KernelSet set;
    std::vector<Configuration> configurations;
    std::size_t refused = 0;
    std::string reason;
    for (const Configuration& cfg : configurations_to_generate(model, &set.note)) {
        Derivation d;
        try {
            d = derive(model, cfg);
        } catch (const NotDerivable& e) {  // the Eigen solver takes it at run time, in every kind
            if (refused++ == 0) reason = e.what();
            continue;
        }
        const std::string sym = kept.empty() ? kernel_symbol(model, cfg) : sweep_kernel_symbol(model, cfg);
        const std::string file = kernel_symbol(model, cfg).substr(std::string("hsnc_kernel_").size()) + ".cpp";
        set.kernels.push_back({file, kept.empty() ? emit_kernel(d) : emit_sweep_kernel(d, kept)});
        set.symbols.push_back(sym);
        configurations.push_back(cfg);
    }
    if (refused > 0)
        set.note += (set.note.empty() ? "" : "; ") + std::to_string(refused) +
                    " configurations the derivation does not take are solved by the Eigen solver at run time (first: " +
                    reason + ")";
    set.manifest = manifest_text(model, configurations, set.note);
    if (!kept.empty()) {  // a comment line after the header, so readers of the list skip it
        std::string names;
        for (const std::string& k : kept) names += (names.empty() ? "" : ", ") + k;
        const std::size_t at = set.manifest.find('\n', set.manifest.find('\n', set.manifest.find('\n') + 1) + 1) + 1;
        set.manifest.insert(at, "# sweep kernels: parameters given at run time (configure): " + names + "\n");
    }
    return set;
}

std::string combined_source(const KernelSet& set) {
    std::string out;
    for (const GeneratedFile& f : set.kernels) out += (out.empty() ? "" : "\n") + f.text;
    return out;
}

void write_if_changed(const std::string& dir, const std::string& name, const std::string& text) {
    namespace fs = std::filesystem;
    std::error_code ec;
    fs::create_directories(dir, ec);
    const fs::path path = fs::path(dir) / name;
    {
        std::ifstream in(path, std::ios::binary);
        if (in) {
            std::ostringstream old;
            old << in.rdbuf();
            if (old.str() == text) return;
        }
    }
    std::ofstream out(path, std::ios::binary);
    out << text;
    if (!out) throw RunError("kernel_set::write_if_changed(): cannot write '" + path.string() + "'");
}

}  // namespace hsnc
