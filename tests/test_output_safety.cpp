// What no output may do (issue 35, items 1-3): write through a symbolic link
// another user planted in a shared sticky directory, create a file through a
// dangling link, replace one of the run's own input files, or stay behind
// when another output of the same run failed.
#include <gtest/gtest.h>
#include <sys/stat.h>
#include <sys/sysmacros.h>
#include <unistd.h>

#include <algorithm>
#include <filesystem>
#include <fstream>
#include <string>
#include <vector>

#include "cli_runner.h"
#include "temp_dir.h"
#include "error.h"
#include "input_files.h"
#include "output_file.h"

namespace hsnc {
namespace {

using testing::model_path;
using testing::run_hsnc;
using testing::slurp;
namespace fs = std::filesystem;

using testing::TempDir;

std::string q(const std::string& s) { return "'" + s + "'"; }

std::string simulate_to(const std::string& flags) {
    return "simulate " + q(model_path("coulomb-1dof.toml")) + " --t-end 1 --quiet " + flags;
}

constexpr uid_t kOtherUser = 65534;  // nobody

// A sticky world-writable directory (as /tmp) inside the test's directory.
// Planting a link owned by another user needs root (lchown); without it the
// planted-link tests are skipped.
struct SharedDir {
    TempDir dir;
    std::string shared = dir / "shared";
    SharedDir() {
        fs::create_directory(shared);
        ::chmod(shared.c_str(), 01777);
        std::ofstream(dir / "victim.csv") << "keep\n";
        ::chmod((dir / "victim.csv").c_str(), 0644);
    }
    // A link at shared/NAME -> target, owned by `uid`; false when it cannot be.
    bool plant(const std::string& name, const std::string& target, uid_t uid) const {
        const std::string link = shared + "/" + name;
        return ::symlink(target.c_str(), link.c_str()) == 0 && ::lchown(link.c_str(), uid, uid) == 0;
    }
};

// ---- 1. planted links ----

TEST(OutputSafety, PlantedLinkInAStickyDirectoryIsNotFollowed) {
    if (::geteuid() != 0) GTEST_SKIP() << "planting another user's link needs root";
    SharedDir s;
    ASSERT_TRUE(s.plant("run.csv", s.dir / "victim.csv", kOtherUser));
    const auto r = run_hsnc(simulate_to("--out " + q(s.shared + "/run.csv")));
    EXPECT_EQ(r.exit_code, 2) << r.err;
    EXPECT_NE(r.err.find("symbolic link in the shared directory"), std::string::npos) << r.err;
    EXPECT_NE(r.err.find("owned by another user"), std::string::npos) << r.err;
    EXPECT_EQ(slurp(s.dir / "victim.csv"), "keep\n");  // not replaced
    EXPECT_EQ(s.dir.names("shared"), std::vector<std::string>{"run.csv"});
}

TEST(OutputSafety, PlantedDanglingLinkCreatesNoFile) {
    if (::geteuid() != 0) GTEST_SKIP() << "planting another user's link needs root";
    SharedDir s;
    ASSERT_TRUE(s.plant("events.csv", s.dir / "created-by-root.csv", kOtherUser));
    const auto r = run_hsnc(simulate_to("--events " + q(s.shared + "/events.csv")));
    EXPECT_EQ(r.exit_code, 2) << r.err;
    EXPECT_FALSE(fs::exists(s.dir / "created-by-root.csv"));
}

// A link deeper in the path (a planted directory link) is checked the same way.
TEST(OutputSafety, PlantedDirectoryLinkIsNotFollowed) {
    if (::geteuid() != 0) GTEST_SKIP() << "planting another user's link needs root";
    SharedDir s;
    fs::create_directory(s.dir / "private");
    ASSERT_TRUE(s.plant("d", s.dir / "private", kOtherUser));
    const auto r = run_hsnc(simulate_to("--out " + q(s.shared + "/d/run.csv")));
    EXPECT_EQ(r.exit_code, 2) << r.err;
    EXPECT_NE(r.err.find("owned by another user"), std::string::npos) << r.err;
    EXPECT_TRUE(s.dir.names("private").empty());
}

// What protected_symlinks allows is allowed: the caller's own link, and a
// link owned by the directory's owner.
TEST(OutputSafety, OwnLinksInAStickyDirectoryAreFollowed) {
    SharedDir s;
    ASSERT_TRUE(s.plant("mine.csv", s.dir / "victim.csv", ::geteuid()));
    const auto r = run_hsnc(simulate_to("--out " + q(s.shared + "/mine.csv")));
    ASSERT_EQ(r.exit_code, 0) << r.err;
    EXPECT_EQ(slurp(s.dir / "victim.csv").rfind("t,x_m1,v_m1\n", 0), 0u);

    if (::geteuid() != 0) return;
    ASSERT_EQ(::chown(s.shared.c_str(), kOtherUser, kOtherUser), 0);
    std::ofstream(s.dir / "second.csv") << "old\n";
    ASSERT_TRUE(s.plant("owner.csv", s.dir / "second.csv", kOtherUser));  // the directory's owner's link
    const auto o = run_hsnc(simulate_to("--out " + q(s.shared + "/owner.csv")));
    ASSERT_EQ(o.exit_code, 0) << o.err;
    EXPECT_EQ(slurp(s.dir / "second.csv").rfind("t,x_m1,v_m1\n", 0), 0u);
}

TEST(OutputSafety, NoFileIsCreatedThroughADanglingLink) {
    TempDir dir;
    ASSERT_EQ(::symlink("sub/new.csv", (dir / "dangling.csv").c_str()), 0);
    fs::create_directory(dir / "sub");
    const auto r = run_hsnc(simulate_to("--out " + q(dir / "dangling.csv")));
    EXPECT_EQ(r.exit_code, 2) << r.err;
    EXPECT_NE(r.err.find("dangling link"), std::string::npos) << r.err;
    EXPECT_TRUE(dir.names("sub").empty());
}

TEST(OutputSafety, APathWithANulIsRefused) {
    EXPECT_THROW(check_output("--out", std::string("a\0b.csv", 7)), InputError);
}

// ---- 2. an output never names an input ----

struct Inputs {
    TempDir dir;
    std::string model = dir / "model.toml";
    Inputs() { fs::copy_file(model_path("coulomb-1dof.toml"), model); }
    void expect_refused_and_kept(const testing::CliRun& r, const std::string& what) const {
        EXPECT_EQ(r.exit_code, 2) << what << "\n" << r.err;
        EXPECT_NE(r.err.find("is the input file"), std::string::npos) << what << "\n" << r.err;
        EXPECT_EQ(slurp(model), slurp(model_path("coulomb-1dof.toml"))) << what;
    }
};

TEST(OutputSafety, AnOutputNamingTheModelIsRefused) {
    Inputs in;
    const std::string m = q(in.model);
    in.expect_refused_and_kept(run_hsnc("simulate " + m + " --t-end 1 --quiet --out " + m), "simulate --out");
    in.expect_refused_and_kept(run_hsnc("simulate " + m + " --t-end 1 --quiet --events " + m), "simulate --events");
    in.expect_refused_and_kept(run_hsnc("lyapunov " + m + " --t-end 1 --quiet --out " + m), "lyapunov --out");
    in.expect_refused_and_kept(run_hsnc("periodic " + m + " --quiet --multipliers " + m), "periodic --multipliers");
    // Other names for the same file: a hard link, a symbolic link, a path through "..".
    ASSERT_EQ(::link(in.model.c_str(), (in.dir / "hard.toml").c_str()), 0);
    ASSERT_EQ(::symlink("model.toml", (in.dir / "soft.toml").c_str()), 0);
    fs::create_directory(in.dir / "sub");
    for (const std::string other : {"hard.toml", "soft.toml", "sub/../model.toml"})
        in.expect_refused_and_kept(run_hsnc("simulate " + m + " --t-end 1 --quiet --out " + q(in.dir / other)), other);
}

TEST(OutputSafety, AnOutputNamingASweepInputIsRefused) {
    Inputs in;
    std::ofstream(in.model) << "name = \"h\"\n[parameters]\nomega = 1.0\n[[mass]]\nname = \"m\"\nm = 1.0\n"
                               "[[spring]]\nbetween = [\"ground\", \"m\"]\nk = 1.0\n[damping]\nalpha = 0.04\n"
                               "[[forcing]]\nomega = \"omega\"\namplitude = { m = 0.1 }\n";
    const std::string original = slurp(in.model);
    const std::string args = "sweep " + q(in.model) + " --param omega --from 1 --to 1.2 --points 2 --max-periods 20 "
                             "--record-periods 2 --quiet ";
    for (const std::string flag : {"--out", "--diagram"}) {
        const auto r = run_hsnc(args + flag + " " + q(in.model));
        EXPECT_EQ(r.exit_code, 2) << flag << r.err;
        EXPECT_EQ(slurp(in.model), original) << flag;
    }
    const auto part = run_hsnc(args + "--part 1/2 --part-out " + q(in.model));
    EXPECT_EQ(part.exit_code, 2) << part.err;
    EXPECT_EQ(slurp(in.model), original);

    // sweep-merge p1 p2 --out p1
    const std::string p1 = in.dir / "p1.txt", p2 = in.dir / "p2.txt";
    ASSERT_EQ(run_hsnc(args + "--part 1/2 --part-out " + q(p1)).exit_code, 0);
    ASSERT_EQ(run_hsnc(args + "--part 2/2 --part-out " + q(p2)).exit_code, 0);
    const std::string part1 = slurp(p1);
    const auto m = run_hsnc("sweep-merge " + q(p1) + " " + q(p2) + " --out " + q(p1));
    EXPECT_EQ(m.exit_code, 2) << m.err;
    EXPECT_NE(m.err.find("is the input file"), std::string::npos) << m.err;
    EXPECT_EQ(slurp(p1), part1);
}

TEST(OutputSafety, AnOutputNamingAStructureMatrixIsRefused) {
    TempDir dir;
    for (const char* f : {"beam-crack.toml", "M.mtx", "K.mtx", "C.mtx"})
        fs::copy_file(std::string(HSNC_SOURCE_DIR) + "/examples/beam-crack/" + f, dir / f);
    const std::string k = slurp(dir / "K.mtx");
    const auto r = run_hsnc("simulate " + q(dir / "beam-crack.toml") + " --t-end 0.1 --quiet --out " + q(dir / "K.mtx"));
    EXPECT_EQ(r.exit_code, 2) << r.err;
    EXPECT_NE(r.err.find("is the input file"), std::string::npos) << r.err;
    EXPECT_EQ(slurp(dir / "K.mtx"), k);
}

// Outside a scope (a library user, Python) nothing is remembered.
TEST(OutputSafety, InputsAreRememberedOnlyInsideAScope) {
    TempDir dir;
    const std::string f = dir / "in.toml";
    std::ofstream(f) << "x\n";
    note_input_file(f);
    EXPECT_NO_THROW(check_output("--out", f));
    {
        InputFileScope scope;
        note_input_file(f);
        EXPECT_THROW(check_output("--out", f), InputError);
    }
    EXPECT_NO_THROW(check_output("--out", f));
}

// ---- 3. all outputs or none ----

// A character device that fails every write (as /dev/full): a private node
// when root can make one, else the system's.
std::string full_device(const TempDir& dir) {
    const std::string p = dir / "full";
    if (::mknod(p.c_str(), S_IFCHR | 0666, makedev(1, 7)) == 0) return p;
    return "/dev/full";
}

TEST(OutputSafety, AFailedOutputLeavesNoOtherOutput) {
    TempDir dir;
    const std::string full = full_device(dir);
    std::ofstream(dir / "old.csv") << "old\n";
    struct Case {
        const char* name;
        std::string flags;
    };
    const Case cases[] = {
        {"events fails", "--out " + q(dir / "new.csv") + " --events " + q(full)},
        {"events fails, out replaces", "--out " + q(dir / "old.csv") + " --events " + q(full)},
        {"out fails", "--out " + q(full) + " --events " + q(dir / "new.csv")},
        {"plot fails", "--out " + q(dir / "new.csv") + " --events " + q(dir / "old.csv") + " --plot " + q(full)},
    };
    for (const Case& c : cases) {
        const auto r = run_hsnc(simulate_to(c.flags));
        EXPECT_EQ(r.exit_code, 1) << c.name << "\n" << r.err;
        EXPECT_FALSE(fs::exists(dir / "new.csv")) << c.name;
        EXPECT_EQ(slurp(dir / "old.csv"), "old\n") << c.name;
        for (const std::string& n : dir.names()) EXPECT_EQ(n.find(".tmp"), std::string::npos) << c.name << ": " << n;
    }
}

TEST(OutputSafety, ASweepWhoseDiagramFailsLeavesNoCurve) {
    TempDir dir;
    const std::string full = full_device(dir);
    const std::string model = dir / "h.toml";
    std::ofstream(model) << "name = \"h\"\n[parameters]\nomega = 1.0\n[[mass]]\nname = \"m\"\nm = 1.0\n"
                            "[[spring]]\nbetween = [\"ground\", \"m\"]\nk = 1.0\n[damping]\nalpha = 0.04\n"
                            "[[forcing]]\nomega = \"omega\"\namplitude = { m = 0.1 }\n";
    std::ofstream(dir / "curve.csv") << "old\n";
    const auto r = run_hsnc("sweep " + q(model) + " --param omega --from 1 --to 1.2 --points 2 --max-periods 20 "
                            "--record-periods 2 --quiet --out " + q(dir / "curve.csv") + " --diagram " + q(full));
    EXPECT_EQ(r.exit_code, 1) << r.err;
    EXPECT_EQ(slurp(dir / "curve.csv"), "old\n");
}

// The transaction itself: nothing is renamed before commit(), everything after.
TEST(OutputSafety, TransactionRenamesOnlyOnCommit) {
    TempDir dir;
    std::ofstream(dir / "a.csv") << "old a\n";
    {
        OutputTransaction t;
        OutputFile a(check_output("--a", dir / "a.csv"));
        a.write("new a\n", 6);
        a.commit();
        OutputFile b(check_output("--b", dir / "b.csv"));
        b.write("new b\n", 6);
        b.commit();
        EXPECT_EQ(t.pending(), 2u);
        EXPECT_EQ(slurp(dir / "a.csv"), "old a\n");
        EXPECT_FALSE(fs::exists(dir / "b.csv"));
    }  // not committed: both dropped
    EXPECT_EQ(slurp(dir / "a.csv"), "old a\n");
    EXPECT_EQ(dir.names(), std::vector<std::string>{"a.csv"});
    {
        OutputTransaction t;
        OutputFile a(check_output("--a", dir / "a.csv"));
        a.write("new a\n", 6);
        a.commit();
        t.commit();
    }
    EXPECT_EQ(slurp(dir / "a.csv"), "new a\n");
    EXPECT_EQ(dir.names(), std::vector<std::string>{"a.csv"});
}

}  // namespace
}  // namespace hsnc
