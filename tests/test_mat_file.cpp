// [structure] matrices from MATLAB .mat files (model/mat_file.h): the beam
// example's M, K, C written with libmatio (dense, and K sparse) must give the
// model its Matrix Market files give, bit for bit; bad variables are refused
// by file, variable and reason.
#include <gtest/gtest.h>

#include <sys/resource.h>
#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <chrono>
#include <cstdint>
#include <filesystem>
#include <fstream>
#include <string>
#include <vector>

#include "cli_runner.h"
#include "engine_runner.h"
#include "error.h"
#include "mat_file.h"
#include "matrix_market.h"
#include "model_reader.h"

#if HSNC_WITH_MATIO
#include <matio.h>
#endif

namespace hsnc {
namespace {

namespace fs = std::filesystem;

#if HSNC_WITH_MATIO

const std::string kBeam = std::string(HSNC_SOURCE_DIR) + "/examples/beam-crack/";

class MatFolder : public ::testing::Test {
protected:
    void SetUp() override {
        dir_ = fs::path(::testing::TempDir()) /
               ("hsnc_mat_" + std::to_string(::getpid()) + "_" +
                ::testing::UnitTest::GetInstance()->current_test_info()->name());
        fs::remove_all(dir_);
        fs::create_directories(dir_);
    }
    void TearDown() override { fs::remove_all(dir_); }
    std::string path(const std::string& name) const { return (dir_ / name).string(); }
    fs::path dir_;
};

// Variables of one .mat file: dense (column-major) or sparse (CSC) doubles.
struct Writer {
    explicit Writer(const std::string& file, mat_ft version = MAT_FT_MAT5, matio_compression z = MAT_COMPRESSION_NONE)
        : mat(Mat_CreateVer(file.c_str(), nullptr, version)), compression(z) {}
    ~Writer() { Mat_Close(mat); }
    void dense(const char* name, const MarketMatrix& A) {
        std::vector<double> col(A.rows * A.cols);
        for (std::size_t i = 0; i < A.rows; ++i)
            for (std::size_t j = 0; j < A.cols; ++j) col[j * A.rows + i] = A(i, j);
        std::size_t dims[2] = {A.rows, A.cols};
        matvar_t* v = Mat_VarCreate(name, MAT_C_DOUBLE, MAT_T_DOUBLE, 2, dims, col.data(), 0);
        Mat_VarWrite(mat, v, compression);
        Mat_VarFree(v);
    }
    void sparse(const char* name, const MarketMatrix& A) {
        std::vector<mat_uint32_t> ir, jc{0};
        std::vector<double> data;
        for (std::size_t j = 0; j < A.cols; ++j) {
            for (std::size_t i = 0; i < A.rows; ++i)
                if (A(i, j) != 0.0) ir.push_back(static_cast<mat_uint32_t>(i)), data.push_back(A(i, j));
            jc.push_back(static_cast<mat_uint32_t>(ir.size()));
        }
        mat_sparse_t s{};
        s.nzmax = static_cast<mat_uint32_t>(data.size());
        s.ir = ir.data();
        s.nir = static_cast<mat_uint32_t>(ir.size());
        s.jc = jc.data();
        s.njc = static_cast<mat_uint32_t>(jc.size());
        s.ndata = static_cast<mat_uint32_t>(data.size());
        s.data = data.data();
        std::size_t dims[2] = {A.rows, A.cols};
        matvar_t* v = Mat_VarCreate(name, MAT_C_SPARSE, MAT_T_DOUBLE, 2, dims, &s, MAT_F_DONT_COPY_DATA);
        Mat_VarWrite(mat, v, compression);
        Mat_VarFree(v);
    }
    mat_t* mat;
    matio_compression compression;
};

std::string beam_toml(const std::string& mass, const std::string& stiffness, const std::string& damping) {
    std::ifstream in(kBeam + "beam-crack.toml");
    std::string t((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
    auto swap = [&](const std::string& from, const std::string& to) { t.replace(t.find(from), from.size(), to); };
    swap("mass = \"M.mtx\"", "mass = \"" + mass + "\"");
    swap("stiffness = \"K.mtx\"", "stiffness = \"" + stiffness + "\"");
    swap("damping = \"C.mtx\"", "damping = \"" + damping + "\"");
    return t;
}

TEST_F(MatFolder, TheBeamFromMatFilesIsTheBeamFromMatrixMarket) {
    const MarketMatrix M = read_matrix_market(kBeam + "M.mtx"), K = read_matrix_market(kBeam + "K.mtx"),
                       C = read_matrix_market(kBeam + "C.mtx");
    {
        Writer w(path("beam.mat"));
        w.dense("M", M);
        w.dense("K", K);
        w.dense("C", C);
        w.sparse("Ks", K);
        w.sparse("Ms", M);
    }
    const Model ref = read_model(kBeam + "beam-crack.toml");
    for (const auto& [mass, stiff] : {std::pair<std::string, std::string>{"beam.mat", "beam.mat"},
                                      {"beam.mat:Ms", "beam.mat:Ks"}}) {
        std::ofstream(path("b.toml")) << beam_toml(mass, stiff, "beam.mat");
        const Model m = read_model(path("b.toml"));
        ASSERT_EQ(m.springs.size(), ref.springs.size()) << mass;
        for (std::size_t s = 0; s < m.springs.size(); ++s) EXPECT_EQ(m.springs[s].k, ref.springs[s].k);
        for (std::size_t i = 0; i < m.dof(); ++i) EXPECT_EQ(m.masses[i].m, ref.masses[i].m);
        EXPECT_EQ(m.alpha, ref.alpha);
        EXPECT_EQ(m.beta, ref.beta);
        const testing::Outcome a = testing::simulate(ref, 3.0), b = testing::simulate(m, 3.0);
        ASSERT_EQ(a.events.size(), b.events.size());
        ASSERT_GT(a.events.size(), 3u);
        for (std::size_t e = 0; e < a.events.size(); ++e) EXPECT_EQ(a.events[e].t, b.events[e].t);
    }
}

void expect_error(const std::string& toml_path, const std::string& needle) {
    try {
        read_model(toml_path);
        ADD_FAILURE() << "no error, expected: " << needle;
    } catch (const InputError& e) {
        EXPECT_NE(std::string(e.what()).find(needle), std::string::npos) << e.what();
        EXPECT_NE(std::string(e.what()).find("key 'structure."), std::string::npos) << e.what();
    }
}

TEST_F(MatFolder, BadVariablesAreRefusedByFileVariableAndReason) {
    const MarketMatrix M = read_matrix_market(kBeam + "M.mtx"), K = read_matrix_market(kBeam + "K.mtx");
    {
        Writer w(path("bad.mat"));
        w.dense("M", M);
        w.dense("K", K);
        std::size_t dims3[3] = {2, 2, 2};
        double cube[8] = {1, 2, 3, 4, 5, 6, 7, 8};
        matvar_t* v = Mat_VarCreate("cube", MAT_C_DOUBLE, MAT_T_DOUBLE, 3, dims3, cube, 0);
        Mat_VarWrite(w.mat, v, MAT_COMPRESSION_NONE);
        Mat_VarFree(v);
        std::size_t dims[2] = {5, 5};
        std::vector<double> re(25, 1.0), im(25, 0.5);
        mat_complex_split_t z{re.data(), im.data()};
        v = Mat_VarCreate("Z", MAT_C_DOUBLE, MAT_T_DOUBLE, 2, dims, &z, MAT_F_COMPLEX);
        Mat_VarWrite(w.mat, v, MAT_COMPRESSION_NONE);
        Mat_VarFree(v);
        std::vector<float> single(25, 1.0f);
        v = Mat_VarCreate("S", MAT_C_SINGLE, MAT_T_SINGLE, 2, dims, single.data(), 0);
        Mat_VarWrite(w.mat, v, MAT_COMPRESSION_NONE);
        Mat_VarFree(v);
        std::vector<double> nan(25, 0.0);
        nan[7] = std::nan("");
        v = Mat_VarCreate("N", MAT_C_DOUBLE, MAT_T_DOUBLE, 2, dims, nan.data(), 0);
        Mat_VarWrite(w.mat, v, MAT_COMPRESSION_NONE);
        Mat_VarFree(v);
    }
    fs::copy_file(kBeam + "C.mtx", path("C.mtx"));
    auto model = [&](const std::string& stiffness) {
        std::ofstream(path("b.toml")) << beam_toml("bad.mat", stiffness, "C.mtx");
        return path("b.toml");
    };
    expect_error(model("bad.mat:KK"), "bad.mat:KK: the file has no variable 'KK'");
    expect_error(model("bad.mat:cube"), "bad.mat:cube: a 3-dimensional array, expected a matrix");
    expect_error(model("bad.mat:Z"), "bad.mat:Z: complex, expected a real matrix");
    expect_error(model("bad.mat:S"), "bad.mat:S: expected a real double matrix");
    expect_error(model("bad.mat:N"), "bad.mat:N: entry (3, 2) = nan is not a finite normal double");
    expect_error(model("missing.mat"), "cannot read matrix file");
    std::ofstream(path("text.mat")) << "not a mat file\n";
    expect_error(model("text.mat"), "text.mat");
    fs::create_directories(path("dir.mat"));
    expect_error(model("dir.mat"), "cannot read matrix file");
}

std::string bytes_of(const std::string& file) {
    std::ifstream in(file, std::ios::binary);
    return std::string((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
}

void write_bytes(const std::string& file, const std::string& bytes) {
    std::ofstream(file, std::ios::binary | std::ios::trunc) << bytes;
}

/// The message of read_mat_variable(file, variable), or "" (with a failure) when it reads.
std::string mat_error(const std::string& file, const std::string& variable) {
    try {
        read_mat_variable(file, variable);
    } catch (const InputError& e) {
        return e.what();
    }
    ADD_FAILURE() << file << ":" << variable << " was read";
    return "";
}

// libmatio reads a variable cut short by the end of the file as zeros (K = 0,
// or half its couplings) and says nothing: every cut of the compressed
// default, of an uncompressed file (sparse and dense) and of a version 7.3
// (HDF5) file is refused, naming the file and the variable.
TEST_F(MatFolder, TruncatedFilesAreRefusedNamingFileAndVariable) {
    const MarketMatrix K = read_matrix_market(kBeam + "K.mtx");
    struct Kind {
        const char* name;
        mat_ft version;
        matio_compression compression;
        bool sparse;
    };
    for (const Kind& kind : {Kind{"zlib.mat", MAT_FT_MAT5, MAT_COMPRESSION_ZLIB, false},
                             Kind{"zlib-sparse.mat", MAT_FT_MAT5, MAT_COMPRESSION_ZLIB, true},
                             Kind{"plain.mat", MAT_FT_MAT5, MAT_COMPRESSION_NONE, false},
                             Kind{"plain-sparse.mat", MAT_FT_MAT5, MAT_COMPRESSION_NONE, true},
                             Kind{"hdf5.mat", MAT_FT_MAT73, MAT_COMPRESSION_NONE, false}}) {
        const std::string whole = path(kind.name);
        {
            Writer w(whole, kind.version, kind.compression);
            ASSERT_NE(w.mat, nullptr) << kind.name;
            kind.sparse ? w.sparse("K", K) : w.dense("K", K);
        }
        const MarketMatrix read = read_mat_variable(whole, "K");  // the whole file reads, bit for bit
        ASSERT_EQ(read.values, K.values) << kind.name;
        const std::string bytes = bytes_of(whole);
        const std::size_t size = bytes.size();
        for (const std::size_t cut : {std::size_t{1}, std::size_t{7}, std::size_t{8}, std::size_t{100}, size / 2,
                                      size - 200, size - 130, size - 100}) {
            const std::string cut_file = path(std::string("cut-") + kind.name);
            write_bytes(cut_file, bytes.substr(0, size - cut));
            const std::string message = mat_error(cut_file, "K");
            EXPECT_NE(message.find(cut_file + ":K: "), std::string::npos) << kind.name << " cut " << cut << ": " << message;
            EXPECT_NE(message.find("truncated"), std::string::npos) << kind.name << " cut " << cut << ": " << message;
        }
    }
    // Through a model: exit with the key, the file and the variable.
    {
        Writer w(path("beam.mat"), MAT_FT_MAT5, MAT_COMPRESSION_ZLIB);
        w.dense("K", K);
    }
    const std::string bytes = bytes_of(path("beam.mat"));
    write_bytes(path("beam.mat"), bytes.substr(0, bytes.size() - 8));
    fs::copy_file(kBeam + "M.mtx", path("M.mtx"));
    fs::copy_file(kBeam + "C.mtx", path("C.mtx"));
    std::ofstream(path("b.toml")) << beam_toml("M.mtx", "beam.mat", "C.mtx");
    const testing::CliRun r = testing::run_hsnc("check '" + path("b.toml") + "'");
    EXPECT_EQ(r.exit_code, 2) << r.out;
    EXPECT_EQ(r.out, "");
    EXPECT_NE(r.err.find("key 'structure.stiffness': " + path("beam.mat") + ":K: the file is truncated"),
              std::string::npos)
        << r.err;
    EXPECT_EQ(std::count(r.err.begin(), r.err.end(), '\n'), 1) << r.err;
}

/// The peak resident memory (bytes) that `work` adds, run in a child process,
/// and whether it threw an InputError whose message holds `needle` (exit 0) ...
struct ChildRun {
    int exit_code = -1;
    long added_kb = 0;
    double seconds = 0;
};

template <class Work>
ChildRun in_child(Work work) {
    struct rusage self {};
    ::getrusage(RUSAGE_SELF, &self);  // the child starts with the parent's pages
    const auto start = std::chrono::steady_clock::now();
    const pid_t pid = ::fork();
    if (pid == 0) ::_exit(work());
    int status = 0;
    struct rusage child {};
    ::wait4(pid, &status, 0, &child);
    ChildRun r;
    r.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
    r.exit_code = WIFEXITED(status) ? WEXITSTATUS(status) : -1;
    r.added_kb = child.ru_maxrss - self.ru_maxrss;
    return r;
}

// A small file whose header claims large dimensions is refused from its header,
// before libmatio allocates and reads the data (it read a 1.1 MB file into
// 1.14 GB): beyond the dimension limit, and within it but more doubles than
// the file can hold.
TEST_F(MatFolder, AHeaderClaimingHugeDimensionsIsRefusedBeforeReading) {
    MarketMatrix A;
    A.rows = A.cols = 20;
    A.values.assign(400, 1.0);
    {
        Writer w(path("small.mat"));
        w.dense("A", A);
    }
    const std::string bytes = bytes_of(path("small.mat"));
    // The dimensions subelement of the first variable: tag (miINT32, 8 bytes) at byte 152, then rows, cols.
    ASSERT_EQ(bytes.substr(160, 8), std::string("\x14\0\0\0\x14\0\0\0", 8));
    auto with_dims = [&](std::uint32_t rows, std::uint32_t cols) {
        std::string b = bytes;
        for (int k = 0; k < 4; ++k) {
            b[160 + k] = static_cast<char>(rows >> (8 * k));
            b[164 + k] = static_cast<char>(cols >> (8 * k));
        }
        const std::string file = path("claims-" + std::to_string(rows) + "x" + std::to_string(cols) + ".mat");
        write_bytes(file, b);
        return file;
    };
    const std::string huge = with_dims(9000, 9000), wide = with_dims(20, 2000000), fits = with_dims(300, 300);
    for (const auto& [file, needle] : {std::pair<std::string, std::string>{huge, ":A: 9000 x 9000 exceeds"},
                                       {wide, ":A: 20 x 2000000 exceeds"},
                                       {fits, ":A: the header says 300 x 300 (720000 bytes of doubles), more than"}}) {
        const ChildRun r = in_child([&] {
            try {
                read_mat_variable(file, "A");
            } catch (const InputError& e) {
                return std::string(e.what()).find(file + needle) != std::string::npos ? 0 : 3;
            }
            return 4;
        });
        EXPECT_EQ(r.exit_code, 0) << file << " (3: another message, 4: read)";
        EXPECT_LT(r.added_kb, 64 * 1024) << file;
        EXPECT_LT(r.seconds, 5.0) << file;
        if (r.exit_code != 0) std::cerr << mat_error(file, "A") << "\n";
    }
}

// A version 7.3 header on a file that is no HDF5 file: one message, not
// HDF5's 14-line error stack on stderr.
TEST_F(MatFolder, AVersion73HeaderOnAnotherFileGivesOneMessage) {
    std::string header = "MATLAB 7.3 MAT-file, Platform: GLNXA64, Created on: Mon Jan  1 00:00:00 2024 HDF5 schema 1.00 .";
    header.resize(116, ' ');
    header += std::string(8, ' ') + std::string("\x00\x02", 2) + "IM";
    write_bytes(path("fake.mat"), header + std::string(2000, 'x'));
    fs::copy_file(kBeam + "M.mtx", path("M.mtx"));
    fs::copy_file(kBeam + "C.mtx", path("C.mtx"));
    std::ofstream(path("b.toml")) << beam_toml("M.mtx", "fake.mat", "C.mtx");
    const testing::CliRun r = testing::run_hsnc("check '" + path("b.toml") + "'");
    EXPECT_EQ(r.exit_code, 2) << r.out;
    EXPECT_EQ(r.out, "");
    EXPECT_NE(r.err.find(path("fake.mat") + ":K: a MATLAB version 7.3 header, but not an HDF5 file"), std::string::npos)
        << r.err;
    EXPECT_EQ(std::count(r.err.begin(), r.err.end(), '\n'), 1) << r.err;
    EXPECT_EQ(r.err.find("HDF5-DIAG"), std::string::npos) << r.err;
    // An HDF5 signature where HDF5 looks, the rest damaged: HDF5 cannot open it, still one message.
    std::string damaged = header + std::string(512 - 128, ' ') + "\x89HDF\r\n\x1a\n" + std::string(2000, '\x01');
    write_bytes(path("fake.mat"), damaged);
    const testing::CliRun d = testing::run_hsnc("check '" + path("b.toml") + "'");
    EXPECT_EQ(d.exit_code, 2) << d.out;
    EXPECT_NE(d.err.find(path("fake.mat") + ":K: a MATLAB version 7.3 file that HDF5 cannot open"), std::string::npos)
        << d.err;
    EXPECT_EQ(std::count(d.err.begin(), d.err.end(), '\n'), 1) << d.err;
}

#else

TEST(MatFile, NotBuilt) { GTEST_SKIP() << "built without HSNC_WITH_MATIO"; }

#endif

}  // namespace
}  // namespace hsnc
