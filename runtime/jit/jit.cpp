// hsnc -- Jit (jit.h): Clang CompilerInstance -> LLVM IR (EmitLLVMOnlyAction,
// in libhsnc_jit_clang.so: runtime/jit/jit_frontend.h, loaded on the first compile)
// -> object file (orc::SimpleCompiler, with the TargetMachine the LLJIT itself
// would use) -> ORC LLJIT (addObjectFile), after LLVM's KaleidoscopeJIT
// (create, add, lookup; Expected and Error handled here and nowhere else).
// Producing the object ourselves, rather than handing the IR to the LLJIT,
// is what lets a persistent cache skip Clang and LLVM's code generation
// altogether on a hit (runtime/jit/kernel_cache.h).
#include "jit.h"

#include <dlfcn.h>
#include <llvm/ExecutionEngine/Orc/CompileUtils.h>
#include <llvm/ExecutionEngine/Orc/ExecutionUtils.h>
#include <llvm/ExecutionEngine/Orc/JITTargetMachineBuilder.h>
#include <llvm/ExecutionEngine/Orc/LLJIT.h>
#include <llvm/ExecutionEngine/Orc/ThreadSafeModule.h>
#include <llvm/IR/LLVMContext.h>
#include <llvm/IR/Module.h>
#include <llvm/Object/ObjectFile.h>
#include <llvm/Support/Error.h>
#include <llvm/Support/Host.h>
#include <llvm/Support/MemoryBuffer.h>
#include <llvm/Support/TargetSelect.h>
#include <llvm/Support/raw_ostream.h>
#include <llvm/Target/TargetMachine.h>

#include <mutex>
#include <vector>

#include "error.h"
#include "jit_frontend.h"
#include "kernel_cache.h"

namespace hsnc {
namespace {

std::string error_text(llvm::Error err) { return llvm::toString(std::move(err)); }

void initialize_llvm() {
    static std::once_flag once;
    static bool ok = false;
    std::call_once(once, [] {
        ok = !llvm::InitializeNativeTarget() && !llvm::InitializeNativeTargetAsmPrinter();
    });
    if (!ok) throw RunError("Jit::Jit(): LLVM cannot generate code for this host (" + llvm::sys::getProcessTriple() + ")");
}

// The Clang front end, from libhsnc_jit_clang.so beside this library, loaded
// once per process on the first compile.
JitFrontendFn frontend() {
    static std::once_flag once;
    static JitFrontendFn fn = nullptr;
    static std::string problem;
    std::call_once(once, [] {
        Dl_info self;
        if (!::dladdr(reinterpret_cast<void*>(&frontend), &self) || !self.dli_fname) {
            problem = "cannot locate libhsnc_jit";
            return;
        }
        std::string path = self.dli_fname;
        path = path.substr(0, path.find_last_of('/') + 1) + HSNC_JIT_FRONTEND_MODULE;
        void* module = ::dlopen(path.c_str(), RTLD_NOW | RTLD_LOCAL);  // kept loaded
        if (!module) {
            problem = std::string("cannot load the Clang front end: ") + ::dlerror();
            return;
        }
        fn = reinterpret_cast<JitFrontendFn>(::dlsym(module, kJitFrontendSymbol));
        if (!fn) problem = path + " has no " + kJitFrontendSymbol;
    });
    if (!fn) throw RunError("Jit::compile(): " + problem);
    return fn;
}

}  // namespace

struct Jit::Impl {
    std::unique_ptr<llvm::orc::LLJIT> lljit;
    std::unique_ptr<llvm::TargetMachine> machine;  // the LLJIT's own target, for compile()
};

Jit::Jit() : impl_(std::make_unique<Impl>()) {
    initialize_llvm();
    auto builder = llvm::orc::JITTargetMachineBuilder::detectHost();
    if (!builder) throw RunError("Jit::Jit(): cannot describe this host to LLVM: " + error_text(builder.takeError()));
    // The large code model: every address in the object is an absolute 64-bit
    // relocation, wherever the code lands, which is what lets a cached object
    // be mapped without LLVM (runtime/jit/object_loader.h). LLVM 14's JIT default
    // on x86-64, stated here because the loader depends on it.
    builder->setCodeModel(llvm::CodeModel::Large);
    auto machine = builder->createTargetMachine();
    if (!machine) throw RunError("Jit::Jit(): cannot create an LLVM target machine: " + error_text(machine.takeError()));
    impl_->machine = std::move(*machine);
    auto jit = llvm::orc::LLJITBuilder().setJITTargetMachineBuilder(*builder).create();
    if (!jit) throw RunError("Jit::Jit(): cannot create the LLVM JIT: " + error_text(jit.takeError()));
    impl_->lljit = std::move(*jit);
    // Kernels call libm (__builtin_exp, sin, cos lower to exp, sin, cos):
    // resolve them from the symbols already loaded in this process.
    auto process = llvm::orc::DynamicLibrarySearchGenerator::GetForCurrentProcess(
        impl_->lljit->getDataLayout().getGlobalPrefix());
    if (!process) throw RunError("Jit::Jit(): cannot search this process's symbols: " + error_text(process.takeError()));
    impl_->lljit->getMainJITDylib().addGenerator(std::move(*process));
}

Jit::~Jit() = default;

void Jit::add(const std::string& name, const std::string& source) { add_object(name, compile(name, source)); }

std::string Jit::compile(const std::string& name, const std::string& source) {
    const std::string triple = impl_->machine->getTargetTriple().str();
    auto context = std::make_unique<llvm::LLVMContext>();
    std::string error;
    std::unique_ptr<llvm::Module> module(frontend()(context.get(), triple, name, source, error));
    if (!module) throw RunError("Jit::compile(): " + error);

    // Machine code, as the LLJIT's IR layer would make it (same target machine).
    module->setDataLayout(impl_->machine->createDataLayout());
    llvm::orc::SimpleCompiler codegen(*impl_->machine);
    auto object = codegen(*module);
    if (!object) throw RunError("Jit::compile(): cannot generate code for " + name + ": " + error_text(object.takeError()));
    return (*object)->getBuffer().str();
}

void Jit::add_object(const std::string& name, const std::string& object) {
    // Check that it parses as an object file for this host before the JIT
    // owns it: a bad object found only at lookup would leave its symbols
    // failed in the JIT, so that a recompiled one could not be added.
    auto buffer = llvm::MemoryBuffer::getMemBufferCopy(object, name + ".o");
    auto parsed = llvm::object::ObjectFile::createObjectFile(buffer->getMemBufferRef());
    if (!parsed) throw RunError("Jit::add_object(): " + name + " is not an object file: " + error_text(parsed.takeError()));
    if ((*parsed)->getArch() != impl_->machine->getTargetTriple().getArch())
        throw RunError("Jit::add_object(): " + name + " is an object file for another architecture");
    if (llvm::Error err = impl_->lljit->addObjectFile(std::move(buffer)))
        throw RunError("Jit::add_object(): cannot add " + name + " to the JIT: " + error_text(std::move(err)));
}

std::string Jit::cache_key(const std::string& source) const { return jit_cache_key(source); }

void* Jit::lookup(const std::string& symbol) {
    auto sym = impl_->lljit->lookup(symbol);
    if (!sym) throw RunError("Jit::lookup(): no symbol '" + symbol + "': " + error_text(sym.takeError()));
    return reinterpret_cast<void*>(static_cast<std::uintptr_t>(sym->getAddress()));
}

}  // namespace hsnc
