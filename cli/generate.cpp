// hsnc generate MODEL -o DIR -- write the specialised C++ kernels of a model
// (interface.md section 3): one translation unit per configuration
// (generator/emitter.h), all of them while there are at most 64
// configurations, else those of the model's default run plus the initial one
// and its neighbours (said on stderr), plus <model>.manifest listing them and
// registry.cpp defining hsnc::aot_registry() (kernels/aot_registry.h).
// The files include "kernel_abi.h" and "aot_registry.h" from runtime/.
#include <iostream>

#include "commands.h"
#include "error.h"
#include "hsnc/generate.h"
#include "model_reader.h"
#include "param_emitter.h"

namespace hsnc::cli {

void add_generate(CLI::App& app, int& exit_code) {
    auto* sub = app.add_subcommand("generate", "write the specialised C++ kernels of a model");
    auto model_path = std::make_shared<std::string>();
    auto out_dir = std::make_shared<std::string>();
    auto params = std::make_shared<std::string>();
    sub->add_option("MODEL", *model_path, "model file (TOML)")->required();
    sub->add_option("-o,--out-dir", *out_dir,
                    "directory for <model>_<configuration key>.cpp, <model>.manifest and registry.cpp (created if needed)")
        ->required();
    CLI::Option* params_opt = sub->add_option("--params", *params,
                    "emit sweep kernels: these parameters (NAME,NAME,... or all) become run-time arguments of the "
                    "kernels' configure(); what the model computes from them follows them");
    sub->footer(
        "Every configuration is generated while there are at most 64 (2^(contacts + friction masses));\n"
        "beyond that, those the model's default run ([simulate].t_end, Eigen solver) visits, plus the\n"
        "initial configuration and its single-switch neighbours (at most 128). <model>.manifest lists the\n"
        "configurations generated. Compile the files with runtime/ on the include path (kernel_abi.h,\n"
        "aot_registry.h).");
    sub->callback([&exit_code, model_path, out_dir, params, params_opt] {
        // An empty path would be taken as the current directory; say so instead.
        if (out_dir->empty())
            throw InputError("generate: -o '': empty output directory (write -o . for the current directory)");
        const Model model = read_model(*model_path);
        const std::vector<std::string> kept =
            params_opt->count() == 0 ? std::vector<std::string>{} : kept_parameters(model, *params);
        const GeneratedKernels kernels = generate_kernels(model, kept);
        if (!kernels.note().empty()) std::cerr << "hsnc generate: " << kernels.note() << "\n";
        try {
            write_kernels(model, kernels, *out_dir);
        } catch (const RunError& e) {
            throw InputError(std::string("generate: -o ") + *out_dir + ": " + e.what());  // a bad output path
        }
        std::cout << "wrote " << kernels.kernels() << (kept.empty() ? "" : " sweep") << " kernels, " << model.name
                  << ".manifest and registry.cpp of model '" << model.name
                  << "' to " << *out_dir << "\n";
        exit_code = 0;
    });
}

}  // namespace hsnc::cli
