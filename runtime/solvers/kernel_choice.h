// hsnc -- the kinds of kernels the exact method's segment solvers come from
// (--kernels, SimulateOptions::kernels, Python's kernels=), named once: the
// runtime's providers (kernel_mode.h), the facade (api/hsnc/simulate.h), the
// command line and the Python module all take this enum and this name table.
// Installed with the facade's headers (simulate.h includes it).
#pragma once

#include <cstddef>
#include <optional>
#include <string>

namespace hsnc {

/// Where the exact method's segment solvers come from.
enum class KernelChoice {
    automatic,  ///< the ahead-of-time kernels when the model has them (bundled
                ///  models as generated), else generic; never compiles. The
                ///  same bits whichever it takes.
    aot,        ///< ahead-of-time kernels only (InputError when the model has none)
    jit,        ///< a kernel per configuration, from the persistent cache or
                ///  compiled in-process (RunError when libhsnc_jit.so cannot be loaded)
    generic,    ///< each configuration's program (derived in double-double and
                ///  lowered, as the kernels are printed from it) run by an
                ///  interpreter: the kernels' bits without a compiler
    interp,     ///< the same as generic (its name before generic was the
                ///  interpreter; docs/interface.md: "another name for generic"),
                ///  kept distinct so that a run reports the name it was given
    eigen,      ///< the Eigen solver: the closed forms written independently of
                ///  the programs (the tests' oracle), agreeing with the other
                ///  kinds to rounding, not to the bit; its entry into a
                ///  configuration is cheaper (a modal analysis in double)
    tiered,     ///< interp first; a configuration that has run
                ///  SimulateOptions::tier_evaluations evaluations gets its JIT
                ///  kernel, compiled by a child process (the run never
                ///  waits), kernels in the persistent cache from its first entry;
                ///  the same bits as interp and jit (tiered_provider.h)
};

struct KernelChoiceName {
    const char* name;
    KernelChoice choice;
};

/// The one name table, in the order messages list the names.
inline constexpr KernelChoiceName kKernelChoiceNames[] = {
    {"auto", KernelChoice::automatic}, {"aot", KernelChoice::aot},   {"generic", KernelChoice::generic},
    {"interp", KernelChoice::interp},  {"eigen", KernelChoice::eigen}, {"jit", KernelChoice::jit},
    {"tiered", KernelChoice::tiered},
};

/// "auto", "aot", "generic", "interp", "eigen", "jit", "tiered".
inline const char* kernel_choice_name(KernelChoice choice) {
    for (const KernelChoiceName& n : kKernelChoiceNames)
        if (n.choice == choice) return n.name;
    return "?";
}

/// The choice a name stands for; nothing for a name not in the table.
inline std::optional<KernelChoice> parse_kernel_choice(const std::string& name) {
    for (const KernelChoiceName& n : kKernelChoiceNames)
        if (name == n.name) return n.choice;
    return std::nullopt;
}

/// "auto, aot, generic, interp, eigen, jit or tiered": what a message says is expected.
inline std::string kernel_choice_names() {
    std::string text;
    constexpr std::size_t kCount = sizeof(kKernelChoiceNames) / sizeof(kKernelChoiceNames[0]);
    for (std::size_t i = 0; i < kCount; ++i)
        text += std::string(i == 0 ? "" : i + 1 == kCount ? " or " : ", ") + kKernelChoiceNames[i].name;
    return text;
}

}  // namespace hsnc
