// hsnc -- KernelCache: compiled kernels (object code) kept on disk between
// runs, so that a configuration's kernel is compiled once per machine, not
// once per run (--kernels jit; runtime/jit/jit_solver_provider.h).
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
// ours at all) is told apart from a good one, and never loaded. Since format
// 2 the object itself names its key (jit_key_definition), so that an entry
// holding another kernel's object is told apart without the model (stats). Writes go to a
// temporary name in the same directory (pid and a random suffix) and are
// renamed into place (rename(2) is atomic within a file system), so two
// processes filling one cache at once each leave a whole file: a reader sees
// either no entry or a complete one. No fsync (it would cost milliseconds per
// kernel): a file that a crash of the machine leaves cut short fails its
// header check and is rebuilt.
//
// The entries are machine code this process maps executable, so the cache is
// trusted only when nobody else can write to it: the directory is created
// 0700 (entries 0600), and a directory or entry that is not owned by this
// user or is group- or world-writable is refused (trust_problem). Entries are
// opened only when they are regular files of at most kMaxCacheEntryBytes
// (model/file_read.h: a FIFO or a link to /dev/zero is refused, never read).
// The cache keeps to a size limit (max_bytes, default kDefaultCacheMaxBytes):
// a load that hits touches the entry (its mtime is its last use) and a store
// evicts the least recently used files until the directory fits.
#pragma once

#include <cstdint>
#include <string>
#include <vector>

namespace hsnc {

inline constexpr std::uint32_t kCacheFormatVersion = 2;
inline constexpr const char* kCacheFileExtension = ".hsncobj";
/// Index entries: same format, the payload is the key of a .hsncobj entry.
inline constexpr const char* kCacheIndexExtension = ".hsncidx";
/// The size limit when none is given (`simulate --cache-max-size`).
inline constexpr std::uint64_t kDefaultCacheMaxBytes = std::uint64_t{256} << 20;

/// "256M", "1G", "64k", "1000" (bytes; K, M, G are powers of 1024) as bytes.
/// Throws InputError "WHAT: 'TEXT' is not a size (...)" when it is none of these,
/// "WHAT: 'TEXT' is too large (at most ...)" beyond 2^64 - 1 bytes.
std::uint64_t parse_byte_size(const std::string& text, const std::string& what);

/// The cache directory when none is given: $XDG_CACHE_HOME/hsnc when that is
/// set and absolute, else $HOME/.cache/hsnc; "" when neither can be named.
std::string default_cache_dir();

/// The key of the JIT's object for `source`: FNV-1a-128 (hex) of the source,
/// the embedded kernel_abi.h, Clang's version, the compile flags
/// (runtime/jit/jit_frontend.h) and this host's CPU as CPUID describes it (vendor,
/// family/model/stepping, feature words, the OS-enabled register state), which
/// is everything LLVM's host detection bases the target on. Equal keys mean
/// the JIT would produce the same object; computed without LLVM, so that a
/// run whose kernels are all cached need not load it (runtime/jit/object_loader.h).
std::string jit_cache_key(const std::string& source);

/// The key under which a run finds a kernel without deriving it: FNV-1a-128
/// of module_build_id() (it fixes the generator and emitter code), Clang's
/// version, the flags, the CPU, kernel_abi.h, the
/// model's canonical text (model_hash.h: every number a kernel depends on) and
/// the configuration key. "" when that object has no build ID. Its entry
/// (kCacheIndexExtension) holds the jit_cache_key of the kernel's source.
std::string jit_index_key(const std::string& model_text, const std::string& config_key);

/// What the JIT appends to a kernel's source before compiling it, so that the
/// object names the key it is stored under: a definition of
/// kCacheKeySymbolPrefix + KEY (one symbol per kernel: a JIT holds many)
/// holding KEY. KernelCache::stats counts an entry whose object does not
/// define its own key's symbol as damaged (another kernel's object).
inline constexpr const char* kCacheKeySymbolPrefix = "hsnc_cache_key_";
std::string jit_key_definition(const std::string& key);

/// jit_index_key for one model, its fixed parts (kernel_abi.h is long) hashed
/// once: a provider looks up every configuration it enters.
class JitIndexKeys {
public:
    explicit JitIndexKeys(const std::string& model_text);
    /// jit_index_key(model_text, config_key).
    std::string operator()(const std::string& config_key) const;

private:
    std::uint64_t hi_ = 0, lo_ = 0;  // the FNV state after the fixed parts
    bool none_ = false;              // no build ID: ""
};

/// The GNU build ID, in hex, of the object this code is linked into: the
/// executable (`hsnc`), or libhsnc.so in a program that links the library
/// (found by the address of a function of this file among the loaded
/// objects, not by taking the first one, which is the executable). "" when
/// that object has none.
std::string module_build_id();

/// The host part of jit_cache_key, e.g. "GenuineIntel 000906ea 7ffafbff ...".
std::string host_cpu_identity();

/// FNV-1a, 64 bits (the payload checksum).
std::uint64_t fnv1a64(const void* data, std::size_t size, std::uint64_t h = 0xcbf29ce484222325ULL);

class KernelCache {
public:
    /// A cache in `dir` (created, 0700, on the first store) that store() keeps
    /// to `max_bytes` (0: no limit). Touches nothing yet.
    explicit KernelCache(std::string dir, std::uint64_t max_bytes = kDefaultCacheMaxBytes)
        : dir_(std::move(dir)), max_bytes_(max_bytes) {}

