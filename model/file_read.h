// hsnc -- read_regular_file: the whole of a file that must be a regular file
// of bounded size (a model, a cache entry).
//
// A path can name anything: a FIFO (open() would wait for a writer forever),
// a character device such as /dev/zero (read() never ends, the process runs
// out of memory), a directory, or a file far larger than any model or
// kernel. The file is opened with O_NONBLOCK (so a FIFO never blocks), checked
// with fstat on the opened descriptor (no race between check and use: S_ISREG
// and st_size), and read to at most `max_bytes` (a file that grows while it
// is read is refused as well).
#pragma once

#include <sys/stat.h>

#include <cstddef>
#include <string>

namespace hsnc {

/// The largest model file read_model takes (the bundled ones are a few kB).
inline constexpr std::size_t kMaxModelFileBytes = std::size_t{16} << 20;
/// The largest kernel cache entry (runtime/jit/kernel_cache.h) loaded; a kernel
/// object of 12 masses is about 60 kB.
inline constexpr std::size_t kMaxCacheEntryBytes = std::size_t{16} << 20;

struct FileRead {
    enum class Status {
        ok,       ///< `bytes` holds the file
        missing,  ///< no such file (ENOENT, or a path component is not a directory)
        refused,  ///< not a regular file, larger than allowed, or unreadable: `problem` says which
    };
    Status status = Status::missing;
    std::string bytes;
    /// Unless ok: strerror(errno) ("No such file or directory", "Is a
    /// directory", ...), "not a regular file" or "larger than N bytes".
    std::string problem;
};

/// The contents of `path` when it is a regular file of at most `max_bytes`
/// (a path holding a NUL character is refused, never cut at the NUL).
/// Never blocks on a FIFO and never reads more than max_bytes + 1 bytes.
/// `status`, when given, receives the fstat of the file read (when opened).
FileRead read_regular_file(const std::string& path, std::size_t max_bytes, struct stat* status = nullptr);

}  // namespace hsnc
