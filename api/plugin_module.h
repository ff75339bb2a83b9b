// hsnc -- the modules hsnc loads at run time, only when a run needs them:
// libhsnc_jit.so (LLVM, for --kernels jit) and libhsnc_mpi.so (MPI, under an
// MPI launcher). Finding them and opening them is one rule, written here.
// Private to the library (not installed).
#pragma once

#include <string>

namespace hsnc::api {

/// Where the module FILE_NAME is: beside the object this code is linked into
/// (the shared libhsnc.so, found with dladdr1, or the executable when hsnc
/// links the library statically), else in the library directory of an
/// installed tree (bin/hsnc, lib/FILE_NAME).
std::string plugin_module_path(const std::string& file_name);

/// How a module's symbols are made visible: kLocal keeps them to the module;
/// kGlobal lets libraries the module itself dlopens (Open MPI's plugins)
/// resolve against them.
enum class SymbolScope { kLocal, kGlobal };

/// Opens the module at PATH (it stays loaded for the life of the process) and
/// returns its SYMBOL. On failure returns nullptr and sets PROBLEM to the
/// loader's reason; the caller adds what it was loading for.
void* plugin_module_symbol(const std::string& path, const char* symbol, SymbolScope scope, std::string& problem);

}  // namespace hsnc::api
