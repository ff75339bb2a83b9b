// LoadedObject (runtime/jit/object_loader.h): a JIT-compiled kernel mapped without
// LLVM must compute exactly what the same object linked by LLVM computes, and
// anything outside what the loader supports is refused with a reason.
#include <gtest/gtest.h>

#include <elf.h>

#include <cmath>
#include <cstring>
#include <random>
#include <string>
#include <vector>

#include "cli_runner.h"
#include "derivation.h"
#include "emitter.h"
#include "jit.h"
#include "kernel_solver.h"
#include "model_reader.h"
#include "object_loader.h"

namespace hsnc {
namespace {

struct Compiled {
    std::string symbol, object;
};

Compiled compile(Jit& jit, const Model& model, const Configuration& cfg) {
    const std::string symbol = kernel_symbol(model, cfg);
    return {symbol, jit.compile(symbol + ".cpp", emit_kernel(derive(model, cfg)))};
}

// Every output of every eval, at many taus, bit for bit.
void expect_same_kernel(const hsnc_kernel& a, const hsnc_kernel& b, const Model& model) {
    ASSERT_EQ(a.n_dof, b.n_dof);
    ASSERT_EQ(a.n_slider, b.n_slider);
    ASSERT_EQ(a.n_switch, b.n_switch);
    ASSERT_EQ(a.n_coef, b.n_coef);
    EXPECT_STREQ(a.config_key, b.config_key);
    EXPECT_EQ(a.model_hash, b.model_hash);
    for (int f = 0; f < a.n_switch; ++f) EXPECT_EQ(a.switches[f].kind, b.switches[f].kind);
    const std::size_t n = model.dof(), m = static_cast<std::size_t>(a.n_switch);
    std::vector<double> ca(static_cast<std::size_t>(a.n_coef)), cb(ca.size());
    std::vector<signed char> sgn(n, 1);
    a.setup(ca.data(), 3.25, 1e-16, model.x0.data(), model.v0.data(), sgn.data());
    b.setup(cb.data(), 3.25, 1e-16, model.x0.data(), model.v0.data(), sgn.data());
    EXPECT_EQ(0, std::memcmp(ca.data(), cb.data(), ca.size() * sizeof(double)));
    std::vector<double> oa(3 * n + 4 * m), ob(oa.size());
    for (double tau : {0.0, 1e-9, 1e-3, 0.0171, 0.25, 1.0, 7.5}) {
        double* p = oa.data();
        double* q = ob.data();
        a.eval(ca.data(), tau, p, p + n, p + 2 * n, p + 3 * n, p + 3 * n + m, p + 3 * n + 2 * m, p + 3 * n + 3 * m);
        b.eval(cb.data(), tau, q, q + n, q + 2 * n, q + 3 * n, q + 3 * n + m, q + 3 * n + 2 * m, q + 3 * n + 3 * m);
        EXPECT_EQ(0, std::memcmp(oa.data(), ob.data(), oa.size() * sizeof(double))) << "tau = " << tau;
        EXPECT_TRUE(std::isfinite(oa[0]));
    }
}

TEST(ObjectLoader, KernelsComputeExactlyWhatLlvmLinkedOnesDo) {
    Jit jit;
    std::vector<std::unique_ptr<LoadedObject>> keep;
    for (const char* file : {"seed-scenario-2.toml", "chain-8.toml", "seed-scenario-1.toml"}) {
        const Model model = read_model(testing::model_path(file));
        std::vector<Configuration> cfgs = {Configuration::all_open(model)};
        Configuration closed = Configuration::all_open(model);
        closed.closed[0] = 1;
        cfgs.push_back(closed);
        for (const Configuration& cfg : cfgs) {
            const Compiled c = compile(jit, model, cfg);
            std::string why;
            keep.push_back(LoadedObject::load(c.object, why));
            ASSERT_TRUE(keep.back()) << file << " " << cfg.key() << ": " << why;
            const auto* mine = static_cast<const hsnc_kernel*>(keep.back()->symbol(c.symbol));
            ASSERT_NE(mine, nullptr) << c.symbol;
            jit.add_object(c.symbol, c.object);
            const auto* llvms = static_cast<const hsnc_kernel*>(jit.lookup(c.symbol));
            SCOPED_TRACE(std::string(file) + " " + cfg.key());
            expect_same_kernel(*mine, *llvms, model);
            EXPECT_EQ(keep.back()->symbol("no_such_symbol"), nullptr);
        }
    }
}

TEST(ObjectLoader, RefusesWhatItDoesNotSupportWithAReason) {
    Jit jit;
    const Model model = read_model(testing::model_path("seed-scenario-2.toml"));
    const std::string object = compile(jit, model, Configuration::all_open(model)).object;
    auto refusal = [](const std::string& bytes) {
        std::string why;
        EXPECT_EQ(LoadedObject::load(bytes, why), nullptr);
        return why;
    };
    EXPECT_EQ(refusal(""), "shorter than an ELF header");
    EXPECT_EQ(refusal(std::string(100, 'x')), "not an ELF file");
    EXPECT_EQ(refusal(object.substr(0, object.size() - 200)), "section headers outside the file");

    Elf64_Ehdr eh;
    std::memcpy(&eh, object.data(), sizeof eh);
    std::string other = object;
    const Elf64_Half arm = EM_AARCH64;
    std::memcpy(&other[offsetof(Elf64_Ehdr, e_machine)], &arm, sizeof arm);
    EXPECT_EQ(refusal(other), "not an x86-64 relocatable object");

    // A relocation of another type (PC-relative, 32 bits) in the first RELA section.
    std::vector<Elf64_Shdr> sh(eh.e_shnum);
    std::memcpy(sh.data(), object.data() + eh.e_shoff, sh.size() * sizeof(Elf64_Shdr));
    std::size_t rela = 0;
    for (std::size_t i = 0; i < sh.size() && !rela; ++i)
        if (sh[i].sh_type == SHT_RELA && sh[i].sh_size) rela = i;
    ASSERT_NE(rela, 0u);
    std::string pc32 = object;
    Elf64_Rela r;
    std::memcpy(&r, pc32.data() + sh[rela].sh_offset, sizeof r);
    r.r_info = ELF64_R_INFO(ELF64_R_SYM(r.r_info), R_X86_64_PC32);
    std::memcpy(&pc32[sh[rela].sh_offset], &r, sizeof r);
    EXPECT_EQ(refusal(pc32), "relocation type 2 (only R_X86_64_64)");
    // A relocation past the end of its section.
    std::string past = object;
    std::memcpy(&r, past.data() + sh[rela].sh_offset, sizeof r);
    r.r_offset = sh[sh[rela].sh_info].sh_size - 4;
    std::memcpy(&past[sh[rela].sh_offset], &r, sizeof r);
    EXPECT_EQ(refusal(past), "a relocation outside its section");

    // An undefined symbol this process does not have.
    const std::string missing = Jit().compile("missing.cpp", "extern \"C\" double hsnc_no_such_function(double);\n"
                                                             "extern \"C\" double f(double x) { return hsnc_no_such_function(x); }\n");
    EXPECT_EQ(refusal(missing), "undefined symbol 'hsnc_no_such_function' not found in this process");
}

// An empty symbol table (found by fuzz/fuzz_object_loader: a memcpy to the
// null data() of an empty vector, which UBSan reports, so this test fails
// without the fix in the sanitized suite, .ci/sanitize): refused, since the
// relocations have no symbols.
TEST(ObjectLoader, RefusesAnEmptySymbolTable) {
    Jit jit;
    const Model model = read_model(testing::model_path("seed-scenario-2.toml"));
    std::string object = compile(jit, model, Configuration::all_open(model)).object;
    Elf64_Ehdr eh;
    std::memcpy(&eh, object.data(), sizeof eh);
    bool emptied = false;
    for (std::size_t i = 1; i < eh.e_shnum; ++i) {
        Elf64_Shdr sh;
        std::memcpy(&sh, object.data() + eh.e_shoff + i * sizeof sh, sizeof sh);
        if (sh.sh_type != SHT_SYMTAB) continue;
        sh.sh_size = 0;
        std::memcpy(&object[eh.e_shoff + i * sizeof sh], &sh, sizeof sh);
        emptied = true;
    }
    ASSERT_TRUE(emptied);
    std::string why;
    EXPECT_EQ(LoadedObject::load(object, why), nullptr);
    EXPECT_EQ(why, "a relocation against an unusable symbol");
}

// Sections of no contents (SHT_NOBITS) cost no bytes in the file but their
// size in memory: a few of them announcing 512 MB each must be refused, not
// mapped (4096 sections of 1 GB each were once taken, terabytes of mapping).
TEST(ObjectLoader, RefusesSectionsLargerThanAKernelEverIs) {
    Jit jit;
    const Model model = read_model(testing::model_path("seed-scenario-2.toml"));
    const std::string object = compile(jit, model, Configuration::all_open(model)).object;
    Elf64_Ehdr eh;
    std::memcpy(&eh, object.data(), sizeof eh);
    std::string big = object;
    int changed = 0;
    for (std::size_t i = 1; i < eh.e_shnum; ++i) {
        Elf64_Shdr sh;
        std::memcpy(&sh, big.data() + eh.e_shoff + i * sizeof sh, sizeof sh);
        if (sh.sh_flags & SHF_ALLOC || sh.sh_type == SHT_SYMTAB || sh.sh_type == SHT_STRTAB ||
            sh.sh_type == SHT_RELA)
            continue;
        sh.sh_type = SHT_NOBITS;
        sh.sh_flags = SHF_ALLOC;
        sh.sh_size = std::size_t{512} << 20;
        sh.sh_addralign = 1;
        std::memcpy(&big[eh.e_shoff + i * sizeof sh], &sh, sizeof sh);
        ++changed;
    }
    ASSERT_GT(changed, 0) << "no section to enlarge";
    std::string why;
    EXPECT_EQ(LoadedObject::load(big, why), nullptr);
    EXPECT_EQ(why, "sections too large");
}

// Damaged objects (the cache's checksum normally keeps them out): random
// byte changes and cuts are refused or mapped, never a crash, and writes stay
// inside the loader's own pages (every offset is checked against the file).
TEST(ObjectLoader, RandomDamageNeverCrashes) {
    Jit jit;
    const Model model = read_model(testing::model_path("seed-scenario-2.toml"));
    const std::string object = compile(jit, model, Configuration::all_open(model)).object;
    std::mt19937 rng(20261123);
    int refused = 0, loaded = 0;
    for (int trial = 0; trial < 3000; ++trial) {
        std::string bytes = object;
        if (trial % 4 == 0) {
            bytes.resize(rng() % object.size());
        } else {
            for (int k = 0, n = 1 + static_cast<int>(rng() % 4); k < n; ++k)
                bytes[rng() % bytes.size()] = static_cast<char>(rng());
        }
        std::string why;
        (LoadedObject::load(bytes, why) ? loaded : refused) += 1;
    }
    EXPECT_GT(refused, 0);
    EXPECT_EQ(refused + loaded, 3000);
}

}  // namespace
}  // namespace hsnc
