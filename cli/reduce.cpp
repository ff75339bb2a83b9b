// hsnc reduce MODEL -o DIR -- write the reduced structure of a model with
// [reduction] (interface.md "Reduction of a large structure"): its M, K, C
// as Matrix Market files, the dof map, the frequencies of the full and the
// reduced structure, and a [structure] table that reads them.
#include <sys/stat.h>
#include <unistd.h>

#include <cerrno>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <iostream>
#include <memory>
#include <sstream>

#include "commands.h"
#include "error.h"
#include "matrix_market.h"
#include "model_reader.h"
#include "number_text.h"
#include "output_file.h"

namespace hsnc::cli {
namespace {

constexpr const char* kWrittenBy = "written by hsnc reduce";

std::string dof_map(const Model& model) {
    const ReductionSource& r = model.reduction;
    std::ostringstream out;
    out << "index,name,kind,omega\n";
    for (std::size_t i = 0; i < model.dof(); ++i) {
        const bool mode = i >= r.boundary;
        out << i + 1 << "," << model.masses[i].name << "," << (mode ? "mode" : "boundary") << ","
            << (mode ? number_text(r.interface_omega[i - r.boundary]) : std::string()) << "\n";
    }
    return out.str();
}

std::string frequencies(const ReductionSource& r) {
    std::ostringstream out;
    out << "contacts,mode,omega_full,omega_reduced,relative_error\n";
    for (const auto& [f, contacts] : {std::pair{&r.open, "open"}, std::pair{&r.closed, "closed"}})
        for (std::size_t k = 0; k < f->reduced.size(); ++k) {
            const bool full = k < f->full.size();
            out << contacts << "," << k + 1 << "," << (full ? number_text(f->full[k]) : "") << ","
                << number_text(f->reduced[k]) << ","
                << (full && f->full[k] > 0.0 ? number_text((f->reduced[k] - f->full[k]) / f->full[k]) : "") << "\n";
        }
    return out.str();
}

std::string structure_table(const Model& model) {
    const ReductionSource& r = model.reduction;
    std::ostringstream out;
    out << "# hsnc reduce of model '" << model.name << "': " << r.method << ", " << r.full_dofs << " dofs -> "
        << r.boundary << " boundary dofs + " << r.modal_names.size() << " " << r.modes_kind() << "\n"
        << "# (paths relative to this directory)\n[structure]\ndofs = [";
    for (std::size_t i = 0; i < model.dof(); ++i) out << (i ? ", " : "") << "\"" << model.masses[i].name << "\"";
    out << "]\nmass = \"M.mtx\"\nstiffness = \"K.mtx\"\n";
    if (!r.C.empty()) out << "damping = \"C.mtx\"\n";
    return out.str();
}

/// Every file of `hsnc reduce` into `dir` (an existing directory), checked
/// before the first is written; the command's transaction commits them together.
void write_reduction(const Model& model, const std::string& dir) {
    const ReductionSource& r = model.reduction;
    const std::size_t n = model.dof();
    std::vector<std::pair<std::string, std::string>> files = {{"M.mtx", symmetric_market_text(r.M, n, kWrittenBy)},
                                                                {"K.mtx", symmetric_market_text(r.K, n, kWrittenBy)}};
    if (!r.C.empty()) files.emplace_back("C.mtx", symmetric_market_text(r.C, n, kWrittenBy));
    files.emplace_back("dofs.csv", dof_map(model));
    files.emplace_back("frequencies.csv", frequencies(r));
    files.emplace_back("structure.toml", structure_table(model));
    std::vector<OutputTarget> targets;
    for (const auto& f : files) targets.push_back(check_output("-o", dir + "/" + f.first));
    for (std::size_t i = 0; i < files.size(); ++i) {
        OutputFile out(targets[i]);
        out.write(files[i].second.data(), files[i].second.size());
        out.commit();
    }
    std::cout << "reduced '" << model.name << "': " << r.full_dofs << " dofs -> " << r.boundary << " boundary dofs + "
              << r.modal_names.size() << " " << r.modes_kind() << "; wrote";
    for (const auto& f : files) std::cout << " " << f.first;
    std::cout << " to " << dir << "\n";
    for (const auto* f : {&r.open, &r.closed})
        if (!f->problem.empty())
            std::cerr << "hsnc reduce: the full structure's frequencies (every contact "
                      << (f == &r.open ? "open" : "closed") << ") are not in frequencies.csv: " << f->problem << "\n";
}

}  // namespace

void add_reduce(CLI::App& app, int& exit_code) {
    auto* sub = app.add_subcommand(
        "reduce", "Write the reduced structure of a model with [reduction]: M.mtx, K.mtx (C.mtx), dofs.csv, "
                  "frequencies.csv and structure.toml");
    auto model_path = std::make_shared<std::string>();
    auto out_dir = std::make_shared<std::string>();
    sub->add_option("MODEL", *model_path, "model file (TOML) with [structure] and [reduction]")->required();
    sub->add_option("-o,--out-dir", *out_dir, "directory for the files (created if needed)")->required();
    sub->callback([&exit_code, model_path, out_dir] {
        if (out_dir->empty()) throw InputError("reduce: -o '': empty output directory (write -o . for the current directory)");
        ModelOverrides overrides;
        overrides.full_frequencies = true;
        const Model model = read_model(*model_path, overrides);
        if (!model.reduction.present)
            throw InputError("reduce: " + *model_path + " has no [reduction] table: there is nothing to reduce");
        struct stat st {};
        bool created = false;
        if (::stat(out_dir->c_str(), &st) != 0) {
            if (::mkdir(out_dir->c_str(), 0777) != 0)
                throw InputError("reduce: -o " + *out_dir + ": cannot create the directory: " + std::strerror(errno));
            created = true;
        } else if (!S_ISDIR(st.st_mode)) {
            throw InputError("reduce: -o " + *out_dir + ": exists and is not a directory");
        }
        try {
            write_reduction(model, *out_dir);
        } catch (...) {
            if (created) ::rmdir(out_dir->c_str());  // a directory this command made stays only with its files
            throw;
        }
        exit_code = 0;
    });
}

}  // namespace hsnc::cli
