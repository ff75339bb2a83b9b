#include "kernel_cache.h"

#if defined(__x86_64__)
#include <cpuid.h>
#endif
#include <fcntl.h>
#include <link.h>
#include <sys/stat.h>
#include <unistd.h>

#include <cerrno>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <initializer_list>
#include <random>

#include "jit_frontend.h"     // jit_compile_flags
#include "kernel_abi_text.h"  // generated at build time: kKernelAbiHeaderText

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

bool read_all(int fd, std::string& out) {
    char buf[65536];
    for (;;) {
        const ssize_t n = ::read(fd, buf, sizeof buf);
        if (n < 0 && errno == EINTR) continue;
        if (n < 0) return false;
        if (n == 0) return true;
        out.append(buf, static_cast<std::size_t>(n));
    }
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
std::string fnv1a128_hex(std::initializer_list<std::string> parts) {
    __extension__ typedef unsigned __int128 u128;  // GCC and Clang on 64-bit hosts
    // Offset basis and prime 2^88 + 2^8 + 0x3b.
    u128 h = (static_cast<u128>(0x6c62272e07bb0142ULL) << 64) | 0x62b821756295c58dULL;
    const u128 prime = (static_cast<u128>(1) << 88) | 0x13b;
    for (const std::string& t : parts) {
        for (unsigned char c : t) h = (h ^ c) * prime;
        h = (h ^ 0xff) * prime;
    }
    char hex[33];
    std::snprintf(hex, sizeof hex, "%016llx%016llx", static_cast<unsigned long long>(h >> 64),
                  static_cast<unsigned long long>(h));
    return hex;
}

std::string compiler_identity() {
    std::string id = "clang " HSNC_CLANG_VERSION;
    for (const char* flag : jit_compile_flags()) id += std::string(" ") + flag;
    return id;
}

}  // namespace

std::string jit_cache_key(const std::string& source) {
    static const std::string cpu = host_cpu_identity();
    return fnv1a128_hex({"hsnc-jit-object 2", compiler_identity(), cpu, kKernelAbiHeaderText, source});
}

std::string executable_build_id() {
    std::string id;
    // The first object dl_iterate_phdr reports is the executable itself.
    ::dl_iterate_phdr(
        [](dl_phdr_info* info, std::size_t, void* out) {
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
                        auto* s = static_cast<std::string*>(out);
                        for (unsigned k = 0; k < nh.n_descsz; ++k) {
                            char byte[3];
                            std::snprintf(byte, sizeof byte, "%02x", static_cast<unsigned char>(desc[k]));
                            *s += byte;
                        }
                        return 1;
                    }
                    p = next;
                }
            }
            return 1;  // only the executable
        },
        &id);
    return id;
}

std::string jit_index_key(const std::string& model_text, const std::string& config_key) {
    static const std::string build_id = executable_build_id(), cpu = host_cpu_identity();
    if (build_id.empty()) return "";
    return fnv1a128_hex({"hsnc-jit-index 1", build_id, compiler_identity(), cpu,
                         kKernelAbiHeaderText, model_text, config_key});
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
    const int fd = ::open(path.c_str(), O_RDONLY | O_CLOEXEC);
    if (fd < 0) {
        if (errno != ENOENT && errno != ENOTDIR) {  // no file, or no directory: a miss
            e.status = Status::bad;
            e.problem = "cannot read: " + errno_text();
        }
        return e;
    }
    std::string data;
    const bool ok = read_all(fd, data);
    ::close(fd);
    e.status = Status::bad;
    if (!ok) {
        e.problem = "cannot read: " + errno_text();
        return e;
    }
    Header h;
    e.problem = parse_header(data.data(), data.size(), h);
    if (!e.problem.empty()) {
        if (data.size() < kHeaderSize) e.problem = "truncated (" + std::to_string(data.size()) + " bytes)";
        return e;
    }
    const std::uint64_t expected = kHeaderSize + h.key_size + h.payload_size;
    if (data.size() != expected) {
        e.problem = (data.size() < expected ? "truncated (" : "too long (") + std::to_string(data.size()) +
                    " bytes, its header says " + std::to_string(expected) + ")";
        return e;
    }
    const std::string stored_key = data.substr(kHeaderSize, h.key_size);
    if (stored_key != key) {
        e.problem = "holds the kernel of key " + stored_key + ", not " + key;
        return e;
    }
    e.payload = data.substr(kHeaderSize + h.key_size);
    if (fnv1a64(e.payload.data(), e.payload.size()) != h.checksum) {
        e.payload.clear();
        e.problem = "corrupt (checksum mismatch)";
        return e;
    }
    e.status = Status::hit;
    return e;
}

std::string KernelCache::store(const std::string& key, const std::string& payload, const char* ext) const {
    std::error_code ec;
    std::filesystem::create_directories(dir_, ec);
    if (ec) return "cannot create directory " + dir_ + ": " + ec.message();

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
    const int fd = ::open(tmp.c_str(), O_WRONLY | O_CREAT | O_EXCL | O_CLOEXEC, 0644);
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
    return "";
}

KernelCache::Stats KernelCache::stats(const std::string& dir) {
    Stats s;
    std::error_code ec;
    for (std::filesystem::directory_iterator it(dir, ec), end; !ec && it != end; it.increment(ec)) {
        const std::filesystem::path& p = it->path();
        if (!has_extension(p) || p.filename().string()[0] == '.') continue;
        struct stat st;
        if (::stat(p.c_str(), &st) != 0 || !S_ISREG(st.st_mode)) continue;
        s.bytes += static_cast<std::uint64_t>(st.st_size);
        // A whole entry: our header, and the size it announces.
        char data[kHeaderSize];
        Header h;
        bool whole = false;
        if (std::FILE* f = std::fopen(p.c_str(), "rb")) {
            whole = std::fread(data, 1, sizeof data, f) == sizeof data && parse_header(data, sizeof data, h).empty() &&
                    kHeaderSize + h.key_size + h.payload_size == static_cast<std::uint64_t>(st.st_size);
            std::fclose(f);
        }
        if (!whole) {
            ++s.damaged;
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
