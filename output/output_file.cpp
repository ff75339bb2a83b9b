#include "output_file.h"

#include <fcntl.h>
#include <sys/stat.h>
#include <sys/wait.h>
#include <unistd.h>

#include <atomic>
#include <cerrno>
#include <climits>
#include <csignal>
#include <cstdlib>
#include <cstring>

#include "error.h"

namespace hsnc {
namespace {

// ---- the interrupt-cleanup registry ----
// The signal handler may only use async-signal-safe calls (POSIX.1-2017,
// 2.4.3: unlink, kill, waitpid, write, signal, raise, sigprocmask, _exit), so
// the temporary paths live in fixed arrays, not in std::string.
constexpr int kSlots = 16;
constexpr std::size_t kPathMax = 4096;
char g_paths[kSlots][kPathMax];
volatile std::sig_atomic_t g_used[kSlots];
volatile std::sig_atomic_t g_child = 0;
volatile std::sig_atomic_t g_stderr_tty = 0;

int register_temporary(const std::string& path) {
    if (path.size() >= kPathMax) return -1;
    for (int i = 0; i < kSlots; ++i)
        if (!g_used[i]) {
            std::memcpy(g_paths[i], path.c_str(), path.size() + 1);
            std::atomic_signal_fence(std::memory_order_seq_cst);  // the path is complete before the slot is used
            g_used[i] = 1;
            return i;
        }
    return -1;  // more outputs than slots: that one is not removed on an interrupt
}

void unregister_temporary(int slot) {
    if (slot >= 0) g_used[slot] = 0;
}

extern "C" void on_interrupt(int sig) {
    const int saved = errno;
    const pid_t child = static_cast<pid_t>(g_child);
    if (child > 0) {
        ::kill(child, SIGKILL);  // first, so that it cannot recreate a file removed below
        ::waitpid(child, nullptr, 0);
    }
    for (int i = 0; i < kSlots; ++i)
        if (g_used[i]) ::unlink(g_paths[i]);
    static const char int_msg[] = "hsnc: interrupted (SIGINT): unfinished output files removed\n";
    static const char term_msg[] = "hsnc: terminated (SIGTERM): unfinished output files removed\n";
    if (g_stderr_tty) (void)!::write(2, "\n", 1);  // past a progress bar or ^C
    if (sig == SIGINT)
        (void)!::write(2, int_msg, sizeof int_msg - 1);
    else
        (void)!::write(2, term_msg, sizeof term_msg - 1);
    // End by the same signal, so that a calling shell or script sees it
    // (a shell loop stops on a child killed by SIGINT; $? is 128 + signal).
    std::signal(sig, SIG_DFL);
    sigset_t set;
    sigemptyset(&set);
    sigaddset(&set, sig);
    ::sigprocmask(SIG_UNBLOCK, &set, nullptr);
    ::raise(sig);
    errno = saved;
    ::_exit(128 + sig);
}

std::string dir_of(const std::string& p) {
    const auto k = p.find_last_of('/');
    if (k == std::string::npos) return ".";
    if (k == 0) return "/";
    return p.substr(0, k);
}

std::string base_of(const std::string& p) {
    const auto k = p.find_last_of('/');
    return k == std::string::npos ? p : p.substr(k + 1);
}

std::string real_path(const std::string& p) {
    char* r = ::realpath(p.c_str(), nullptr);
    if (!r) return p;
    std::string s(r);
    std::free(r);
    return s;
}

// The directory a new file is created in must exist and be writable.
void check_directory(const OutputTarget& t, const std::string& dir) {
    struct stat st;
    if (::stat(dir.c_str(), &st) != 0) {
        if (errno == ENOENT) throw InputError(t.label() + ": directory '" + dir + "' does not exist");
        throw InputError(t.label() + ": directory '" + dir + "': " + std::strerror(errno));
    }
    if (!S_ISDIR(st.st_mode)) throw InputError(t.label() + ": '" + dir + "' is not a directory");
    if (::access(dir.c_str(), W_OK | X_OK) != 0)
        throw InputError(t.label() + ": cannot create a file in directory '" + dir + "': " + std::strerror(errno));
}

}  // namespace

std::string OutputTarget::label() const { return (flag.empty() ? "cannot write" : flag) + " '" + path + "'"; }

OutputTarget check_output(const std::string& flag, const std::string& path) {
    OutputTarget t;
    t.flag = flag;
    t.path = path;
    t.file = path;
    if (path.empty()) throw InputError((flag.empty() ? std::string("output") : flag) + ": empty file name");
    struct stat st;
    if (::stat(path.c_str(), &st) == 0) {  // exists (through symbolic links)
        t.exists = true;
        t.dev = st.st_dev;
        t.ino = st.st_ino;
        t.char_device = S_ISCHR(st.st_mode);
        t.canonical = real_path(path);
        // This process's stdout or stderr (/dev/stdout, or the file the shell
        // redirected it to): written through that descriptor, whatever it is.
        for (int fd : {1, 2}) {
            struct stat s;
            if (::fstat(fd, &s) == 0 && s.st_dev == st.st_dev && s.st_ino == st.st_ino) {
                t.mode = OutputTarget::Mode::stream;
                t.standard_fd = fd;
                return t;
            }
        }
        if (S_ISDIR(st.st_mode)) throw InputError(t.label() + ": is a directory");
        if (S_ISBLK(st.st_mode))
            throw InputError(t.label() + ": is a block device (hsnc writes CSV and PNG files, not disks)");
        if (S_ISSOCK(st.st_mode)) throw InputError(t.label() + ": is a socket");
        if (S_ISCHR(st.st_mode) || S_ISFIFO(st.st_mode)) {
            if (::access(path.c_str(), W_OK) != 0)
                throw InputError(t.label() + ": not writable: " + std::strerror(errno));
            t.mode = OutputTarget::Mode::stream;
            return t;
        }
        if (!S_ISREG(st.st_mode)) throw InputError(t.label() + ": is not a regular file");
        // A regular file, possibly through symbolic links: the link's target
        // is replaced (the temporary file goes beside it), the link stays.
        t.file = t.canonical;
        if (::access(t.file.c_str(), W_OK) != 0)
            throw InputError(t.label() + ": not writable: " + std::strerror(errno));
        check_directory(t, dir_of(t.file));
        return t;
    }
    if (errno != ENOENT) throw InputError(t.label() + ": " + std::strerror(errno));  // ENOTDIR, EACCES, ELOOP, ...
    // Does not exist: a new file, or the missing target of a dangling link.
    std::string p = path;
    for (int hops = 0;; ++hops) {
        struct stat ls;
        if (::lstat(p.c_str(), &ls) != 0) break;  // the name to create
        if (!S_ISLNK(ls.st_mode) || hops == 40)
            throw InputError(t.label() + ": cannot be resolved (a loop of symbolic links?)");
        char buf[PATH_MAX];
        const ssize_t n = ::readlink(p.c_str(), buf, sizeof buf - 1);
        if (n < 0) throw InputError(t.label() + ": " + std::strerror(errno));
        const std::string target(buf, static_cast<std::size_t>(n));
        p = !target.empty() && target[0] == '/' ? target : dir_of(p) + "/" + target;
    }
    const std::string name = base_of(p);
    if (name.empty() || name == "." || name == "..") throw InputError(t.label() + ": names a directory, not a file");
    const std::string dir = dir_of(p);
    check_directory(t, dir);
    t.file = p;
    t.canonical = real_path(dir) + "/" + name;
    return t;
}

bool same_file(const OutputTarget& a, const OutputTarget& b) {
    if (a.exists && b.exists) return a.dev == b.dev && a.ino == b.ino;
    if (!a.exists && !b.exists) return a.canonical == b.canonical;
    return false;
}

void check_distinct(const std::vector<const OutputTarget*>& targets) {
    for (std::size_t i = 0; i < targets.size(); ++i)
        for (std::size_t j = i + 1; j < targets.size(); ++j) {
            const OutputTarget& a = *targets[i];
            const OutputTarget& b = *targets[j];
            if (same_file(a, b) && !(a.char_device && b.char_device))
                throw InputError(a.label() + " and " + b.label() +
                                 " are the same file: each output needs its own (they would overwrite each other)");
        }
}

// ---- OutputFile ----

OutputFile::OutputFile(OutputTarget target) : target_(std::move(target)) {
    if (target_.mode == OutputTarget::Mode::stream) {
        if (target_.standard_fd >= 0)
            fd_ = ::fcntl(target_.standard_fd, F_DUPFD_CLOEXEC, 3);
        else  // a FIFO blocks here until a reader opens it, as a shell redirection does
            do fd_ = ::open(target_.file.c_str(), O_WRONLY | O_NOCTTY | O_CLOEXEC);
            while (fd_ < 0 && errno == EINTR);
        if (fd_ < 0) throw RunError(target_.label() + ": cannot open: " + std::strerror(errno));
    } else {
        struct stat st;
        const bool replacing = ::stat(target_.file.c_str(), &st) == 0 && S_ISREG(st.st_mode);
        for (int k = 0; fd_ < 0; ++k) {
            tmp_ = target_.file + ".tmp." + std::to_string(::getpid()) + (k ? "." + std::to_string(k) : "");
            slot_ = register_temporary(tmp_);  // before it exists: an interrupt can come at any time
            fd_ = ::open(tmp_.c_str(), O_WRONLY | O_CREAT | O_EXCL | O_CLOEXEC, 0666);
            if (fd_ >= 0) break;
            const int err = errno;
            unregister_temporary(slot_);
            slot_ = -1;
            if (err != EEXIST || k == 100) {
                tmp_.clear();
                throw RunError(target_.label() + ": cannot create a file beside it: " + std::strerror(err));
            }
        }
        if (replacing) (void)::fchmod(fd_, st.st_mode & 07777);  // the replaced file's permissions
    }
    buffer_.resize(1 << 16);
}

OutputFile::~OutputFile() { discard(); }

void OutputFile::discard() {
    if (fd_ >= 0) ::close(fd_);
    fd_ = -1;
    if (!tmp_.empty()) ::unlink(tmp_.c_str());
    tmp_.clear();
    unregister_temporary(slot_);
    slot_ = -1;
}

void OutputFile::fail(const std::string& what, int err) {
    discard();
    throw RunError(target_.label() + ": " + what + ": " + std::strerror(err));
}

void OutputFile::flush() {
    if (fd_ < 0) throw RunError(target_.label() + ": not written (an earlier error)");
    std::size_t done = 0;
    while (done < used_) {
        const ssize_t n = ::write(fd_, buffer_.data() + done, used_ - done);
        if (n < 0 && errno == EINTR) continue;
        if (n <= 0) fail("write failed", n < 0 ? errno : EIO);
        done += static_cast<std::size_t>(n);
    }
    used_ = 0;
}

void OutputFile::write(const char* data, std::size_t size) {
    while (size > 0) {
        if (used_ == buffer_.size()) flush();
        const std::size_t k = std::min(size, buffer_.size() - used_);
        std::memcpy(buffer_.data() + used_, data, k);
        used_ += k;
        data += k;
        size -= k;
    }
}

void OutputFile::commit() {
    flush();
    const int fd = fd_;
    fd_ = -1;
    if (::close(fd) != 0) fail("write failed", errno);  // NFS and quotas report at close
    if (!tmp_.empty() && ::rename(tmp_.c_str(), target_.file.c_str()) != 0) fail("cannot rename into place", errno);
    tmp_.clear();
    unregister_temporary(slot_);
    slot_ = -1;
}

void install_interrupt_cleanup() {
    g_stderr_tty = ::isatty(2) ? 1 : 0;
    struct sigaction sa;
    std::memset(&sa, 0, sizeof sa);
    sa.sa_handler = on_interrupt;
    sigemptyset(&sa.sa_mask);
    sigaddset(&sa.sa_mask, SIGINT);
    sigaddset(&sa.sa_mask, SIGTERM);
    for (int sig : {SIGINT, SIGTERM}) {
        struct sigaction old;
        // A signal ignored by whoever started us (nohup, a background job) stays ignored.
        if (::sigaction(sig, nullptr, &old) == 0 && old.sa_handler == SIG_IGN) continue;
        ::sigaction(sig, &sa, nullptr);
    }
    std::signal(SIGPIPE, SIG_IGN);
}

void set_interrupt_child(pid_t pid) { g_child = static_cast<std::sig_atomic_t>(pid); }

}  // namespace hsnc
