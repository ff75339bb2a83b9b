#include "object_loader.h"

#include <dlfcn.h>
#include <elf.h>
#include <sys/mman.h>
#include <unistd.h>

#include <cstdint>
#include <cstring>

namespace hsnc {
namespace {

std::size_t round_up(std::size_t v, std::size_t a) { return (v + a - 1) / a * a; }

}  // namespace

LoadedObject::~LoadedObject() {
    if (base_) ::munmap(base_, size_);
}

std::unique_ptr<LoadedObject> LoadedObject::load(const std::string& elf, std::string& error) {
    const char* data = elf.data();
    const std::size_t size = elf.size();
    auto fail = [&error](const std::string& why) {
        error = why;
        return nullptr;
    };
    // ---- the ELF header: 64-bit little-endian x86-64 relocatable ----
    if (size < sizeof(Elf64_Ehdr)) return fail("shorter than an ELF header");
    Elf64_Ehdr eh;
    std::memcpy(&eh, data, sizeof eh);
    if (std::memcmp(eh.e_ident, ELFMAG, SELFMAG) != 0) return fail("not an ELF file");
    if (eh.e_ident[EI_CLASS] != ELFCLASS64 || eh.e_ident[EI_DATA] != ELFDATA2LSB || eh.e_machine != EM_X86_64 ||
        eh.e_type != ET_REL)
        return fail("not an x86-64 relocatable object");
    if (eh.e_shentsize != sizeof(Elf64_Shdr) || eh.e_shnum == 0 || eh.e_shnum > 4096 || eh.e_shoff > size ||
        (size - eh.e_shoff) / sizeof(Elf64_Shdr) < eh.e_shnum)
        return fail("section headers outside the file");
    std::vector<Elf64_Shdr> sh(eh.e_shnum);
    std::memcpy(sh.data(), data + eh.e_shoff, sh.size() * sizeof(Elf64_Shdr));
    for (const Elf64_Shdr& s : sh)
        if (s.sh_type != SHT_NOBITS && s.sh_type != SHT_NULL && (s.sh_offset > size || s.sh_size > size - s.sh_offset))
            return fail("a section outside the file");

    // ---- layout: allocated sections, code first, then data, page-aligned apart ----
    const std::size_t page = static_cast<std::size_t>(::sysconf(_SC_PAGESIZE));
    std::vector<std::size_t> offset(sh.size(), 0);
    std::vector<char> placed(sh.size(), 0);
    std::size_t at = 0, code_end = 0;
    for (int pass = 0; pass < 2; ++pass) {
        for (std::size_t i = 0; i < sh.size(); ++i) {
            const Elf64_Shdr& s = sh[i];
            if (!(s.sh_flags & SHF_ALLOC) || ((s.sh_flags & SHF_EXECINSTR) != 0) != (pass == 0)) continue;
            if (s.sh_type != SHT_PROGBITS && s.sh_type != SHT_NOBITS) return fail("an unexpected allocated section type");
            const std::size_t align = s.sh_addralign ? s.sh_addralign : 1;
            if (align > page || (align & (align - 1))) return fail("an unexpected section alignment");
            if (s.sh_size > kMaxMappedBytes || at > kMaxMappedBytes) return fail("sections too large");
            at = round_up(at, align);
            offset[i] = at;
            placed[i] = 1;
            at += s.sh_size;
        }
        if (pass == 0) code_end = at = round_up(at, page);
    }
    if (at > kMaxMappedBytes) return fail("sections too large");
    const std::size_t total = round_up(std::max<std::size_t>(at, 1), page);
    void* base = ::mmap(nullptr, total, PROT_READ | PROT_WRITE, MAP_PRIVATE | MAP_ANONYMOUS, -1, 0);
    if (base == MAP_FAILED) return fail("cannot map memory");
    std::unique_ptr<LoadedObject> obj(new LoadedObject());
    obj->base_ = base;
    obj->size_ = total;
    obj->code_size_ = code_end;
    char* mem = static_cast<char*>(base);
    for (std::size_t i = 0; i < sh.size(); ++i)
        if (placed[i] && sh[i].sh_type == SHT_PROGBITS) std::memcpy(mem + offset[i], data + sh[i].sh_offset, sh[i].sh_size);

    // ---- the symbol table ----
    std::size_t symtab = 0;
    for (std::size_t i = 0; i < sh.size(); ++i)
        if (sh[i].sh_type == SHT_SYMTAB) symtab = i;
    if (!symtab || sh[symtab].sh_entsize != sizeof(Elf64_Sym) || sh[symtab].sh_link >= sh.size() ||
        sh[sh[symtab].sh_link].sh_type != SHT_STRTAB)
        return fail("no usable symbol table");
    const std::size_t nsym = sh[symtab].sh_size / sizeof(Elf64_Sym);
    const Elf64_Shdr& strtab = sh[sh[symtab].sh_link];
    std::vector<Elf64_Sym> syms(nsym);
    if (nsym) std::memcpy(syms.data(), data + sh[symtab].sh_offset, nsym * sizeof(Elf64_Sym));  // data() may be null
    auto name_of = [&](const Elf64_Sym& s, std::string& name) {
        if (s.st_name >= strtab.sh_size) return false;
        const char* p = data + strtab.sh_offset + s.st_name;
        const std::size_t n = ::strnlen(p, strtab.sh_size - s.st_name);
        if (n == strtab.sh_size - s.st_name) return false;  // not terminated inside the table
        name.assign(p, n);
        return true;
    };
    std::vector<std::uint64_t> address(nsym, 0);
    std::vector<char> resolved(nsym, 0);
    for (std::size_t k = 1; k < nsym; ++k) {
        const Elf64_Sym& s = syms[k];
        const int type = ELF64_ST_TYPE(s.st_info);
        if (type == STT_FILE) continue;
        std::string name;
        if (s.st_shndx == SHN_UNDEF) {
            if (!name_of(s, name) || name.empty()) return fail("an undefined symbol without a name");
            void* p = ::dlsym(RTLD_DEFAULT, name.c_str());
            if (!p) return fail("undefined symbol '" + name + "' not found in this process");
            address[k] = reinterpret_cast<std::uint64_t>(p);
        } else if (s.st_shndx == SHN_ABS) {
            address[k] = s.st_value;
        } else if (s.st_shndx < sh.size() && placed[s.st_shndx]) {
            if (s.st_value > sh[s.st_shndx].sh_size || s.st_size > sh[s.st_shndx].sh_size - s.st_value)
                return fail("a symbol outside its section");
            address[k] = reinterpret_cast<std::uint64_t>(mem + offset[s.st_shndx] + s.st_value);
            if (ELF64_ST_BIND(s.st_info) == STB_GLOBAL && type != STT_SECTION && name_of(s, name))
                obj->globals_.push_back({name, mem + offset[s.st_shndx] + s.st_value, s.st_size});
        } else {
            continue;  // a symbol of a section that is not loaded: relocations must not use it
        }
        resolved[k] = 1;
    }

    // ---- relocations: R_X86_64_64 only, S + A, inside loaded sections ----
    for (const Elf64_Shdr& r : sh) {
        if (r.sh_type == SHT_REL) return fail("REL relocations (only RELA)");
        if (r.sh_type != SHT_RELA) continue;
        if (r.sh_info >= sh.size() || !placed[r.sh_info]) continue;  // e.g. relocations of debug sections
        if (r.sh_entsize != sizeof(Elf64_Rela) || r.sh_link != symtab) return fail("a malformed relocation section");
        const Elf64_Shdr& target = sh[r.sh_info];
        if (target.sh_type != SHT_PROGBITS) return fail("relocations in a section without contents");
        const std::size_t n = r.sh_size / sizeof(Elf64_Rela);
        for (std::size_t k = 0; k < n; ++k) {
            Elf64_Rela rel;
            std::memcpy(&rel, data + r.sh_offset + k * sizeof rel, sizeof rel);
            const auto type = ELF64_R_TYPE(rel.r_info);
            const auto sym = ELF64_R_SYM(rel.r_info);
            if (type == R_X86_64_NONE) continue;
            if (type != R_X86_64_64) return fail("relocation type " + std::to_string(type) + " (only R_X86_64_64)");
            if (sym == 0 || sym >= nsym || !resolved[sym]) return fail("a relocation against an unusable symbol");
            if (rel.r_offset > target.sh_size || target.sh_size - rel.r_offset < 8)
                return fail("a relocation outside its section");
            const std::uint64_t value = address[sym] + static_cast<std::uint64_t>(rel.r_addend);
            std::memcpy(mem + offset[r.sh_info] + rel.r_offset, &value, 8);
        }
    }
    for (std::size_t i = 0; i < sh.size(); ++i)
        if (placed[i] && (sh[i].sh_flags & SHF_WRITE)) return fail("writable data (a kernel has none)");

    // ---- protect: code read+execute, the rest read-only ----
    if ((code_end && ::mprotect(mem, code_end, PROT_READ | PROT_EXEC) != 0) ||
        (total > code_end && ::mprotect(mem + code_end, total - code_end, PROT_READ) != 0))
        return fail("cannot protect the mapped pages");
    __builtin___clear_cache(mem, mem + code_end);
    return obj;
}

std::vector<std::string> LoadedObject::symbol_names() const {
    std::vector<std::string> names;
    for (const Global& g : globals_) names.push_back(g.name);
    return names;
}

bool LoadedObject::contains(const void* p, std::size_t size) const {
    const auto a = reinterpret_cast<std::uintptr_t>(p), b = reinterpret_cast<std::uintptr_t>(base_);
    return a >= b && a - b <= size_ && size <= size_ - (a - b);
}

bool LoadedObject::contains_string(const char* p) const {
    if (!contains(p, 1)) return false;
    const std::size_t room = size_ - static_cast<std::size_t>(p - static_cast<const char*>(base_));
    return ::strnlen(p, room) < room;
}

bool LoadedObject::contains_code(const void* p) const {
    const auto a = reinterpret_cast<std::uintptr_t>(p), b = reinterpret_cast<std::uintptr_t>(base_);
    return a >= b && a - b < code_size_;
}

void* LoadedObject::symbol(const std::string& name, std::size_t min_size) const {
    for (const Global& g : globals_)
        if (g.name == name) return g.size >= min_size ? g.address : nullptr;
    return nullptr;
}

}  // namespace hsnc
