// The output side of `hsnc simulate` (issue 11): outputs never clobber what
// their path points at (devices, FIFOs, symbolic links), every output path is
// checked before the run, a write error or an interrupt stops the run and
// leaves no temporary file, flags that would make a silent non-run are
// refused, and the --plot figure.
#include <gtest/gtest.h>
#include <fcntl.h>
#include <signal.h>
#include <sys/socket.h>
#include <sys/stat.h>
#include <sys/un.h>
#include <sys/sysmacros.h>
#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <string>
#include <thread>
#include <vector>

#include "cli_runner.h"
#include "temp_dir.h"
#include "csv_writer.h"
#include "error.h"
#include "integrators.h"
#include "model_reader.h"
#include "output_file.h"
#include "plot.h"
#include "simulate_outputs.h"

namespace hsnc {
namespace {

using testing::file_exists;
using testing::model_path;
using testing::run_hsnc;
using testing::slurp;
namespace fs = std::filesystem;

using testing::TempDir;

std::string q(const std::string& s) { return "'" + s + "'"; }

// A private node of a character device (mknod: root only), which a faulty
// build could replace without harm; otherwise the system's node, which a
// process that is not root cannot replace (/dev is not writable to it).
std::string device_node(const TempDir& dir, const char* name, unsigned major, unsigned minor,
                        const std::string& system_path) {
    const std::string p = dir / name;
    if (::mknod(p.c_str(), S_IFCHR | 0666, makedev(major, minor)) == 0) return p;
    return system_path;
}

bool is_char_device(const std::string& p) {
    struct stat st;
    return ::stat(p.c_str(), &st) == 0 && S_ISCHR(st.st_mode);
}

std::size_t count_lines(const std::string& text) { return static_cast<std::size_t>(std::count(text.begin(), text.end(), '\n')); }

const char* const kTrajHeader = "t,x_m1,v_m1\n";  // coulomb-1dof

// ---- 1. outputs never clobber what they point at ----

// The one test that names a system device: that /dev/null stays one, also
// when two outputs share it.
TEST(Outputs, DevNullStaysACharacterDevice) {
    const auto r = run_hsnc("simulate " + q(model_path("coulomb-1dof.toml")) +
                            " --t-end 1 --out /dev/null --events /dev/null --quiet");
    EXPECT_EQ(r.exit_code, 0) << r.err;
    EXPECT_TRUE(is_char_device("/dev/null"));
}

TEST(Outputs, ACharacterDeviceIsWrittenNotReplaced) {
    TempDir dir;
    const std::string null_node = device_node(dir, "null", 1, 3, "/dev/null");
    const auto r = run_hsnc("simulate " + q(model_path("coulomb-1dof.toml")) + " --t-end 1 --quiet --out " + q(null_node));
    EXPECT_EQ(r.exit_code, 0) << r.err;
    EXPECT_TRUE(is_char_device(null_node));
    for (const std::string& n : dir.names()) EXPECT_EQ(n.find(".tmp"), std::string::npos) << n;
}

TEST(Outputs, AFifoIsWrittenInOrderNotReplaced) {
    TempDir dir;
    const std::string fifo = dir / "fifo";
    ASSERT_EQ(::mkfifo(fifo.c_str(), 0600), 0);
    // Read and write end held here: hsnc's open does not block, and the
    // trajectory (4.5 kB) fits in the pipe's buffer.
    const int fd = ::open(fifo.c_str(), O_RDWR | O_NONBLOCK);
    ASSERT_GE(fd, 0);
    const auto r = run_hsnc("simulate " + q(model_path("coulomb-1dof.toml")) +
                            " --t-end 1 --dt 0.01 --quiet --out " + q(fifo));
    EXPECT_EQ(r.exit_code, 0) << r.err;
    std::string got;
    char buf[4096];
    for (ssize_t n; (n = ::read(fd, buf, sizeof buf)) > 0;) got.append(buf, static_cast<std::size_t>(n));
    ::close(fd);
    struct stat st;
    ASSERT_EQ(::lstat(fifo.c_str(), &st), 0);
    EXPECT_TRUE(S_ISFIFO(st.st_mode));
    EXPECT_EQ(got.rfind(kTrajHeader, 0), 0u) << got.substr(0, 100);
    EXPECT_EQ(count_lines(got), 1u + 101u);
}

TEST(Outputs, ASymbolicLinkIsWrittenThroughAndKept) {
    TempDir dir;
    fs::create_directory(dir / "data");
    std::ofstream(dir / "data/target.csv") << "old\n";
    ASSERT_EQ(::symlink("data/target.csv", (dir / "link.csv").c_str()), 0);
    const auto r = run_hsnc("simulate " + q(model_path("coulomb-1dof.toml")) + " --t-end 1 --quiet --out " +
                            q(dir / "link.csv"));
    ASSERT_EQ(r.exit_code, 0) << r.err;
    struct stat st;
    ASSERT_EQ(::lstat((dir / "link.csv").c_str(), &st), 0);
    EXPECT_TRUE(S_ISLNK(st.st_mode));
    EXPECT_EQ(slurp(dir / "data/target.csv").rfind(kTrajHeader, 0), 0u);
    EXPECT_EQ(dir.names(), (std::vector<std::string>{"data", "link.csv"}));
    std::vector<std::string> data;
    for (const auto& e : fs::directory_iterator(dir / "data")) data.push_back(e.path().filename().string());
    EXPECT_EQ(data, (std::vector<std::string>{"target.csv"}));
}

TEST(Outputs, AReplacedFileKeepsItsPermissions) {
    TempDir dir;
    const std::string out = dir / "out.csv";
    std::ofstream(out) << "old\n";
    ASSERT_EQ(::chmod(out.c_str(), 0640), 0);
    const auto r = run_hsnc("simulate " + q(model_path("coulomb-1dof.toml")) + " --t-end 1 --quiet --out " + q(out));
    ASSERT_EQ(r.exit_code, 0) << r.err;
    struct stat st;
    ASSERT_EQ(::stat(out.c_str(), &st), 0);
    EXPECT_EQ(st.st_mode & 07777, 0640u);
    EXPECT_EQ(slurp(out).rfind(kTrajHeader, 0), 0u);
}

// ---- 6. every output path checked before the run ----

struct BadPath {
    const char* name;
    std::string args;     // with DIR for the test's directory
    const char* message;  // in stderr
};

// A Unix-domain socket file at `path` (it stays after the socket is closed).
void bind_socket(const std::string& path) {
    const int fd = ::socket(AF_UNIX, SOCK_STREAM, 0);
    ASSERT_GE(fd, 0);
    sockaddr_un addr{};
    addr.sun_family = AF_UNIX;
    ASSERT_LT(path.size(), sizeof addr.sun_path);
    std::memcpy(addr.sun_path, path.c_str(), path.size() + 1);
    EXPECT_EQ(::bind(fd, reinterpret_cast<const sockaddr*>(&addr), sizeof addr), 0) << path;
    ::close(fd);
}

std::string with_dir(std::string s, const std::string& dir) {
    // Past each replacement: a temporary directory's random name may itself hold "DIR".
    for (std::size_t k = s.find("DIR"); k != std::string::npos; k = s.find("DIR", k + dir.size())) s.replace(k, 3, dir);
    return s;
}

TEST(Outputs, BadPathsAreRefusedBeforeTheRunAndNothingIsWritten) {
    const BadPath cases[] = {
        {"events names a directory", "--out DIR/out.csv --events DIR", "--events 'DIR': is a directory"},
        {"out names a directory", "--out DIR/sub/", "--out 'DIR/sub/': is a directory"},
        {"missing directory", "--out DIR/out.csv --events DIR/nope/ev.csv",
         "--events 'DIR/nope/ev.csv': directory 'DIR/nope' does not exist"},
        {"a file as directory", "--out DIR/out.csv --events DIR/file/ev.csv", "--events 'DIR/file/ev.csv'"},
        {"bad plot path", "--out DIR/out.csv --plot DIR/nope/p.png",
         "--plot 'DIR/nope/p.png': directory 'DIR/nope' does not exist"},
        {"out and events the same", "--out DIR/out.csv --events DIR/sub/../out.csv",
         "--out 'DIR/out.csv' and --events 'DIR/sub/../out.csv' are the same file"},
        {"plot equal to out", "--out DIR/out.csv --plot DIR/out.csv",
         "--out 'DIR/out.csv' and --plot 'DIR/out.csv' are the same file"},
        {"through a symbolic link", "--out DIR/link.csv --events DIR/existing.csv",
         "--out 'DIR/link.csv' and --events 'DIR/existing.csv' are the same file"},
        {"through a dangling link", "--out DIR/dangling.csv --events DIR/sub/new.csv",
         "--out 'DIR/dangling.csv': is a symbolic link to 'DIR/sub/new.csv', which does not exist"},
        {"a socket", "--out DIR/out.csv --events DIR/sock", "--events 'DIR/sock': is a socket"},
    };
    for (const BadPath& c : cases) {
        TempDir dir;
        fs::create_directory(dir / "sub");
        std::ofstream(dir / "file") << "x\n";
        std::ofstream(dir / "existing.csv") << "keep\n";
        ASSERT_EQ(::symlink("existing.csv", (dir / "link.csv").c_str()), 0);
        ASSERT_EQ(::symlink("sub/new.csv", (dir / "dangling.csv").c_str()), 0);
        bind_socket(dir / "sock");
        const auto before = dir.names();
        const auto r = run_hsnc("simulate " + q(model_path("coulomb-1dof.toml")) + " --t-end 1 --quiet " +
                                with_dir(c.args, dir.path()));
        EXPECT_EQ(r.exit_code, 2) << c.name << "\n" << r.err;
        EXPECT_NE(r.err.find(with_dir(c.message, dir.path())), std::string::npos) << c.name << "\n" << r.err;
        EXPECT_EQ(count_lines(r.err), 1u) << c.name << "\n" << r.err;
        EXPECT_EQ(r.out, "") << c.name;
        EXPECT_EQ(dir.names(), before) << c.name;  // nothing written, nothing left
        EXPECT_EQ(slurp(dir / "existing.csv"), "keep\n") << c.name;
        EXPECT_FALSE(file_exists(dir / "sub/new.csv")) << c.name;
    }
}

// A path that is this process's stdout (as /dev/stdout is) is written through
// the descriptor, whatever stdout is (here the file run_hsnc redirects it to).
// The path is a private link to /proc/self/fd/1, so that a faulty build could
// only replace that link, never the system's /dev/stdout.
TEST(Outputs, StdoutIsWrittenThroughItsDescriptor) {
    TempDir dir;
    ASSERT_EQ(::symlink("/proc/self/fd/1", (dir / "stdout").c_str()), 0);
    const auto r = run_hsnc("simulate " + q(model_path("coulomb-1dof.toml")) +
                            " --t-end 1 --dt 0.5 --quiet --out " + q(dir / "stdout"));
    ASSERT_EQ(r.exit_code, 0) << r.err;
    // The CSV (header and t = 0, 0.5, 1), then the summary line.
    EXPECT_EQ(r.out.rfind(kTrajHeader, 0), 0u) << r.out;
    EXPECT_EQ(count_lines(r.out), 1u + 3u + 1u) << r.out;
    EXPECT_NE(r.out.find("\nstatus=ok"), std::string::npos) << r.out;
    struct stat st;
    ASSERT_EQ(::lstat((dir / "stdout").c_str(), &st), 0);
    EXPECT_TRUE(S_ISLNK(st.st_mode));
}

// gnuplot's own output never reaches stdout; its diagnostics come trimmed on stderr.
TEST(Outputs, AFailingGnuplotWritesNothingOnStdout) {
    TempDir dir;
    fs::create_directory(dir / "bin");
    const std::string fake = dir / "bin/gnuplot";
    std::ofstream(fake) << "#!/bin/sh\ncat >/dev/null\nhead -c 60000 /dev/zero | tr '\\0' 'x'\n"
                           "for i in 1 2 3 4 5 6 7 8 9; do echo \"line $i: something went wrong\" >&2; done\nexit 1\n";
    ASSERT_EQ(::chmod(fake.c_str(), 0755), 0);
    const std::string png = dir / "plot.png", out = dir / "out.csv";
    const auto r = run_hsnc("simulate " + q(model_path("coulomb-1dof.toml")) + " --t-end 1 --quiet --out " + q(out) +
                                " --plot " + q(png),
                            "PATH=" + q(dir / "bin") + ":\"$PATH\"");
    EXPECT_EQ(r.exit_code, 1) << r.err;
    EXPECT_EQ(r.out, "");
    EXPECT_NE(r.err.find("--plot: gnuplot failed (exit status 1"), std::string::npos) << r.err;
    EXPECT_NE(r.err.find("gnuplot: line 1: something went wrong"), std::string::npos) << r.err;
    EXPECT_EQ(r.err.find("line 5"), std::string::npos) << r.err;  // trimmed
    EXPECT_LT(r.err.size(), 600u) << r.err;
    EXPECT_FALSE(file_exists(png));
    // All or nothing (issue 35): the complete CSV goes with the failed plot.
    EXPECT_FALSE(file_exists(out));
    EXPECT_EQ(dir.names(), std::vector<std::string>{"bin"});
}

// ---- 5. write errors, interrupts, runaway output ----

TEST(Outputs, AWriteErrorStopsAtTheFirstFailedWrite) {
    TempDir dir;
    const std::string full = device_node(dir, "full", 1, 7, "/dev/full");
    const Model model = read_model(model_path("coulomb-1dof.toml"));
    CsvFile csv(full);
    CsvObserver obs(model, &csv, nullptr);
    const double x = 0.125, v = -1.5;
    std::size_t rows = 0;
    try {
        for (; rows < 100000; ++rows) obs.on_sample(static_cast<double>(rows) * 1e-3, &x, &v);
        ADD_FAILURE() << "no error after " << rows << " rows";
    } catch (const RunError& e) {
        const std::string what = e.what();
        EXPECT_NE(what.find("'" + full + "'"), std::string::npos) << what;
        EXPECT_NE(what.find("No space left on device"), std::string::npos) << what;
    }
    // The first flush of the 64 kB buffer fails: about 2000 rows of ~30 bytes.
    EXPECT_LT(rows, 5000u);
    EXPECT_TRUE(is_char_device(full));
}

TEST(Outputs, AWriteErrorEndsTheRunWithExitOneAndNoTemporaryFile) {
    TempDir dir;
    const std::string full = device_node(dir, "full", 1, 7, "/dev/full");
    const std::string ev = dir / "events.csv";
    const auto before = dir.names();
    const auto r = run_hsnc("simulate " + q(model_path("coulomb-1dof.toml")) + " --t-end 1 --dt 1e-5 --quiet --out " +
                            q(full) + " --events " + q(ev));
    EXPECT_EQ(r.exit_code, 1) << r.err;
    EXPECT_NE(r.err.find("--out '" + full + "': write failed: No space left on device"), std::string::npos) << r.err;
    EXPECT_EQ(count_lines(r.err), 1u) << r.err;
    EXPECT_EQ(r.out, "");
    EXPECT_EQ(dir.names(), before);  // no events.csv, no temporary file
    EXPECT_TRUE(is_char_device(full));
}

TEST(Outputs, AVeryLargeTrajectoryNeedsAllowLargeOutput) {
    TempDir dir;
    const std::string out = dir / "out.csv";
    auto r = run_hsnc("simulate " + q(model_path("seed-scenario-2.toml")) + " --t-end 10 --dt 1e-9 --out " + q(out));
    EXPECT_EQ(r.exit_code, 2) << r.err;
    EXPECT_NE(r.err.find("--dt 1e-09: the trajectory --out would have 1e+10 rows, about 1.1 TB"), std::string::npos)
        << r.err;
    EXPECT_NE(r.err.find("--allow-large-output"), std::string::npos) << r.err;
    EXPECT_TRUE(dir.names().empty());
    // Just over the row limit (1e7 + 1 rows) is refused too.
    r = run_hsnc("simulate " + q(model_path("coulomb-1dof.toml")) + " --t-end 1000 --dt 1e-4 --out " + q(out));
    EXPECT_EQ(r.exit_code, 2) << r.err;
    EXPECT_TRUE(dir.names().empty());
    // With the flag it runs (stopped early here by --max-events, to keep the test short).
    r = run_hsnc("simulate " + q(model_path("coulomb-1dof.toml")) +
                 " --t-end 1000 --dt 1e-4 --allow-large-output --max-events 1 --quiet --out " + q(out));
    EXPECT_EQ(r.exit_code, 0) << r.err;
    EXPECT_NE(r.out.find("status=max_events"), std::string::npos) << r.out;
    EXPECT_GT(count_lines(slurp(out)), 3000u);  // rows up to the first reversal, near t = pi/10
}

TEST(Outputs, TheRowEstimateMatchesTheWrittenRows) {
    TempDir dir;
    const std::string out = dir / "out.csv";
    const auto r = run_hsnc("simulate " + q(model_path("coulomb-1dof.toml")) + " --t-end 0.95 --dt 0.1 --quiet --out " +
                            q(out));
    ASSERT_EQ(r.exit_code, 0) << r.err;
    EXPECT_EQ(static_cast<double>(count_lines(slurp(out)) - 1), trajectory_rows(0.0, 0.95, 0.1));
}

// A run interrupted by a signal removes its temporary files, says so, and
// ends by that signal (a shell reports 130 / 143).
void interrupt_test(int sig, const char* message) {
    TempDir dir;
    const std::string out = dir / "out.csv", err = dir / "stderr";
    const pid_t pid = testing::spawn_hsnc({"simulate", model_path("seed-scenario-2.toml"), "--t-end", "1e6", "--dt",
                                           "1e-4", "--allow-large-output", "--quiet", "--out", out},
                                          "/dev/null", err);
    ASSERT_GE(pid, 0);
    // Wait until the temporary file has data, then interrupt.
    bool started = false;
    for (int i = 0; i < 1000 && !started; ++i) {
        for (const std::string& n : dir.names())
            if (n.find("out.csv.tmp.") == 0 && fs::file_size(dir / n) > 0) started = true;
        if (!started) std::this_thread::sleep_for(std::chrono::milliseconds(10));
    }
    EXPECT_TRUE(started);
    ::kill(pid, sig);
    int status = 0;
    ASSERT_EQ(::waitpid(pid, &status, 0), pid);
    EXPECT_TRUE(WIFSIGNALED(status) && WTERMSIG(status) == sig) << status;
    EXPECT_EQ(dir.names(), std::vector<std::string>{"stderr"});
    EXPECT_EQ(slurp(err), message);
}

TEST(Outputs, SigintRemovesTheTemporaryFiles) {
    interrupt_test(SIGINT, "hsnc: interrupted (SIGINT): unfinished output files removed\n");
}

TEST(Outputs, SigtermRemovesTheTemporaryFiles) {
    interrupt_test(SIGTERM, "hsnc: terminated (SIGTERM): unfinished output files removed\n");
}

// ---- 10. silent non-runs and NaN ----

TEST(Outputs, FlagsThatWouldMakeASilentNonRunAreRefused) {
    const BadPath cases[] = {
        {"t-end nan", "--t-end nan", "--t-end: must be a finite number, not 'nan'"},
        {"dt nan", "--t-end 1 --dt nan", "--dt: must be a finite number, not 'nan'"},
        {"dt inf", "--t-end 1 --dt inf", "--dt: must be a finite number, not 'inf'"},
        {"h tiny", "--t-end 1 --method ab4 --h 1e-20", "--h 1e-20: more than 1e12 steps"},
        {"h huge", "--t-end 1 --method ab4 --h 1e300", "--h 1e+300: longer than the run"},
        {"h nan", "--t-end 1 --method ab4 --h nan", "--h: must be a finite number"},
        {"h negative", "--t-end 1 --method ab4 --h -1e-3", "--h -0.001: method ab4 needs a fixed step h > 0"},
        {"rtol nan", "--t-end 1 --method rk45 --rtol nan", "--rtol: must be a finite number"},
        {"atol inf", "--t-end 1 --method cvode --atol inf", "--atol: must be a finite number"},
        {"rtol 0, method hsnc", "--t-end 1 --rtol 0", "--rtol 0: must be finite and > 0"},
        {"atol negative, method hsnc", "--t-end 1 --atol -1", "--atol -1: must be finite and > 0"},
    };
    for (const BadPath& c : cases) {
        TempDir dir;
        const auto r = run_hsnc("simulate " + q(model_path("coulomb-1dof.toml")) + " --quiet --out " +
                                q(dir / "out.csv") + " " + c.args);
        EXPECT_EQ(r.exit_code, 2) << c.name << "\n" << r.err << r.out;
        EXPECT_NE(r.err.find(c.message), std::string::npos) << c.name << "\n" << r.err;
        EXPECT_EQ(r.out, "") << c.name;
        EXPECT_TRUE(dir.names().empty()) << c.name;
    }
}

TEST(Outputs, TheLibraryRefusesAnAb4StepThatCannotRun) {
    const Model model = read_model(model_path("coulomb-1dof.toml"));
    struct NullObserver : Observer {
        void on_sample(double, const double*, const double*) override {}
        void on_event(double, EventKind, int, const double*, const double*) override {}
    } obs;
    EngineOptions eo;
    eo.t_end = 1.0;
    eo.dt = 0.1;
    for (double h : {1e-20, 1e300, 2.0}) {
        IntegratorOptions io;
        io.h = h;
        EXPECT_THROW(integrate(model, Method::ab4, io, eo, obs), InputError) << h;
    }
    IntegratorOptions io;
    io.h = 1000.0;  // 1000 steps, but t + h == t at t = 1e20 (its ulp is 16384)
    EXPECT_THROW(validate(Method::ab4, io, 1e20, 1e20 + 1e6), InputError);
    io.h = 1.0;  // one step, the whole run
    EXPECT_EQ(integrate(model, Method::ab4, io, eo, obs).status, RunStatus::ok);
}

// ---- the figure ----

TEST(Outputs, PlotWithoutOutWritesOnlyThePng) {
    TempDir dir;
    const std::string png = dir / "plot.png";
    const auto r = run_hsnc("simulate " + q(model_path("seed-scenario-1.toml")) + " --t-end 2 --quiet --plot " + q(png));
    ASSERT_EQ(r.exit_code, 0) << r.err;
    EXPECT_EQ(dir.names(), std::vector<std::string>{"plot.png"});
    const std::string bytes = slurp(png);
    ASSERT_GT(bytes.size(), 1000u);
    EXPECT_EQ(bytes.substr(1, 3), "PNG");
}

// A chain of n masses (the figure's colours and legend depend on n), forced or not.
Model chain(int n, bool forced) {
    std::string toml = "name = \"chain\"\n";
    for (int i = 1; i <= n; ++i) toml += "[[mass]]\nname = \"m" + std::to_string(i) + "\"\nm = 1.0\nmu_k = 0.05\n";
    toml += "[[spring]]\nbetween = [\"ground\", \"m1\"]\nk = 100.0\n";
    for (int i = 1; i < n; ++i)
        toml += "[[spring]]\nbetween = [\"m" + std::to_string(i) + "\", \"m" + std::to_string(i + 1) + "\"]\nk = 100.0\n";
    toml += "[[contact]]\nbetween = [\"m1\", \"ground\"]\ngap = 0.05\nk = 1000.0\n";
    if (forced) toml += "[[forcing]]\nomega = 6.8\namplitude = { m1 = 40.0 }\n";
    TempDir dir;
    std::ofstream(dir / "chain.toml") << toml;
    return read_model(dir / "chain.toml");
}

TEST(Outputs, PlotScriptHasUnitsAZoomWindowAndEventMarks) {
    const Model m = chain(2, true);
    PlotRecorder rec(m, 0.0, 100.0, 0.01);
    const double x[2] = {0.01, -0.02}, v[2] = {0, 0};
    for (int k = 0; k <= 10000; ++k) rec.on_sample(k * 0.01, x, v);
    rec.on_event(99.5, EventKind::stick, 1, x, v);
    rec.on_event(1.0, EventKind::contact_close, 0, x, v);
    const std::string s = rec.script();
    EXPECT_NE(s.find("set xlabel 't [s]'"), std::string::npos);
    EXPECT_NE(s.find("set ylabel 'x [m]'"), std::string::npos);
    // The last 5 forcing periods: 5*2*pi/6.8 = 4.62 s.
    const double a = 100.0 - 5 * 2 * M_PI / 6.8;
    char range[64];
    std::snprintf(range, sizeof range, "t = %.6g .. 100 s", a);
    EXPECT_NE(s.find(std::string("'last 5 forcing periods, ") + range), std::string::npos) << s.substr(s.size() - 2000);
    // Ticks for the two kinds in the strip; only the stick in the zoom.
    EXPECT_NE(s.find("set ytics ('contact_close' 2, 'stick' 1)"), std::string::npos);
    EXPECT_NE(s.find("with points pt 7"), std::string::npos);  // stick
    EXPECT_EQ(s.find("with points pt 9"), std::string::npos);  // contact_close at t = 1, outside the zoom
    EXPECT_NE(s.find("title 'm1'"), std::string::npos);
    EXPECT_NE(s.find("title 'm2'"), std::string::npos);

    const Model free = chain(1, false);
    PlotRecorder rec1(free, 0.0, 20.0, 0.02);
    EXPECT_NE(rec1.script().find("'first 10% of the run, t = 0 .. 2 s'"), std::string::npos);
}

TEST(Outputs, PlotScriptColoursManyMassesAlongAScale) {
    for (int n : {8, 9, 64}) {
        const Model m = chain(n, true);
        PlotRecorder rec(m, 0.0, 10.0, 0.01);
        std::vector<double> x(static_cast<std::size_t>(n), 0.0);
        for (int k = 0; k <= 1000; ++k) rec.on_sample(k * 0.01, x.data(), x.data());
        const std::string s = rec.script();
        if (n <= 8) {
            EXPECT_EQ(s.find("palette"), std::string::npos) << n;
            EXPECT_NE(s.find("title 'm8'"), std::string::npos) << n;
        } else {
            EXPECT_NE(s.find("lc palette cb " + std::to_string(n) + " notitle"), std::string::npos) << n;
            EXPECT_NE(s.find("'m1' 1"), std::string::npos) << n;
            EXPECT_NE(s.find("'m" + std::to_string(n) + "' " + std::to_string(n) + ")"), std::string::npos) << n;
            EXPECT_EQ(s.find("title 'm1'"), std::string::npos) << n;  // no legend of 64 entries
        }
    }
}

// More samples than pixels: the min/max envelope keeps a single-sample spike.
TEST(Outputs, PlotEnvelopeKeepsExtremes) {
    const Model m = chain(1, false);
    PlotRecorder rec(m, 0.0, 100.0, 1e-4);
    for (int k = 0; k <= 1000000; ++k) {
        const double t = k * 1e-4;
        const double x = k == 123457 ? 7.25 : std::sin(t), v = 0;
        rec.on_sample(t, &x, &v);
    }
    const std::string s = rec.script();
    EXPECT_NE(s.find("(min/max envelope of the samples)"), std::string::npos);
    EXPECT_NE(s.find(" 7.25\n"), std::string::npos);
    EXPECT_LT(s.size(), 400000u);  // bounded by the buckets, not the samples
}

TEST(Outputs, PlotsOfOneTwoEightAndSixtyFourMassesRender) {
    TempDir dir;
    for (int n : {1, 2, 8, 64}) {
        const Model m = chain(n, true);
        PlotRecorder rec(m, 0.0, 10.0, 0.01);
        std::vector<double> x(static_cast<std::size_t>(n));
        for (int k = 0; k <= 1000; ++k) {
            for (int i = 0; i < n; ++i) x[static_cast<std::size_t>(i)] = std::sin(0.1 * k + i);
            rec.on_sample(k * 0.01, x.data(), x.data());
            if (k % 97 == 0) rec.on_event(k * 0.01, EventKind::reversal, k % n, x.data(), x.data());
        }
        const std::string png = dir / ("plot" + std::to_string(n) + ".png");
        rec.draw(check_output("--plot", png));
        const std::string bytes = slurp(png);
        ASSERT_GT(bytes.size(), 10000u) << n;
        EXPECT_EQ(bytes.substr(1, 3), "PNG") << n;
    }
}

}  // namespace
}  // namespace hsnc
