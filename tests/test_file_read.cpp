// read_regular_file (model/file_read.h): only regular files of bounded size
// are read; a FIFO, a device or a directory is refused without blocking or
// reading, so that `hsnc check` on any path ends promptly.
#include <gtest/gtest.h>

#include <signal.h>
#include <sys/stat.h>
#include <sys/wait.h>
#include <unistd.h>

#include <chrono>
#include <filesystem>
#include <fstream>
#include <functional>
#include <thread>

#include "cli_runner.h"
#include "file_read.h"

namespace hsnc {
namespace {

namespace fs = std::filesystem;

// An address-space limit for `hsnc`: were a device read without end, the
// process would stop at it instead of taking the machine's memory. Not under
// AddressSanitizer, whose shadow memory needs terabytes of address space.
#if defined(__SANITIZE_ADDRESS__)
constexpr const char* kMemoryLimit = "";
#else
constexpr const char* kMemoryLimit = " prlimit --as=8000000000";
#endif

// Runs `body` in a child process and returns its exit code, or -1 when it did
// not end within `seconds` (it is killed): a call that would block forever or
// read without end fails the test instead of hanging it.
int exit_code_within(const std::function<int()>& body, int seconds) {
    const pid_t pid = ::fork();
    if (pid == 0) {
        ::alarm(static_cast<unsigned>(seconds) + 5);  // a backstop should the parent die
        ::_exit(body());
    }
    const auto deadline = std::chrono::steady_clock::now() + std::chrono::seconds(seconds);
    int status = 0;
    while (::waitpid(pid, &status, WNOHANG) == 0) {
        if (std::chrono::steady_clock::now() > deadline) {
            ::kill(pid, SIGKILL);
            ::waitpid(pid, &status, 0);
            return -1;
        }
        std::this_thread::sleep_for(std::chrono::milliseconds(10));
    }
    return WIFEXITED(status) ? WEXITSTATUS(status) : -1;
}

class FileReadDir : public ::testing::Test {
protected:
    void SetUp() override { fs::create_directories(dir); }
    void TearDown() override { fs::remove_all(dir); }
    std::string dir = testing::temp_path("file-read");
};

TEST_F(FileReadDir, ReadsARegularFileWhole) {
    const std::string text(100000, 'a');
    std::ofstream(dir + "/f", std::ios::binary) << text;
    const FileRead r = read_regular_file(dir + "/f", text.size());
    ASSERT_EQ(r.status, FileRead::Status::ok) << r.problem;
    EXPECT_EQ(r.bytes, text);
    EXPECT_EQ(r.problem, "");
    const FileRead empty = read_regular_file((std::ofstream(dir + "/e"), dir + "/e"), 10);
    EXPECT_EQ(empty.status, FileRead::Status::ok);
    EXPECT_EQ(empty.bytes, "");
}

TEST_F(FileReadDir, MissingDirectoryAndOversizedFilesSayWhy) {
    FileRead r = read_regular_file(dir + "/none", 10);
    EXPECT_EQ(r.status, FileRead::Status::missing);
    EXPECT_EQ(r.problem, "No such file or directory");
    r = read_regular_file(dir + "/none/deeper", 10);
    EXPECT_EQ(r.status, FileRead::Status::missing);
    r = read_regular_file(dir, 10);
    EXPECT_EQ(r.status, FileRead::Status::refused);
    EXPECT_EQ(r.problem, "Is a directory");
    std::ofstream(dir + "/big") << std::string(1001, 'b');
    r = read_regular_file(dir + "/big", 1000);
    EXPECT_EQ(r.status, FileRead::Status::refused);
    EXPECT_EQ(r.problem, "larger than 1000 bytes");
    EXPECT_EQ(r.bytes, "");
    EXPECT_EQ(read_regular_file(dir + "/big", 1001).status, FileRead::Status::ok);
}

TEST_F(FileReadDir, AFifoIsRefusedWithoutWaitingForAWriter) {
    ASSERT_EQ(::mkfifo((dir + "/fifo").c_str(), 0600), 0);
    const int code = exit_code_within(
        [&] {
            const FileRead r = read_regular_file(dir + "/fifo", 1000);
            return r.status == FileRead::Status::refused && r.problem == "not a regular file" ? 0 : 1;
        },
        20);
    EXPECT_EQ(code, 0) << "-1: blocked in open() or read()";
}

TEST_F(FileReadDir, ALinkToDevZeroIsRefusedNotRead) {
    fs::create_symlink("/dev/zero", dir + "/zero");
    const int code = exit_code_within(
        [&] {
            const FileRead r = read_regular_file(dir + "/zero", std::size_t{1} << 40);
            return r.status == FileRead::Status::refused && r.problem == "not a regular file" ? 0 : 1;
        },
        20);
    EXPECT_EQ(code, 0) << "-1: read without end";
}

// `hsnc check` (read_model) on such paths: exit 2 with the reason, promptly.
TEST_F(FileReadDir, CheckRefusesFifoAndDeviceModelFiles) {
    ASSERT_EQ(::mkfifo((dir + "/model.toml").c_str(), 0600), 0);
    fs::create_symlink("/dev/zero", dir + "/zero.toml");
    for (const std::string name : {"model.toml", "zero.toml"}) {
        const std::string path = dir + "/" + name;
        const testing::CliRun r = testing::run_hsnc("check '" + path + "'", std::string("timeout 20") + kMemoryLimit);
        EXPECT_EQ(r.exit_code, 2) << name << ": " << r.err << " (124: it hung)";
        EXPECT_EQ(r.err, "hsnc: cannot read model file '" + path + "': not a regular file\n");
    }
    std::ofstream(dir + "/huge.toml") << "";
    fs::resize_file(dir + "/huge.toml", kMaxModelFileBytes + 1);  // sparse: no disk used
    const testing::CliRun huge = testing::run_hsnc("check '" + dir + "/huge.toml'");
    EXPECT_EQ(huge.exit_code, 2) << huge.err;
    EXPECT_EQ(huge.err, "hsnc: cannot read model file '" + dir + "/huge.toml': larger than " +
                            std::to_string(kMaxModelFileBytes) + " bytes\n");
}

}  // namespace
}  // namespace hsnc
