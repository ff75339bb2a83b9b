#include "file_read.h"

#include <fcntl.h>
#include <sys/stat.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <cstdint>
#include <cstring>

namespace hsnc {

FileRead read_regular_file(const std::string& path, std::size_t max_bytes, struct stat* status) {
    FileRead r;
    // open() stops at a NUL: "K.mtx\0x" would read K.mtx, a file the caller did not name.
    if (path.find('\0') != std::string::npos) {
        r.status = FileRead::Status::refused;
        r.problem = "the path contains a NUL character";
        return r;
    }
    // O_NONBLOCK: opening a FIFO for reading would otherwise wait for a writer.
    const int fd = ::open(path.c_str(), O_RDONLY | O_CLOEXEC | O_NONBLOCK);
    if (fd < 0) {
        r.status = errno == ENOENT || errno == ENOTDIR ? FileRead::Status::missing : FileRead::Status::refused;
        r.problem = std::strerror(errno);
        return r;
    }
    r.status = FileRead::Status::refused;
    struct stat st;
    const bool known = ::fstat(fd, &st) == 0;
    if (known && status) *status = st;
    if (!known) {
        r.problem = std::strerror(errno);
    } else if (!S_ISREG(st.st_mode)) {
        r.problem = S_ISDIR(st.st_mode) ? std::strerror(EISDIR) : "not a regular file";
    } else if (static_cast<std::uint64_t>(st.st_size) > max_bytes) {
        r.problem = "larger than " + std::to_string(max_bytes) + " bytes";
    } else {
        // Read to end of file, but never past max_bytes + 1 (the file may grow).
        r.bytes.resize(static_cast<std::size_t>(st.st_size));
        std::size_t got = 0;
        for (;;) {
            if (got == r.bytes.size()) {
                if (got > max_bytes) break;
                r.bytes.resize(std::min(max_bytes + 1, got + 4096));
            }
            const ssize_t n = ::read(fd, &r.bytes[got], r.bytes.size() - got);
            if (n < 0 && errno == EINTR) continue;
            if (n < 0) {
                r.problem = std::strerror(errno);
                break;
            }
            if (n == 0) break;
            got += static_cast<std::size_t>(n);
        }
        r.bytes.resize(got);
        if (r.problem.empty() && got > max_bytes) r.problem = "larger than " + std::to_string(max_bytes) + " bytes";
        if (r.problem.empty()) r.status = FileRead::Status::ok;
    }
    ::close(fd);
    if (r.status != FileRead::Status::ok) r.bytes.clear();
    return r;
}

}  // namespace hsnc
