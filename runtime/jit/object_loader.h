// hsnc -- LoadedObject: a cached kernel's object file mapped into this process
// without LLVM, so that a run whose kernels all come from the persistent cache
// (runtime/jit/kernel_cache.h) does not load libLLVM (about 13 ms of start-up).
//
// Deliberately minimal: it accepts exactly what the JIT produces for a kernel
// (runtime/jit/jit.cpp: an x86-64 ELF relocatable object, large code model, so
// every relocation is R_X86_64_64, absolute 64-bit) and refuses anything else
// with a reason; the caller then falls back to LLVM's own linker. Every offset,
// index and size in the file is checked against the file before it is used.
// Sections are copied into fresh pages; undefined symbols (libm's sin, cos,
// sincos, exp, sqrt) are resolved in this process (dlsym); code pages end up
// read+execute, the others read-only.
#pragma once

#include <memory>
#include <string>
#include <vector>

namespace hsnc {

class LoadedObject {
public:
    /// Map `elf`. Returns null with the reason in `error` when it is not an
    /// object this loader takes (the caller falls back to LLVM).
    static std::unique_ptr<LoadedObject> load(const std::string& elf, std::string& error);
    ~LoadedObject();
    LoadedObject(const LoadedObject&) = delete;
    LoadedObject& operator=(const LoadedObject&) = delete;

    /// Address of the defined global symbol `name` when the object gives it
    /// at least `min_size` bytes (its ELF st_size), else null.
    void* symbol(const std::string& name, std::size_t min_size = 0) const;
    /// The names of the defined global symbols, in symbol table order.
    std::vector<std::string> symbol_names() const;

    /// Whether [p, p + size) lies inside the mapped object (code or data).
    bool contains(const void* p, std::size_t size) const;
    /// Whether `p` is a NUL-terminated string inside the mapped object.
    bool contains_string(const char* p) const;
    /// Whether `p` points into the object's code (read+execute pages).
    bool contains_code(const void* p) const;

    /// The largest object taken (sections laid out, page-rounded).
    static constexpr std::size_t kMaxMappedBytes = std::size_t{64} << 20;

private:
    LoadedObject() = default;
    void* base_ = nullptr;
    std::size_t size_ = 0, code_size_ = 0;
    struct Global {
        std::string name;
        void* address;
        std::size_t size;
    };
    std::vector<Global> globals_;
};

}  // namespace hsnc
