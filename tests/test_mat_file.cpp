// [structure] matrices from MATLAB .mat files (model/mat_file.h): the beam
// example's M, K, C written with libmatio (dense, and K sparse) must give the
// model its Matrix Market files give, bit for bit; bad variables are refused
// by file, variable and reason.
#include <gtest/gtest.h>

#include <unistd.h>

#include <filesystem>
#include <fstream>
#include <string>
#include <vector>

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
    explicit Writer(const std::string& file) : mat(Mat_CreateVer(file.c_str(), nullptr, MAT_FT_MAT5)) {}
    ~Writer() { Mat_Close(mat); }
    void dense(const char* name, const MarketMatrix& A) {
        std::vector<double> col(A.rows * A.cols);
        for (std::size_t i = 0; i < A.rows; ++i)
            for (std::size_t j = 0; j < A.cols; ++j) col[j * A.rows + i] = A(i, j);
        std::size_t dims[2] = {A.rows, A.cols};
        matvar_t* v = Mat_VarCreate(name, MAT_C_DOUBLE, MAT_T_DOUBLE, 2, dims, col.data(), 0);
        Mat_VarWrite(mat, v, MAT_COMPRESSION_NONE);
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
        Mat_VarWrite(mat, v, MAT_COMPRESSION_NONE);
        Mat_VarFree(v);
    }
    mat_t* mat;
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

#else

TEST(MatFile, NotBuilt) { GTEST_SKIP() << "built without HSNC_WITH_MATIO"; }

#endif

}  // namespace
}  // namespace hsnc
