#include "hsnc/generate.h"

#include "emitter.h"
#include "kernel_set.h"

namespace hsnc {

GeneratedKernels::GeneratedKernels() : set(std::make_unique<KernelSet>()) {}
GeneratedKernels::~GeneratedKernels() = default;
GeneratedKernels::GeneratedKernels(GeneratedKernels&&) noexcept = default;
GeneratedKernels& GeneratedKernels::operator=(GeneratedKernels&&) noexcept = default;

std::size_t GeneratedKernels::kernels() const { return set->kernels.size(); }
const std::string& GeneratedKernels::note() const { return set->note; }

GeneratedKernels generate_kernels(const Model& model, const std::vector<std::string>& sweep_parameters) {
    GeneratedKernels k;
    *k.set = generate_kernel_set(model, sweep_parameters);
    return k;
}

std::vector<std::string> write_kernels(const Model& model, const GeneratedKernels& kernels, const std::string& dir) {
    std::vector<std::string> written;
    for (const GeneratedFile& f : kernels.set->kernels) {
        write_if_changed(dir, f.name, f.text);
        written.push_back(f.name);
    }
    write_if_changed(dir, model.name + ".manifest", kernels.set->manifest);
    written.push_back(model.name + ".manifest");
    write_if_changed(dir, "registry.cpp", emit_registry(kernels.set->symbols));
    written.push_back("registry.cpp");
    return written;
}

}  // namespace hsnc
