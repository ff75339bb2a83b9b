#include "plugin_module.h"

#include <dlfcn.h>
#include <link.h>
#include <unistd.h>

namespace hsnc::api {

std::string plugin_module_path(const std::string& file_name) {
    // The object holding this function. For a shared library, dladdr1 names
    // its file; for the executable, glibc gives argv[0] (possibly a bare name
    // found through PATH), so take /proc/self/exe instead.
    std::string file;
    Dl_info info{};
    link_map* map = nullptr;
    if (::dladdr1(reinterpret_cast<void*>(&plugin_module_path), &info, reinterpret_cast<void**>(&map),
                  RTLD_DL_LINKMAP) != 0 &&
        map != nullptr && map->l_name != nullptr && map->l_name[0] != '\0')
        file = map->l_name;
    if (file.empty()) {
        char exe[4096];
        const ssize_t len = ::readlink("/proc/self/exe", exe, sizeof exe - 1);
        file = len > 0 ? std::string(exe, static_cast<std::size_t>(len)) : std::string("./");
    }
    const std::string dir = file.substr(0, file.find_last_of('/') + 1);
    const std::string beside = dir + file_name;
    const std::string installed = dir + HSNC_LIBDIR_FROM_BINDIR + "/" + file_name;
    return ::access(beside.c_str(), F_OK) != 0 && ::access(installed.c_str(), F_OK) == 0 ? installed : beside;
}

void* plugin_module_symbol(const std::string& path, const char* symbol, SymbolScope scope, std::string& problem) {
    void* module = ::dlopen(path.c_str(), RTLD_NOW | (scope == SymbolScope::kGlobal ? RTLD_GLOBAL : RTLD_LOCAL));
    if (!module) {
        problem = ::dlerror();
        return nullptr;
    }
    void* address = ::dlsym(module, symbol);
    if (!address) problem = path + " has no " + symbol;
    return address;
}

}  // namespace hsnc::api
