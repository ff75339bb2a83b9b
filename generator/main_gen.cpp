// hsnc_gen -- the build's generator tool (not installed).
//   hsnc_gen --samples FILE        every kernel of generator/sample_models.h, with
//                                  hsnc::sample_registry(), in one source FILE
//   hsnc_gen DIR [MODEL.toml ...]  DIR/<model file stem>.cpp with every kernel of
//                                  each model, DIR/<stem>.manifest (the configurations
//                                  generated, generator/kernel_set.h), and DIR/registry.cpp
//                                  (hsnc::aot_registry)
#include <filesystem>
#include <iostream>
#include <string>
#include <vector>

#include "emitter.h"
#include "error.h"
#include "kernel_set.h"
#include "model_reader.h"
#include "sample_models.h"

int main(int argc, char** argv) {
    using namespace hsnc;
    namespace fs = std::filesystem;
    try {
        std::vector<std::string> args(argv + 1, argv + argc);
        const char* usage = "usage: hsnc_gen --samples FILE | hsnc_gen DIR [MODEL.toml ...]\n";
        if (args.empty()) {
            std::cerr << usage;
            return 2;
        }
        if (args[0] == "--help" || args[0] == "-h") {
            std::cout << usage;
            return 0;
        }
        if (args[0].rfind("-", 0) == 0 && args[0] != "--samples") {  // not taken for an output folder
            std::cerr << "hsnc_gen: unknown option " << args[0] << "\n" << usage;
            return 2;
        }
        std::vector<std::string> symbols;
        if (args[0] == "--samples") {
            if (args.size() != 2) throw InputError("hsnc_gen: --samples takes one file");
            std::string text;
            for (const Model& m : sample_models())
                for (const Configuration& cfg : all_configurations(m)) {
                    text += emit_kernel(derive(m, cfg)) + "\n";
                    symbols.push_back(kernel_symbol(m, cfg));
                }
            text += emit_registry(symbols, "sample_registry");
            const fs::path out(args[1]);
            write_if_changed(out.parent_path().string(), out.filename().string(), text);
            return 0;
        }
        for (std::size_t k = 1; k < args.size(); ++k) {
            const KernelSet set = generate_kernel_set(read_model(args[k]));
            if (!set.note.empty()) std::cerr << "hsnc_gen: " << set.note << "\n";
            const std::string stem = fs::path(args[k]).stem().string();
            write_if_changed(args[0], stem + ".cpp", combined_source(set));
            write_if_changed(args[0], stem + ".manifest", set.manifest);
            symbols.insert(symbols.end(), set.symbols.begin(), set.symbols.end());
        }
        write_if_changed(args[0], "registry.cpp", emit_registry(symbols));
        return 0;
    } catch (const InputError& e) {
        std::cerr << "hsnc_gen: " << e.what() << "\n";
        return 2;
    } catch (const std::exception& e) {
        std::cerr << "hsnc_gen: " << e.what() << "\n";
        return 1;
    }
}
