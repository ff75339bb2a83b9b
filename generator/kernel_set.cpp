#include "kernel_set.h"

#include <deque>
#include <filesystem>
#include <fstream>
#include <set>
#include <sstream>

#include "assembly.h"
#include "derivation.h"
#include "emitter.h"
#include "error.h"
#include "sample_models.h"

namespace hsnc {

Configuration initial_configuration(const Model& model) {
    Configuration cfg = Configuration::all_open(model);
    for (std::size_t c = 0; c < model.contacts.size(); ++c) {
        const double g = gap(model, static_cast<int>(c), model.x0.data());
        const double dg = gap_rate(model, static_cast<int>(c), model.v0.data());
        cfg.closed[c] = g > 0 || (g == 0 && dg > 0);
    }
    for (std::size_t i = 0; i < model.dof(); ++i) cfg.stuck[i] = model.masses[i].has_friction && model.v0[i] == 0.0;
    return cfg;
}

std::vector<Configuration> configurations_to_generate(const Model& model, std::string* note) {
    std::size_t bits = model.contacts.size();
    for (const Mass& m : model.masses) bits += m.has_friction ? 1 : 0;
    if (bits < 7) {  // 2^bits <= 64
        if (note) note->clear();
        return all_configurations(model);
    }
    std::vector<Configuration> out;
    std::set<Configuration> seen;
    std::deque<Configuration> queue{initial_configuration(model)};
    seen.insert(queue.front());
    while (!queue.empty() && out.size() < kMaxGeneratedConfigurations) {
        const Configuration cfg = queue.front();
        queue.pop_front();
        out.push_back(cfg);
        auto visit = [&](Configuration next) {
            if (seen.insert(next).second) queue.push_back(std::move(next));
        };
        for (std::size_t c = 0; c < cfg.closed.size(); ++c) {
            Configuration next = cfg;
            next.closed[c] = !next.closed[c];
            visit(next);
        }
        for (std::size_t i = 0; i < cfg.stuck.size(); ++i) {
            if (!model.masses[i].has_friction) continue;
            Configuration next = cfg;
            next.stuck[i] = !next.stuck[i];
            visit(next);
        }
    }
    if (note) {
        std::ostringstream s;
        s << "model '" << model.name << "' has 2^" << bits << " configurations, more than "
          << kMaxGeneratedConfigurations << ": generated the " << out.size()
          << " nearest to the initial configuration (one switch at a time, breadth first); "
             "the others are solved by the generic solver at run time";
        *note = s.str();
    }
    return out;
}

KernelSet generate_kernel_set(const Model& model) {
    KernelSet set;
    for (const Configuration& cfg : configurations_to_generate(model, &set.note)) {
        const Derivation d = derive(model, cfg);
        const std::string sym = kernel_symbol(model, cfg);
        set.kernels.push_back({sym.substr(std::string("hsnc_kernel_").size()) + ".cpp", emit_kernel(d)});
        set.symbols.push_back(sym);
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
