#include "jit_module.h"

#include <dlfcn.h>
#include <link.h>
#include <unistd.h>

#include <utility>

namespace hsnc::api {

#ifdef HSNC_JIT_MODULE
std::string jit_module_path() {
    // The object holding this function. For a shared library, dladdr names
    // its file; for the executable, glibc gives argv[0] (possibly a bare
    // name found through PATH), so take /proc/self/exe instead.
    std::string file;
    Dl_info info{};
    link_map* map = nullptr;
    if (::dladdr1(reinterpret_cast<void*>(&jit_module_path), &info, reinterpret_cast<void**>(&map),
                  RTLD_DL_LINKMAP) != 0 &&
        map != nullptr && map->l_name != nullptr && map->l_name[0] != '\0')
        file = map->l_name;
    if (file.empty()) {
        char exe[4096];
        const ssize_t len = ::readlink("/proc/self/exe", exe, sizeof exe - 1);
        file = len > 0 ? std::string(exe, static_cast<std::size_t>(len)) : std::string("./");
    }
    const std::string dir = file.substr(0, file.find_last_of('/') + 1);
    const std::string beside = dir + HSNC_JIT_MODULE;
    // An installed hsnc: bin/hsnc, lib/libhsnc_jit.so.
    const std::string installed = dir + HSNC_LIBDIR_FROM_BINDIR + "/" + HSNC_JIT_MODULE;
    return ::access(beside.c_str(), F_OK) != 0 && ::access(installed.c_str(), F_OK) == 0 ? installed : beside;
}

std::unique_ptr<JitSolverProvider> load_jit_provider(const Model& model, JitSolverProvider::SourceFn source,
                                                     const JitOptions& options) {
    const std::string path = jit_module_path();
    void* module = ::dlopen(path.c_str(), RTLD_NOW | RTLD_LOCAL);  // kept loaded: kernels live in it
    if (!module) throw JitUnavailable(std::string("cannot load the JIT module: ") + ::dlerror());
    auto factory = reinterpret_cast<JitProviderFactory>(::dlsym(module, kJitProviderFactorySymbol));
    if (!factory) throw JitUnavailable(path + " has no " + kJitProviderFactorySymbol);
    // The factory makes a JitSolverProvider (runtime/jit/jit_solver_provider.cpp).
    return std::unique_ptr<JitSolverProvider>(
        static_cast<JitSolverProvider*>(factory(model, std::move(source), options)));
}

#else  // built with HSNC_WITH_JIT=OFF
std::string jit_module_path() { return ""; }
std::unique_ptr<JitSolverProvider> load_jit_provider(const Model&, JitSolverProvider::SourceFn, const JitOptions&) {
    throw JitUnavailable("this hsnc was built without the JIT (HSNC_WITH_JIT=OFF)");
}
#endif

}  // namespace hsnc::api
