// hsnc -- how the runtime finds an ahead-of-time kernel.
//
// `hsnc generate` and the build (library hsnc_kernels, from generated/) emit a
// registry source that defines hsnc::aot_registry(): every compiled kernel,
// in a fixed order. A kernel is used only when model name, model hash
// (model/model_hash.h) and configuration key all match, so a model file
// edited after generation silently falls back to another solver instead of
// running stale numbers.
//
// The runtime library does not define aot_registry(): the program that links
// hsnc_kernels (the CLI, the tests) passes the registry to whoever needs it.
#pragma once

#include <cstddef>
#include <cstdint>
#include <cstring>

#include "kernel_abi.h"

namespace hsnc {

struct AotRegistry {
    const hsnc_kernel* const* kernels = nullptr;
    std::size_t count = 0;
};

/// Defined by the generated registry source (hsnc_kernels).
const AotRegistry& aot_registry();

/// The kernel for (model name, model hash, configuration key), or nullptr.
inline const hsnc_kernel* find_aot_kernel(const AotRegistry& registry, const char* model_name,
                                          std::uint64_t model_hash, const char* config_key) {
    for (std::size_t i = 0; i < registry.count; ++i) {
        const hsnc_kernel* k = registry.kernels[i];
        if (k->model_hash == model_hash && std::strcmp(k->model_name, model_name) == 0 &&
            std::strcmp(k->config_key, config_key) == 0)
            return k;
    }
    return nullptr;
}

}  // namespace hsnc
