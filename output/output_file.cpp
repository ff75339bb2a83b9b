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
#include <deque>
#include <mutex>
#include <stdexcept>

#include "error.h"
#include "input_files.h"

namespace hsnc {
namespace {

// ---- the interrupt-cleanup registry ----
// The signal handler may only use async-signal-safe calls (POSIX.1-2017,
// 2.4.3: unlink, kill, waitpid, write, signal, raise, sigprocmask, _exit), so
// the temporary paths live in fixed arrays, not in std::string.
constexpr int kSlots = 64;
constexpr std::size_t kPathMax = 4096;
char g_paths[kSlots][kPathMax];
volatile std::sig_atomic_t g_used[kSlots];
volatile std::sig_atomic_t g_child = 0;
volatile std::sig_atomic_t g_stderr_tty = 0;

// The transaction of this command, if any (OutputTransaction).
std::mutex g_transaction_mutex;
OutputTransaction* g_transaction = nullptr;

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

// ---- following symbolic links safely ----
// hsnc replaces an existing file by renaming a temporary file onto the end of
// its path's chain of links, so the kernel's fs.protected_symlinks, which
// guards open(), never sees those links. walk_links applies its rule itself
// (Documentation/admin-guide/sysctl/fs.rst, protected_symlinks): a link in a
// sticky world-writable directory (/tmp) is followed only when the caller or
// the directory's owner owns it. Otherwise any user could plant
// /tmp/run.csv -> /etc/passwd and wait for root to write its output there.
// It also refuses a final link whose target does not exist: a file is never
// created through a dangling link (where the link says, as whoever runs).
// Links under /proc (/dev/stdout -> /proc/self/fd/1 -> "pipe:[..]") are the
// kernel's own and are not read as text: the walk stops there.

// Splits a path into its components, empty ones dropped.
void push_components(std::deque<std::string>& to, const std::string& path) {
    std::deque<std::string> parts;
    std::size_t i = 0;
    while (i <= path.size()) {
        const std::size_t j = std::min(path.find('/', i), path.size());
        if (j > i) parts.push_back(path.substr(i, j - i));
        i = j + 1;
    }
    to.insert(to.begin(), parts.begin(), parts.end());
}

void walk_links(const OutputTarget& t) {
    std::deque<std::string> rest;
    push_components(rest, t.path);
    std::string dir = t.path[0] == '/' ? "" : ".";  // the part resolved so far: no links in it
    bool final_from_link = false;  // the last component is (in) a link's target
    for (int hops = 0; !rest.empty();) {
        const std::string name = rest.front();
        rest.pop_front();
        if (name == ".") continue;
        const std::string next = dir + "/" + name;
        struct stat ls;
        if (::lstat(next.c_str(), &ls) != 0) {
            if (errno == ENOENT && rest.empty() && final_from_link)
                throw InputError(t.label() + ": is a symbolic link to '" + next +
                                 "', which does not exist: hsnc does not create a file through a dangling link");
            return;  // a new name, or an error check_output reports with the kernel's words
        }
        if (!S_ISLNK(ls.st_mode)) {
            dir = next;
            continue;
        }
        if (dir == "/proc" || dir.rfind("/proc/", 0) == 0) return;  // the kernel's own links
        if (++hops > 40) throw InputError(t.label() + ": cannot be resolved (a loop of symbolic links?)");
        struct stat ds;
        const std::string parent = dir.empty() ? "/" : dir;
        if (::stat(parent.c_str(), &ds) == 0 && (ds.st_mode & S_ISVTX) && (ds.st_mode & S_IWOTH) &&
            ls.st_uid != ::geteuid() && ls.st_uid != ds.st_uid)
            throw InputError(t.label() + ": '" + next + "' is a symbolic link in the shared directory '" + parent +
                             "' owned by another user (uid " + std::to_string(ls.st_uid) +
                             "): hsnc does not write through it (as the kernel's protected_symlinks would refuse)");
        char buf[PATH_MAX];
        const ssize_t n = ::readlink(next.c_str(), buf, sizeof buf - 1);
        if (n < 0) throw InputError(t.label() + ": " + std::strerror(errno));
        const std::string target(buf, static_cast<std::size_t>(n));
        final_from_link = final_from_link || rest.empty();
        push_components(rest, target);
        if (!target.empty() && target[0] == '/') dir = "";
    }
}

// An output that is one of the run's inputs (input_files.h) would replace it.
void check_not_input(const OutputTarget& t, const struct stat& st) {
    const std::string input = input_file_named(st.st_dev, st.st_ino);
    if (!input.empty())
        throw InputError(t.label() + ": is the input file '" + input +
                         "' of this run: an output never replaces an input (name another file)");
}

}  // namespace

std::string OutputTarget::label() const { return (flag.empty() ? "cannot write" : flag) + " '" + path + "'"; }

OutputTarget check_output(const std::string& flag, const std::string& path) {
    OutputTarget t;
    t.flag = flag;
    t.path = path;
    t.file = path;
    if (path.empty()) throw InputError((flag.empty() ? std::string("output") : flag) + ": empty file name");
    if (path.find('\0') != std::string::npos) throw InputError(t.label() + ": the file name holds a NUL character");
    walk_links(t);  // links planted by another user, dangling links
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
        check_not_input(t, st);
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
        // A regular file, possibly through symbolic links (walk_links let them
        // through): the link's target is replaced (the temporary file goes
        // beside it), the link stays.
        t.file = t.canonical;
        if (::access(t.file.c_str(), W_OK) != 0)
            throw InputError(t.label() + ": not writable: " + std::strerror(errno));
        check_directory(t, dir_of(t.file));
        return t;
    }
    if (errno != ENOENT) throw InputError(t.label() + ": " + std::strerror(errno));  // ENOTDIR, EACCES, ELOOP, ...
    // Does not exist: a new name (walk_links refused a dangling link).
    struct stat ls;
    if (::lstat(path.c_str(), &ls) == 0)  // a link whose target vanished since walk_links
        throw InputError(t.label() + ": is a dangling symbolic link: hsnc does not create a file through it");
    const std::string name = base_of(path);
    if (name.empty() || name == "." || name == "..") throw InputError(t.label() + ": names a directory, not a file");
    const std::string dir = dir_of(path);
    check_directory(t, dir);
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
    {
        std::lock_guard<std::mutex> lock(g_transaction_mutex);
        if (g_transaction && !tmp_.empty()) {  // renamed when the whole command has succeeded
            g_transaction->pending_.push_back({tmp_, target_.file, target_.label(), slot_});
            tmp_.clear();
            slot_ = -1;
            return;
        }
    }
    if (!tmp_.empty() && ::rename(tmp_.c_str(), target_.file.c_str()) != 0) fail("cannot rename into place", errno);
    tmp_.clear();
    unregister_temporary(slot_);
    slot_ = -1;
}

