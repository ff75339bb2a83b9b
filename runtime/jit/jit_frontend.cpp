// hsnc -- jit_frontend.h: Clang CompilerInstance -> LLVM IR (EmitLLVMOnlyAction),
// both files (the source and kernel_abi.h) served from memory.
#include "jit_frontend.h"

#include <clang/Basic/Diagnostic.h>
#include <clang/Basic/DiagnosticOptions.h>
#include <clang/CodeGen/CodeGenAction.h>
#include <clang/Frontend/CompilerInstance.h>
#include <clang/Frontend/CompilerInvocation.h>
#include <clang/Frontend/TextDiagnosticPrinter.h>
#include <clang/Lex/PreprocessorOptions.h>
#include <llvm/IR/LLVMContext.h>
#include <llvm/IR/Module.h>
#include <llvm/Support/MemoryBuffer.h>
#include <llvm/Support/raw_ostream.h>

#include <exception>
#include <memory>

#include "kernel_abi_text.h"  // generated at build time: kKernelAbiHeaderText

namespace {

// The virtual directory that holds the embedded kernel_abi.h and the source
// being compiled; it exists only inside Clang's source manager.
constexpr const char* kVirtualDir = "/hsnc-jit";

llvm::Module* compile(llvm::LLVMContext* context, const std::string& triple, const std::string& name,
                      const std::string& source, std::string& error) {
    const std::string dir = kVirtualDir;
    const std::string path = dir + "/" + name;
    std::vector<const char*> args = {"-triple", triple.c_str()};
    args.insert(args.end(), hsnc::jit_compile_flags().begin(), hsnc::jit_compile_flags().end());
    args.insert(args.end(), {"-I", dir.c_str(), path.c_str()});

    std::string diagnostics;
    llvm::raw_string_ostream diag_stream(diagnostics);
    llvm::IntrusiveRefCntPtr<clang::DiagnosticOptions> diag_opts(new clang::DiagnosticOptions());
    clang::TextDiagnosticPrinter printer(diag_stream, diag_opts.get());
    clang::DiagnosticsEngine arg_diags(llvm::IntrusiveRefCntPtr<clang::DiagnosticIDs>(new clang::DiagnosticIDs()),
                                       diag_opts, &printer, /*ShouldOwnClient=*/false);

    auto invocation = std::make_shared<clang::CompilerInvocation>();
    const bool parsed = clang::CompilerInvocation::CreateFromArgs(*invocation, args, arg_diags);
    if (!parsed) {
        diag_stream.flush();
        error = "cannot set up Clang for " + name + ": " + diagnostics;
        return nullptr;
    }
    // Both files live in memory; the source manager takes ownership of the buffers.
    clang::PreprocessorOptions& pp = invocation->getPreprocessorOpts();
    pp.addRemappedFile(path, llvm::MemoryBuffer::getMemBufferCopy(source, path).release());
    pp.addRemappedFile(dir + "/kernel_abi.h",
                       llvm::MemoryBuffer::getMemBuffer(hsnc::kKernelAbiHeaderText, dir + "/kernel_abi.h").release());

    clang::CompilerInstance compiler;
    compiler.setInvocation(std::move(invocation));
    compiler.createDiagnostics(&printer, /*ShouldOwnClient=*/false);
    compiler.setVerboseOutputStream(diag_stream);  // "1 error generated." goes with the diagnostics

    clang::EmitLLVMOnlyAction action(context);
    const bool compiled = compiler.ExecuteAction(action);
    std::unique_ptr<llvm::Module> module = compiled ? action.takeModule() : nullptr;
    diag_stream.flush();
    if (!module) error = "Clang cannot compile " + name + ":\n" + diagnostics;
    return module.release();
}

}  // namespace

extern "C" __attribute__((visibility("default"))) llvm::Module* hsnc_jit_frontend_compile(
    llvm::LLVMContext* context, const std::string& triple, const std::string& name, const std::string& source,
    std::string& error) {
    try {
        return compile(context, triple, name, source, error);
    } catch (const std::exception& e) {  // bad_alloc; Clang itself reports through diagnostics
        error = std::string("Clang failed on ") + name + ": " + e.what();
        return nullptr;
    }
}
