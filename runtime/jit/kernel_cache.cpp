#include "kernel_cache.h"

#if defined(__x86_64__)
#include <cpuid.h>
#endif
#include <fcntl.h>
#include <link.h>
#include <sys/stat.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <initializer_list>
#include <random>
#include "error.h"
#include "file_read.h"
#include "jit_frontend.h"     // jit_compile_flags
#include "kernel_abi.h"
#include "kernel_abi_text.h"  // generated at build time: kKernelAbiHeaderText
#include "object_loader.h"

namespace hsnc {
namespace {

constexpr char kMagic[8] = {'H', 'S', 'N', 'C', 'K', 'O', 'B', 'J'};
constexpr std::size_t kHeaderSize = 32;

struct Header {
    std::uint32_t version = 0, key_size = 0;
    std::uint64_t payload_size = 0, checksum = 0;
};

std::string errno_text() { return std::strerror(errno); }

// Parses the fixed header of `data` (at least kHeaderSize bytes); "" or why not.
std::string parse_header(const char* data, std::size_t size, Header& h) {
    if (size < kHeaderSize || std::memcmp(data, kMagic, sizeof kMagic) != 0) return "not an hsnc cache entry";
    std::memcpy(&h.version, data + 8, 4);
    std::memcpy(&h.key_size, data + 12, 4);
    std::memcpy(&h.payload_size, data + 16, 8);
    std::memcpy(&h.checksum, data + 24, 8);
    if (h.version != kCacheFormatVersion)
        return "cache format " + std::to_string(h.version) + ", expected " + std::to_string(kCacheFormatVersion);
    if (h.key_size > 1024) return "corrupt header (key of " + std::to_string(h.key_size) + " bytes)";
    return "";
}

bool write_all(int fd, const char* data, std::size_t size) {
    while (size > 0) {
        const ssize_t n = ::write(fd, data, size);
        if (n < 0 && errno == EINTR) continue;
        if (n <= 0) return false;
        data += n;
        size -= static_cast<std::size_t>(n);
    }
    return true;
}

bool has_extension(const std::filesystem::path& p) { return p.extension() == kCacheFileExtension; }
bool is_index(const std::filesystem::path& p) { return p.extension() == kCacheIndexExtension; }

std::string octal_mode(mode_t mode) {
    char text[8];
    std::snprintf(text, sizeof text, "%04o", static_cast<unsigned>(mode & 07777));
    return text;
}

// Why a file or directory with status `st` must not be trusted: "" when this
// user owns it and neither group nor others can write it.
std::string ownership_problem(const struct stat& st) {
    if (st.st_uid != ::geteuid())
        return "owned by uid " + std::to_string(st.st_uid) + ", not by this user (uid " +
               std::to_string(::geteuid()) + ")";
    if (st.st_mode & (S_IWGRP | S_IWOTH)) return "group- or world-writable (mode " + octal_mode(st.st_mode) + ")";
    return "";
}

// Checks `data` as a whole entry of `key` (header, size, key, checksum); ""
// or why not. On success `payload` holds the payload.
std::string check_entry(const std::string& data, const std::string& key, std::string& payload) {
    Header h;
    std::string problem = parse_header(data.data(), data.size(), h);
    if (!problem.empty()) {
        if (data.size() < kHeaderSize) problem = "truncated (" + std::to_string(data.size()) + " bytes)";
        return problem;
    }
    const std::uint64_t expected = kHeaderSize + h.key_size + h.payload_size;
    if (data.size() != expected)
        return (data.size() < expected ? "truncated (" : "too long (") + std::to_string(data.size()) +
               " bytes, its header says " + std::to_string(expected) + ")";
    const std::string stored_key = data.substr(kHeaderSize, h.key_size);
    if (stored_key != key) return "holds the kernel of key " + stored_key + ", not " + key;
    payload = data.substr(kHeaderSize + h.key_size);
    if (fnv1a64(payload.data(), payload.size()) != h.checksum) {
        payload.clear();
        return "corrupt (checksum mismatch)";
    }
    return "";
}

// Why the payload of a whole .hsncobj entry of `key` is not a kernel object
// this process can use: "" when the loader (runtime/jit/object_loader.h) maps
// it, it defines a kernel (an hsnc_kernel_* object of this ABI version) and it
// names `key` (jit_key_definition: the object compiled for this key, not
// another kernel's). Only on x86-64, where the loader takes what the JIT makes.
std::string object_problem(const std::string& payload, const std::string& key) {
#if defined(__x86_64__)
    std::string why;
    const std::unique_ptr<LoadedObject> object = LoadedObject::load(payload, why);
    if (!object) return "not a loadable object: " + why;
    bool kernel = false, own = false;
    std::string other;  // the key another kernel's object names
    const std::string prefix = kCacheKeySymbolPrefix;
    for (const std::string& name : object->symbol_names()) {
        if (name.compare(0, prefix.size(), prefix) == 0) {
            const auto* text = static_cast<const char*>(object->symbol(name, key.size() + 1));
            if (name == prefix + key)
                own = text && object->contains_string(text) && key == text;
            else
                other = name.substr(prefix.size());
        } else if (name.compare(0, 12, "hsnc_kernel_") == 0) {
            const auto* k = static_cast<const hsnc_kernel*>(object->symbol(name, sizeof(hsnc_kernel)));
            kernel = kernel || (k && k->abi_version == HSNC_KERNEL_ABI_VERSION);
        }
    }
    if (!kernel) return "defines no kernel of ABI version " + std::to_string(HSNC_KERNEL_ABI_VERSION);
    if (!other.empty()) return "holds the object of key " + other + ", not " + key;
    if (!own) return "its object does not name its key (no " + prefix + key + ")";
    return "";
#else
    (void)payload, (void)key;
    return "";
#endif
}

// Why the payload of an index entry is not "<32 hex digits> <symbol>".
std::string index_problem(const std::string& payload) {
    const std::size_t space = payload.find(' ');
    if (space != 32 || payload.find_first_not_of("0123456789abcdef") != 32 || space + 1 >= payload.size())
        return "not an index entry (\"<key> <symbol>\")";
    return "";
}

}  // namespace

std::uint64_t fnv1a64(const void* data, std::size_t size, std::uint64_t h) {
    const auto* p = static_cast<const unsigned char*>(data);
    for (std::size_t i = 0; i < size; ++i) h = (h ^ p[i]) * 0x100000001b3ULL;
    return h;
}

std::string host_cpu_identity() {
#if !defined(__x86_64__)
    return "not-x86-64";  // the JIT's objects are then only ever loaded by LLVM
#else
    unsigned a = 0, b = 0, c = 0, d = 0;
    char text[256];
    std::size_t n = 0;
    auto word = [&](unsigned w) { n += std::snprintf(text + n, sizeof text - n, " %08x", w); };
    if (!__get_cpuid(0, &a, &b, &c, &d)) return "no-cpuid";
    const unsigned max_leaf = a;
    char vendor[13] = {};
    std::memcpy(vendor, &b, 4);
    std::memcpy(vendor + 4, &d, 4);
    std::memcpy(vendor + 8, &c, 4);
    n += std::snprintf(text + n, sizeof text - n, "%s", vendor);
    __get_cpuid(1, &a, &b, &c, &d);
    word(a);  // family, model, stepping (not ebx: it holds this core's APIC id)
    word(c);
    word(d);
    const bool osxsave = (c >> 27) & 1;
    if (max_leaf >= 7 && __get_cpuid_count(7, 0, &a, &b, &c, &d)) {
        word(b);
        word(c);
        word(d);
    }
    if (__get_cpuid(0x80000001, &a, &b, &c, &d)) {
        word(c);
        word(d);
    }
    if (osxsave) {  // the register state the OS saves: AVX, AVX-512 usable or not
        unsigned lo = 0, hi = 0;
        __asm__ volatile("xgetbv" : "=a"(lo), "=d"(hi) : "c"(0));
        word(lo);
    }
    return std::string(text, n);
#endif
}

namespace {

// FNV-1a 128 (Fowler, Noll, Vo) of the parts, each followed by a separator
// byte ("ab"+"c" differs from "a"+"bc"), in hex.
__extension__ typedef unsigned __int128 u128;  // GCC and Clang on 64-bit hosts

// FNV-1a-128 (offset basis, prime 2^88 + 2^8 + 0x3b) over parts, each followed by 0xff.
constexpr u128 kFnvBasis = (static_cast<u128>(0x6c62272e07bb0142ULL) << 64) | 0x62b821756295c58dULL;
u128 fnv1a128_add(u128 h, const std::string& t) {
    const u128 prime = (static_cast<u128>(1) << 88) | 0x13b;
    for (unsigned char c : t) h = (h ^ c) * prime;
    return (h ^ 0xff) * prime;
}

std::string hex128(u128 h) {
    char hex[33];
    std::snprintf(hex, sizeof hex, "%016llx%016llx", static_cast<unsigned long long>(h >> 64),
                  static_cast<unsigned long long>(h));
    return hex;
}

std::string fnv1a128_hex(std::initializer_list<std::string> parts) {
    u128 h = kFnvBasis;
    for (const std::string& t : parts) h = fnv1a128_add(h, t);
    return hex128(h);
}

std::string compiler_identity() {
    std::string id = "clang " HSNC_CLANG_VERSION;
    for (const char* flag : jit_compile_flags()) id += std::string(" ") + flag;
    return id;
}

}  // namespace

std::string jit_cache_key(const std::string& source) {
    static const std::string cpu = host_cpu_identity();
    // 3: the object names its key (jit_key_definition).
    return fnv1a128_hex({"hsnc-jit-object 3", compiler_identity(), cpu, kKernelAbiHeaderText, source});
}

std::string jit_key_definition(const std::string& key) {
    return "\n// The key of this kernel's cache entry (runtime/jit/kernel_cache.h).\nextern \"C\" const char " +
           std::string(kCacheKeySymbolPrefix) + key + "[] = \"" + key + "\";\n";
}

namespace {

// An address inside the code of this file: the object that holds it (the
// executable, or libhsnc.so in a program that links the library) is the one
// whose build ID keys the index. Internal linkage, so no other object's
// definition can stand in for it.
void build_id_anchor() {}

}  // namespace

std::string module_build_id() {
    struct Search {
        ElfW(Addr) address;
        std::string id;
    } search{reinterpret_cast<ElfW(Addr)>(&build_id_anchor), ""};
    ::dl_iterate_phdr(
        [](dl_phdr_info* info, std::size_t, void* out) {
            auto* s = static_cast<Search*>(out);
            bool holds = false;  // does one of this object's loaded segments hold the anchor?
            for (int i = 0; i < info->dlpi_phnum && !holds; ++i) {
                const ElfW(Phdr)& ph = info->dlpi_phdr[i];
                const ElfW(Addr) start = info->dlpi_addr + ph.p_vaddr;
                holds = ph.p_type == PT_LOAD && s->address >= start && s->address - start < ph.p_memsz;
            }
            if (!holds) return 0;  // the next object
            for (int i = 0; i < info->dlpi_phnum; ++i) {
                const ElfW(Phdr)& ph = info->dlpi_phdr[i];
                if (ph.p_type != PT_NOTE) continue;
                const char* p = reinterpret_cast<const char*>(info->dlpi_addr + ph.p_vaddr);
                const char* end = p + ph.p_memsz;
                while (end - p >= static_cast<std::ptrdiff_t>(sizeof(ElfW(Nhdr)))) {
                    ElfW(Nhdr) nh;
                    std::memcpy(&nh, p, sizeof nh);
                    const char* name = p + sizeof nh;
                    const char* desc = name + ((nh.n_namesz + 3) & ~3u);
                    const char* next = desc + ((nh.n_descsz + 3) & ~3u);
                    if (next > end) break;
                    if (nh.n_type == NT_GNU_BUILD_ID && nh.n_namesz == 4 && std::memcmp(name, "GNU", 4) == 0) {
                        for (unsigned k = 0; k < nh.n_descsz; ++k) {
                            char byte[3];
                            std::snprintf(byte, sizeof byte, "%02x", static_cast<unsigned char>(desc[k]));
                            s->id += byte;
                        }
                        return 1;
                    }
                    p = next;
                }
            }
            return 1;  // the object holding this code has no build ID
        },
        &search);
    return search.id;
}

std::string jit_index_key(const std::string& model_text, const std::string& config_key) {
    return JitIndexKeys(model_text)(config_key);
}

JitIndexKeys::JitIndexKeys(const std::string& model_text) {
    static const std::string build_id = module_build_id();
    // The parts every model shares, hashed once per process.
    static const u128 shared = [] {
        u128 h = kFnvBasis;
        for (const std::string& t : {std::string("hsnc-jit-index 1"), build_id, compiler_identity(),
                                     host_cpu_identity(), std::string(kKernelAbiHeaderText)})
            h = fnv1a128_add(h, t);
        return h;
    }();
    none_ = build_id.empty();
    const u128 h = fnv1a128_add(shared, model_text);
    hi_ = static_cast<std::uint64_t>(h >> 64);
    lo_ = static_cast<std::uint64_t>(h);
}

std::string JitIndexKeys::operator()(const std::string& config_key) const {
    if (none_) return "";
    return hex128(fnv1a128_add((static_cast<u128>(hi_) << 64) | lo_, config_key));
}

std::string default_cache_dir() {
    const char* xdg = std::getenv("XDG_CACHE_HOME");
    // The XDG base directory spec: relative paths are invalid and ignored.
    if (xdg && xdg[0] == '/') return std::string(xdg) + "/hsnc";
    const char* home = std::getenv("HOME");
    if (home && home[0] != '\0') return std::string(home) + "/.cache/hsnc";
    return "";
}

std::string KernelCache::path_of(const std::string& key, const char* ext) const { return dir_ + "/" + key + ext; }

KernelCache::Entry KernelCache::load(const std::string& key, const char* ext) const {
    Entry e;
    const std::string path = path_of(key, ext);
    // Never a FIFO, a device or an endless file; never one somebody else can write.
    struct stat st;
    const FileRead file = read_regular_file(path, kMaxCacheEntryBytes, &st);
    if (file.status == FileRead::Status::missing) return e;  // no file, or no directory
    e.status = Status::bad;
    if (file.status != FileRead::Status::ok) {
        e.problem = file.problem == "not a regular file" || file.problem.compare(0, 12, "larger than ") == 0
                        ? file.problem
                        : "cannot read: " + file.problem;
        return e;
    }
    e.problem = ownership_problem(st);
    if (e.problem.empty()) e.problem = check_entry(file.bytes, key, e.payload);
    if (!e.problem.empty()) return e;
    e.status = Status::hit;
    ::utimensat(AT_FDCWD, path.c_str(), nullptr, 0);  // used now: the last to be evicted
    return e;
}

std::string KernelCache::store(const std::string& key, const std::string& payload, const char* ext) const {
    // Its parents as any directory (~/.cache), the cache itself 0700.
    std::error_code ec;
    const std::filesystem::path parent = std::filesystem::path(dir_).parent_path();
    if (!parent.empty()) std::filesystem::create_directories(parent, ec);
    if (ec) return "cannot create directory " + dir_ + ": " + ec.message();
    if (::mkdir(dir_.c_str(), 0700) != 0 && errno != EEXIST)
        return "cannot create directory " + dir_ + ": " + errno_text();

    char header[kHeaderSize];
    const std::uint32_t version = kCacheFormatVersion, key_size = static_cast<std::uint32_t>(key.size());
    const std::uint64_t payload_size = payload.size(), checksum = fnv1a64(payload.data(), payload.size());
    std::memcpy(header, kMagic, 8);
    std::memcpy(header + 8, &version, 4);
    std::memcpy(header + 12, &key_size, 4);
    std::memcpy(header + 16, &payload_size, 8);
    std::memcpy(header + 24, &checksum, 8);

    // A name no other writer uses: pid plus 64 random bits; a dot first so
    // that it never looks like an entry while it is being written.
    std::random_device rd;
    char suffix[40];
    std::snprintf(suffix, sizeof suffix, ".%ld.%08x%08x.tmp", static_cast<long>(::getpid()), rd(), rd());
    const std::string tmp = dir_ + "/." + key + ext + suffix;
    const int fd = ::open(tmp.c_str(), O_WRONLY | O_CREAT | O_EXCL | O_CLOEXEC, 0600);
    if (fd < 0) return "cannot write in " + dir_ + ": " + errno_text();
    const bool ok = write_all(fd, header, sizeof header) && write_all(fd, key.data(), key.size()) &&
                    write_all(fd, payload.data(), payload.size());
    std::string why = ok ? "" : "cannot write " + tmp + ": " + errno_text();
    if (::close(fd) != 0 && ok) why = "cannot write " + tmp + ": " + errno_text();  // e.g. a full disk on NFS
    if (!why.empty()) {
        ::unlink(tmp.c_str());
        return why;
    }
    if (::rename(tmp.c_str(), path_of(key, ext).c_str()) != 0) {
        const std::string why = "cannot rename " + tmp + " into place: " + errno_text();
        ::unlink(tmp.c_str());
        return why;
    }
    if (max_bytes_ > 0) evict(dir_, max_bytes_, path_of(key, ext));
    return "";
}

std::size_t KernelCache::evict(const std::string& dir, std::uint64_t max_bytes, const std::string& keep) {
    struct File {
        struct timespec used;
        std::uint64_t bytes;
        std::string path;
    };
    std::vector<File> files;
    std::uint64_t total = 0;
    std::error_code ec;
    for (std::filesystem::directory_iterator it(dir, ec), end; !ec && it != end; it.increment(ec)) {
        const std::filesystem::path& p = it->path();
        if ((!has_extension(p) && !is_index(p)) || p.filename().string()[0] == '.') continue;
        struct stat st;
        if (::lstat(p.c_str(), &st) != 0 || !S_ISREG(st.st_mode)) continue;
        total += static_cast<std::uint64_t>(st.st_size);
        if (p.string() != keep) files.push_back({st.st_mtim, static_cast<std::uint64_t>(st.st_size), p.string()});
    }
    if (total <= max_bytes) return 0;
    std::sort(files.begin(), files.end(), [](const File& a, const File& b) {
        return a.used.tv_sec != b.used.tv_sec ? a.used.tv_sec < b.used.tv_sec : a.used.tv_nsec < b.used.tv_nsec;
    });
    std::size_t removed = 0;
    for (const File& f : files) {
        if (total <= max_bytes) break;
        // Another process may have removed it first: it is gone either way.
        if (::unlink(f.path.c_str()) == 0 || errno == ENOENT) {
            total -= f.bytes;
            ++removed;
        }
    }
    return removed;
}

std::string KernelCache::trust_problem(const std::string& dir) {
    struct stat st;
    if (::stat(dir.c_str(), &st) != 0) return "";  // created 0700 on the first store
    if (!S_ISDIR(st.st_mode)) return "";           // store() says it cannot create it
    const std::string problem = ownership_problem(st);
    return problem.empty() ? "" : dir + " is " + problem;
}

std::uint64_t parse_byte_size(const std::string& text, const std::string& what) {
    std::size_t digits = 0;
    while (digits < text.size() && text[digits] >= '0' && text[digits] <= '9') ++digits;
    const std::string suffix = text.substr(digits);
    int shift = -1;
    if (suffix.empty() || suffix == "B") shift = 0;
    if (suffix == "k" || suffix == "K" || suffix == "KB" || suffix == "KiB") shift = 10;
    if (suffix == "M" || suffix == "MB" || suffix == "MiB") shift = 20;
    if (suffix == "G" || suffix == "GB" || suffix == "GiB") shift = 30;
    if (digits == 0 || digits > 12 || shift < 0)
        throw InputError(what + ": '" + text + "' is not a size (a number of bytes, or with K, M or G: 256M)");
    // At most 12 digits, so the number fits; shifted, it may not (2^64 wraps
    // to 0, which means "no limit").
    const std::uint64_t number = std::stoull(text.substr(0, digits));
    const std::uint64_t largest = UINT64_MAX >> shift;
    if (number > largest)
        throw InputError(what + ": '" + text + "' is too large (at most " + std::to_string(largest) + suffix + ")");
    return number << shift;
}

KernelCache::Stats KernelCache::stats(const std::string& dir) {
    Stats s;
    std::error_code ec;
    std::vector<std::filesystem::path> paths;
    for (std::filesystem::directory_iterator it(dir, ec), end; !ec && it != end; it.increment(ec))
        paths.push_back(it->path());
    std::sort(paths.begin(), paths.end());
    for (const std::filesystem::path& p : paths) {
        const bool object = has_extension(p);
        if ((!object && !is_index(p)) || p.filename().string()[0] == '.') continue;
        // What load() would make of it (without marking it used), and for
        // kernels whether the object maps and defines a kernel.
        struct stat st;
        const FileRead file = read_regular_file(p.string(), kMaxCacheEntryBytes, &st);
        if (file.status == FileRead::Status::missing) continue;  // removed meanwhile
        std::string problem = file.problem, payload;
        struct stat link;
        if (::lstat(p.c_str(), &link) == 0 && S_ISREG(link.st_mode)) s.bytes += static_cast<std::uint64_t>(link.st_size);
        if (problem.empty()) problem = ownership_problem(st);
        if (problem.empty()) problem = check_entry(file.bytes, p.stem().string(), payload);
        if (problem.empty()) problem = object ? object_problem(payload, p.stem().string()) : index_problem(payload);
        if (!problem.empty()) {
            ++(object ? s.damaged : s.index_damaged);
            s.problems.push_back(p.string() + ": " + problem);
            continue;
        }
        if (!object) {
            ++s.index_entries;
            continue;
        }
        const std::int64_t t = st.st_mtime;
        if (s.entries == 0 || t < s.oldest) s.oldest = t;
        if (s.entries == 0 || t > s.newest) s.newest = t;
        ++s.entries;
    }
    return s;
}

std::size_t KernelCache::clear(const std::string& dir, std::string& problem) {
    std::size_t removed = 0;
    std::error_code ec;
    for (std::filesystem::directory_iterator it(dir, ec), end; !ec && it != end; it.increment(ec)) {
        const std::filesystem::path& p = it->path();
        const std::string name = p.filename().string();
        // Entries (<key>.hsncobj, <key>.hsncidx) and temporary files a killed
        // writer left (.<key>.hsncobj.<pid>.<random>.tmp); nothing else.
        const bool temporary = name[0] == '.' && p.extension() == ".tmp" &&
                               (name.find(kCacheFileExtension) != std::string::npos ||
                                name.find(kCacheIndexExtension) != std::string::npos);
        const bool ours = has_extension(p) || is_index(p) || temporary;
        if (!ours || it->is_directory()) continue;
        if (::unlink(p.c_str()) == 0)
            ++removed;
        else if (problem.empty())
            problem = "cannot remove " + p.string() + ": " + errno_text();
    }
    if (ec && ec != std::errc::no_such_file_or_directory && problem.empty())
        problem = "cannot list " + dir + ": " + ec.message();
    return removed;
}

}  // namespace hsnc