// ---- OutputTransaction ----

OutputTransaction::OutputTransaction() {
    std::lock_guard<std::mutex> lock(g_transaction_mutex);
    if (g_transaction) throw std::logic_error("OutputTransaction: transactions do not nest");
    g_transaction = this;
}

OutputTransaction::~OutputTransaction() {
    std::lock_guard<std::mutex> lock(g_transaction_mutex);
    for (const Pending& p : pending_) {
        ::unlink(p.temporary.c_str());
        unregister_temporary(p.slot);
    }
    pending_.clear();
    g_transaction = nullptr;
}

void commit_outputs() {
    OutputTransaction* t;
    {
        std::lock_guard<std::mutex> lock(g_transaction_mutex);
        t = g_transaction;
    }
    if (t) t->commit();
}

std::size_t OutputTransaction::pending() const {
    std::lock_guard<std::mutex> lock(g_transaction_mutex);
    return pending_.size();
}

void OutputTransaction::commit() {
    std::lock_guard<std::mutex> lock(g_transaction_mutex);
    // Before anything is renamed, a second name (hard link) for each file to
    // be replaced, so that a failed rename can put every output back. A file
    // that cannot be linked (a file system without hard links) has none.
    std::vector<std::string> backups(pending_.size());
    for (std::size_t i = 0; i < pending_.size(); ++i) {
        struct stat st;
        if (::lstat(pending_[i].file.c_str(), &st) != 0 || !S_ISREG(st.st_mode)) continue;
        for (int k = 0; k < 100; ++k) {
            const std::string b = pending_[i].file + ".old." + std::to_string(::getpid()) + (k ? "." + std::to_string(k) : "");
            if (::link(pending_[i].file.c_str(), b.c_str()) == 0) {
                backups[i] = b;
                break;
            }
            if (errno != EEXIST) break;
        }
    }
    std::size_t done = 0;
    int err = 0;
    for (; done < pending_.size(); ++done)
        if (::rename(pending_[done].temporary.c_str(), pending_[done].file.c_str()) != 0) {
            err = errno;
            break;
        }
    if (done < pending_.size()) {
        for (std::size_t i = 0; i < done; ++i) {  // undo: the replaced file back, or the new name gone
            if (!backups[i].empty())
                (void)::rename(backups[i].c_str(), pending_[i].file.c_str());
            else
                (void)::unlink(pending_[i].file.c_str());
            backups[i].clear();
        }
    }
    for (const std::string& b : backups)
        if (!b.empty()) ::unlink(b.c_str());
    for (std::size_t i = 0; i < pending_.size(); ++i) {
        if (i >= done) ::unlink(pending_[i].temporary.c_str());
        unregister_temporary(pending_[i].slot);
    }
    const std::string label = done < pending_.size() ? pending_[done].label : std::string();
    pending_.clear();
    if (!label.empty())
        throw RunError(label + ": cannot rename into place: " + std::strerror(err) +
                       " (no output of this run was written)");
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
