// hsnc -- output files that never clobber what their path points at.
//
// Every output path is checked before a run starts (check_output: InputError,
// exit code 2, nothing written), then written by an OutputFile:
//  - a regular file, or a name that does not exist yet, is written under a
//    temporary name in the same directory and renamed into place by commit()
//    (a failed or interrupted run never leaves half a file under the name the
//    user gave); a symbolic link is followed, so its target is replaced and
//    the link stays;
//  - a character device or a FIFO (/dev/null, a terminal, a named pipe), and
//    any path that is this process's stdout or stderr (/dev/stdout), is
//    written directly, in order: replacing it would destroy it;
//  - a directory, a block device or a socket is refused.
// Writes stop at the first error (RunError naming the file and the OS error).
// Paths are refused before a run (InputError) when they would replace one of
// the run's input files (input_files.h), or would be written through a
// symbolic link planted by another user in a shared sticky directory such as
// /tmp (the kernel's protected_symlinks rule), or through a dangling link.
// Inside an OutputTransaction every output is kept under its temporary name
// until the transaction commits: a run that fails leaves none of its outputs.
// install_interrupt_cleanup() makes SIGINT and SIGTERM remove the temporary
// files of the outputs still open before the process ends.
#pragma once

#include <sys/types.h>

#include <cstddef>
#include <string>
#include <vector>

namespace hsnc {

/// What an output path names, found before anything is written.
struct OutputTarget {
    enum class Mode {
        replace,  ///< regular file or new name: temporary file beside it, renamed by commit()
        stream,   ///< character device, FIFO, or a standard stream: written directly
    };
    std::string flag;  ///< the option that named it ("--out"), for messages; may be empty
    std::string path;  ///< as given
    std::string file;  ///< what is written: `path`, or the end of its chain of symbolic links
    Mode mode = Mode::replace;
    bool exists = false;
    dev_t dev = 0;          ///< identity when it exists
    ino_t ino = 0;
    std::string canonical;  ///< realpath of its directory + "/" + name when it does not exist
    bool char_device = false;
    int standard_fd = -1;   ///< 1 or 2 when the path is this process's stdout or stderr

    /// "--out 'x.csv'" (or "cannot write 'x.csv'" without a flag), for messages.
    std::string label() const;
};

/// Checks `path` for the output named by `flag` (e.g. "--out"). Throws
/// InputError when it cannot be written: a directory, a block device or a
/// socket, a directory that does not exist or is not writable, a file that
/// is not writable, a loop of symbolic links, a dangling link, a link in a
/// sticky world-writable directory that neither the caller nor the
/// directory's owner owns, an input file of this run (input_files.h).
OutputTarget check_output(const std::string& flag, const std::string& path);

/// True when the two targets are one file (same inode, or the same new name
/// once directories and symbolic links are resolved).
bool same_file(const OutputTarget& a, const OutputTarget& b);

/// Throws InputError when two of the targets are one file (two outputs would
/// mix into a corrupt file); a character device (/dev/null, a terminal) may be
/// shared.
void check_distinct(const std::vector<const OutputTarget*>& targets);

/// One output being written (see the file comment). Buffered; stops at the
/// first write error.
class OutputFile {
public:
    /// Opens the target (its temporary file for Mode::replace). Throws
    /// RunError when it cannot (the path changed since it was checked).
    explicit OutputFile(OutputTarget target);
    ~OutputFile();  ///< removes the temporary file unless committed
    OutputFile(const OutputFile&) = delete;
    OutputFile& operator=(const OutputFile&) = delete;

    void write(const char* data, std::size_t size);
    void put(char c) {
        if (used_ == buffer_.size()) flush();
        buffer_[used_++] = c;
    }
    /// Flush, close, and rename into place (inside an OutputTransaction: hand
    /// the closed temporary file to it, which renames it when it commits).
    /// Throws RunError on I/O failure (the temporary file is removed).
    void commit();

    const OutputTarget& target() const { return target_; }
    /// The temporary file being written ("" for Mode::stream).
    const std::string& temporary() const { return tmp_; }

private:
    void flush();
    [[noreturn]] void fail(const std::string& what, int err);
    void discard();

    OutputTarget target_;
    std::string tmp_;
    int fd_ = -1;
    int slot_ = -1;  // in the interrupt-cleanup registry
    std::vector<char> buffer_;
    std::size_t used_ = 0;
};

/// The outputs of one command, all or nothing. While a transaction exists,
/// OutputFile::commit() writes and closes its file but leaves it under its
/// temporary name; commit() then renames every one into place, and the
/// destructor of a transaction that was not committed (the command failed)
/// removes them, so that the files they would have replaced stay as they
/// were. Outputs written directly (a device, a FIFO, stdout) cannot be held
/// back and are not part of it. One transaction at a time (the command line
/// opens one per command; a second throws std::logic_error).
class OutputTransaction {
public:
    OutputTransaction();
    ~OutputTransaction();  ///< removes the outputs not committed
    OutputTransaction(const OutputTransaction&) = delete;
    OutputTransaction& operator=(const OutputTransaction&) = delete;

    /// Renames every output into place. When a rename fails (a directory
    /// changed under the run), the outputs already renamed are put back as
    /// they were (the replaced files restored from links taken before), the
    /// rest removed, and RunError names the output.
    void commit();
    /// Outputs waiting for commit().
    std::size_t pending() const;

    struct Pending {
        std::string temporary, file, label;
        int slot;  // in the interrupt-cleanup registry
    };

private:
    std::vector<Pending> pending_;
    friend class OutputFile;
};

/// Commits the current OutputTransaction now (no-op without one): for a
/// command whose outputs record a failure (a sweep's failed points) and that
/// exits 1 after writing them.
void commit_outputs();

/// SIGINT and SIGTERM: remove the temporary files of every OutputFile not yet
/// committed, stop the child registered with set_interrupt_child, print
/// "hsnc: interrupted (SIGINT): ..." on stderr and end the process by the same
/// signal (the shell reports 130 or 143). Also ignores SIGPIPE, so that a
/// closed pipe is a write error with a message rather than a silent death.
void install_interrupt_cleanup();

/// A child process (gnuplot) that the interrupt cleanup kills first; 0: none.
void set_interrupt_child(pid_t pid);

}  // namespace hsnc
