// hsnc -- KernelCache: compiled kernels (object code) kept on disk between
// runs, so that a configuration's kernel is compiled once per machine, not
// once per run (--kernels jit; runtime/jit_solver_provider.h).
//
// Plain file operations, no LLVM: `hsnc cache --stats|--clear` uses it without
// loading the JIT. One file per kernel, DIR/<key>.hsncobj, where key is the
// hex digest the JIT computes from the kernel source, the compiler's version,
// its flags and the target (Jit::cache_key). Each file repeats its key inside a
// fixed header:
//
//   offset  size  field
//        0     8  magic "HSNCKOBJ"
//        8     4  format version (kCacheFormatVersion), host byte order
//       12     4  key length K
//       16     8  payload length P
//       24     8  FNV-1a 64 checksum of the payload
//       32     K  key
//     32+K     P  payload (the object file)
//
// so a truncated, corrupt or foreign file (another key, another format, not
// ours at all) is told apart from a good one, and never loaded. Writes go to a
// temporary name in the same directory (pid and a random suffix) and are
// renamed into place (rename(2) is atomic within a file system), so two
// processes filling one cache at once each leave a whole file: a reader sees
// either no entry or a complete one. No fsync (it would cost milliseconds per
// kernel): a file that a crash of the machine leaves cut short fails its
// header check and is rebuilt.
#pragma once

#include <cstdint>
#include <string>

namespace hsnc {

inline constexpr std::uint32_t kCacheFormatVersion = 1;
inline constexpr const char* kCacheFileExtension = ".hsncobj";
/// Index entries: same format, the payload is the key of a .hsncobj entry.
inline constexpr const char* kCacheIndexExtension = ".hsncidx";

/// The cache directory when none is given: $XDG_CACHE_HOME/hsnc when that is
/// set and absolute, else $HOME/.cache/hsnc; "" when neither can be named.
std::string default_cache_dir();

/// The key of the JIT's object for `source`: FNV-1a-128 (hex) of the source,
/// the embedded kernel_abi.h, Clang's version, the compile flags
/// (runtime/jit_frontend.h) and this host's CPU as CPUID describes it (vendor,
/// family/model/stepping, feature words, the OS-enabled register state), which
/// is everything LLVM's host detection bases the target on. Equal keys mean
/// the JIT would produce the same object; computed without LLVM, so that a
/// run whose kernels are all cached need not load it (runtime/object_loader.h).
std::string jit_cache_key(const std::string& source);

/// The key under which the command line finds a kernel without deriving it:
/// FNV-1a-128 of this executable's GNU build ID (it fixes the generator and
/// emitter code), Clang's version, the flags, the CPU, kernel_abi.h, the
/// model's canonical text (model_hash.h: every number a kernel depends on) and
/// the configuration key. "" when the executable has no build ID. Its entry
/// (kCacheIndexExtension) holds the jit_cache_key of the kernel's source.
std::string jit_index_key(const std::string& model_text, const std::string& config_key);

/// This executable's GNU build ID in hex, "" when it has none.
std::string executable_build_id();

/// The host part of jit_cache_key, e.g. "GenuineIntel 000906ea 7ffafbff ...".
std::string host_cpu_identity();

/// FNV-1a, 64 bits (the payload checksum).
std::uint64_t fnv1a64(const void* data, std::size_t size, std::uint64_t h = 0xcbf29ce484222325ULL);

class KernelCache {
public:
    /// A cache in `dir` (created on the first store). Touches nothing yet.
    explicit KernelCache(std::string dir) : dir_(std::move(dir)) {}

    const std::string& dir() const { return dir_; }
    std::string path_of(const std::string& key, const char* ext = kCacheFileExtension) const;

    enum class Status {
        hit,   ///< a whole entry with this key: `payload` holds it
        miss,  ///< no entry
        bad,   ///< a file that is not a whole entry with this key: `problem` says why
    };
    struct Entry {
        Status status = Status::miss;
        std::string payload;
        std::string problem;
    };

    /// The entry stored under `key`. Never throws on file contents.
    Entry load(const std::string& key, const char* ext = kCacheFileExtension) const;

    /// Store `payload` under `key` (temporary file, then rename). Returns ""
    /// on success, else what went wrong ("cannot create directory ...: ...").
    std::string store(const std::string& key, const std::string& payload, const char* ext = kCacheFileExtension) const;

    struct Stats {
        std::size_t entries = 0;      ///< whole hsnc entries (header checks out)
        std::size_t damaged = 0;      ///< *.hsncobj files that are not (truncated, corrupt)
        std::uint64_t bytes = 0;      ///< file sizes of both
        std::int64_t oldest = 0, newest = 0;  ///< modification times (s since epoch) of entries
    };
    /// What `dir` holds (all zero when it does not exist). Throws nothing.
    static Stats stats(const std::string& dir);

    /// Remove every *.hsncobj and *.hsncidx file of `dir` (ours by name;
    /// other files stay).
    /// Returns how many were removed; `problem` gets the first failure.
    static std::size_t clear(const std::string& dir, std::string& problem);

private:
    std::string dir_;
};

}  // namespace hsnc