    const std::string& dir() const { return dir_; }
    std::uint64_t max_bytes() const { return max_bytes_; }

    /// Why `dir` must not be used: "" when it is a directory owned by this
    /// user that neither group nor others can write, or does not exist yet;
    /// else e.g. "DIR is group- or world-writable (mode 0777)".
    static std::string trust_problem(const std::string& dir);
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

    /// The entry stored under `key`. Never throws on file contents. An entry
    /// that is not a regular file, is larger than kMaxCacheEntryBytes, is not
    /// owned by this user or is group/world-writable is `bad` (never read).
    /// A hit marks the entry used now (its mtime; see store's eviction).
    Entry load(const std::string& key, const char* ext = kCacheFileExtension) const;

    /// Store `payload` under `key` (temporary file, then rename), then evict
    /// least recently used files (not this one) until the cache holds at most
    /// max_bytes. Returns "" on success, else what went wrong ("cannot
    /// create directory ...: ...").
    std::string store(const std::string& key, const std::string& payload, const char* ext = kCacheFileExtension) const;

    /// Remove the least recently used entries and index entries (oldest
    /// mtime first; never `keep`) until their sizes add up to at most
    /// `max_bytes`. Returns how many were removed.
    static std::size_t evict(const std::string& dir, std::uint64_t max_bytes, const std::string& keep = "");

    struct Stats {
        std::size_t entries = 0;  ///< *.hsncobj that load: whole, our key, checksum, a loadable kernel object naming that key
        std::size_t damaged = 0;  ///< *.hsncobj that do not (truncated, corrupt, foreign, not a file, not ours)
        std::size_t index_entries = 0, index_damaged = 0;  ///< the same for *.hsncidx
        std::uint64_t bytes = 0;                           ///< file sizes of all of them
        std::int64_t oldest = 0, newest = 0;  ///< last use (mtime, s since epoch) of the good *.hsncobj
        std::vector<std::string> problems;    ///< "FILE: why" of each damaged one
    };
    /// What `dir` holds (all zero when it does not exist). Throws nothing;
    /// changes nothing (no last-use update).
    static Stats stats(const std::string& dir);

    /// Remove every *.hsncobj and *.hsncidx file of `dir` (ours by name;
    /// other files stay).
    /// Returns how many were removed; `problem` gets the first failure.
    static std::size_t clear(const std::string& dir, std::string& problem);

private:
    std::string dir_;
    std::uint64_t max_bytes_;
};

}  // namespace hsnc
