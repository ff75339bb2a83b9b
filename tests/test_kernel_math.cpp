// Tests of kernel_abi.h's four-lane exp, sin and cos (hsnc_exp4,
// hsnc_sincos4): their accuracy against long double, that a lane's bits
// depend on its own argument alone (so the interpreter and a printed kernel
// may group modes differently), that AVX2 and SSE2 code give the same bits,
// and which programs use them (program.h, kVectorFactorsFrom).
#include <gtest/gtest.h>

#include <cmath>
#include <cstdint>
#include <cstring>
#include <limits>
#include <random>
#include <string>

#include "derivation.h"
#include "emitter.h"
#include "kernel_abi.h"
#include "lowering.h"
#include "model_reader.h"
#include "program.h"

namespace hsnc {
namespace {

// The same helpers compiled for AVX2 (when the processor has it, the
// interpreter runs this code) and for the default target (SSE2: the printed
// kernels, ahead of time and JIT).
__attribute__((target("avx2"))) void sincos4_avx2(const double* x, double* s, double* c) { hsnc_sincos4(x, s, c); }
__attribute__((target("avx2"))) void exp4_avx2(const double* x, double* e) { hsnc_exp4(x, e); }

std::uint64_t bits(double x) {
    std::uint64_t b;
    std::memcpy(&b, &x, sizeof b);
    return b;
}

// |got - ref| in units of the last place of the double nearest ref.
double ulps(double got, long double ref) {
    const double r = static_cast<double>(ref);
    if (r == 0.0) return got == 0.0 ? 0.0 : std::numeric_limits<double>::infinity();
    const double ulp = std::nextafter(std::fabs(r), std::numeric_limits<double>::infinity()) - std::fabs(r);
    return static_cast<double>(std::fabs(static_cast<long double>(got) - ref) / ulp);
}

TEST(KernelMath, SinAndCosAreWithinOneUlpOfLongDouble) {
    std::mt19937_64 gen(11);
    for (double range : {1e-300, 1e-8, 0.5, 4.0, 100.0, 1e4, 1e6}) {
        std::uniform_real_distribution<double> uni(-range, range);
        double worst = 0.0;
        for (int i = 0; i < 50000; ++i) {
            double x[4], s[4], c[4];
            for (double& xi : x) xi = uni(gen);
            hsnc_sincos4(x, s, c);
            for (int l = 0; l < 4; ++l) {
                worst = std::max(worst, ulps(s[l], sinl(x[l])));
                worst = std::max(worst, ulps(c[l], cosl(x[l])));
            }
        }
        EXPECT_LE(worst, 1.0) << "|x| <= " << range;
    }
    // Next to multiples of pi/2, where the reduction cancels: the tail keeps it.
    double worst = 0.0;
    for (long k = 1; k < 2000000; k += 997) {
        double x[4], s[4], c[4];
        const double near = static_cast<double>(k * 1.5707963267948966192313216916397514L);
        x[0] = near, x[1] = std::nextafter(near, 0.0), x[2] = std::nextafter(near, 1e300), x[3] = -near;
        hsnc_sincos4(x, s, c);
        for (int l = 0; l < 4; ++l) {
            worst = std::max(worst, ulps(s[l], sinl(x[l])));
            worst = std::max(worst, ulps(c[l], cosl(x[l])));
        }
    }
    EXPECT_LE(worst, 1.0) << "next to k pi/2";
}

TEST(KernelMath, ExpIsWithinOneUlpOfLongDouble) {
    std::mt19937_64 gen(12);
    for (double range : {1e-300, 1e-8, 0.3, 1.0, 50.0, 700.0}) {
        std::uniform_real_distribution<double> uni(-range, range);
        double worst = 0.0;
        for (int i = 0; i < 50000; ++i) {
            double x[4], e[4];
            for (double& xi : x) xi = uni(gen);
            hsnc_exp4(x, e);
            for (int l = 0; l < 4; ++l) worst = std::max(worst, ulps(e[l], expl(x[l])));
        }
        EXPECT_LE(worst, 1.0) << "|x| <= " << range;
    }
}

TEST(KernelMath, BeyondTheirRangeTheyTakeLibmsValue) {
    const double inf = std::numeric_limits<double>::infinity(), nan = std::numeric_limits<double>::quiet_NaN();
    for (double v : {inf, -inf, nan, 1e300, -3e7, 0x1p20 * 1.5, 700.5, -745.0, 710.0}) {
        double x[4] = {v, 0.25, -v, 1.0}, s[4], c[4], e[4];
        hsnc_sincos4(x, s, c);
        hsnc_exp4(x, e);
        for (int l : {0, 2}) {
            const double sl = std::sin(x[l]), cl = std::cos(x[l]), el = std::exp(x[l]);
            if (!(std::fabs(x[l]) <= 0x1p20)) {
                EXPECT_TRUE(bits(s[l]) == bits(sl) || (std::isnan(s[l]) && std::isnan(sl))) << x[l];
                EXPECT_TRUE(bits(c[l]) == bits(cl) || (std::isnan(c[l]) && std::isnan(cl))) << x[l];
            }
            if (!(std::fabs(x[l]) <= 700.0))
                EXPECT_TRUE(bits(e[l]) == bits(el) || (std::isnan(e[l]) && std::isnan(el))) << x[l];
        }
        // The lanes in range keep their own values.
        EXPECT_LE(ulps(s[1], sinl(0.25L)), 1.0);
        EXPECT_LE(ulps(e[3], expl(1.0L)), 1.0);
    }
    // At a segment's start (tau = 0: sin and cos of +0, exp of -0 or +0) the
    // interpreter writes 0, 1 and 1 without the call: these must be the bits.
    double zero[4] = {0.0, 0.0, 0.0, 0.0}, minus_zero[4] = {-0.0, -0.0, 0.0, -0.0}, s[4], c[4], e[4], e2[4];
    hsnc_sincos4(zero, s, c);
    hsnc_exp4(zero, e);
    hsnc_exp4(minus_zero, e2);
    for (int l = 0; l < 4; ++l) {
        EXPECT_EQ(bits(s[l]), bits(0.0));
        EXPECT_EQ(bits(c[l]), bits(1.0));
        EXPECT_EQ(bits(e[l]), bits(1.0));
        EXPECT_EQ(bits(e2[l]), bits(1.0));
    }
}

// A lane's bits are its argument's alone: in any lane, beside any others, and
// compiled for AVX2 or not.
TEST(KernelMath, ALaneDependsOnItsOwnArgumentAlone) {
    std::mt19937_64 gen(13);
    std::uniform_real_distribution<double> uni(-60.0, 60.0);
    const bool avx2 = __builtin_cpu_supports("avx2");
    for (int i = 0; i < 20000; ++i) {
        const double v = uni(gen);
        double ref_s = 0, ref_c = 0, ref_e = 0;
        for (int lane = 0; lane < 4; ++lane) {
            double x[4], s[4], c[4], e[4];
            for (double& xi : x) xi = uni(gen);
            x[lane] = v;
            hsnc_sincos4(x, s, c);
            hsnc_exp4(x, e);
            if (lane == 0) ref_s = s[0], ref_c = c[0], ref_e = e[0];
            ASSERT_EQ(bits(s[lane]), bits(ref_s)) << v << " in lane " << lane;
            ASSERT_EQ(bits(c[lane]), bits(ref_c)) << v << " in lane " << lane;
            ASSERT_EQ(bits(e[lane]), bits(ref_e)) << v << " in lane " << lane;
            if (avx2) {
                double s2[4], c2[4], e2[4];
                sincos4_avx2(x, s2, c2);
                exp4_avx2(x, e2);
                ASSERT_EQ(bits(s2[lane]), bits(ref_s)) << v << " (AVX2)";
                ASSERT_EQ(bits(c2[lane]), bits(ref_c)) << v << " (AVX2)";
                ASSERT_EQ(bits(e2[lane]), bits(ref_e)) << v << " (AVX2)";
            }
        }
    }
}

// Which kernels call them: from kVectorFactorsFrom modes on, every mode; below,
// none (libm, one mode at a time, is faster for a few modes alone).
TEST(KernelMath, ModelsOfEightModesOrMoreTakeTheirFactorsInLanes) {
    const Model chain = read_model(std::string(HSNC_SOURCE_DIR) + "/models/chain-8.toml");
    const Model scenario = read_model(std::string(HSNC_SOURCE_DIR) + "/models/seed-scenario-2.toml");
    const Derivation many = derive(chain, Configuration::all_open(chain));
    const Derivation few = derive(scenario, Configuration::all_open(scenario));
    EXPECT_TRUE(vector_factors(lower(many).eval));
    EXPECT_FALSE(vector_factors(lower(few).eval));
    const std::string a = emit_kernel(many), b = emit_kernel(few);
    // (The forcing's own sin and cos stay libm's in both.)
    EXPECT_NE(a.find("hsnc_sincos4("), std::string::npos);
    EXPECT_NE(a.find("hsnc_exp4("), std::string::npos);  // chain-8 is damped
    EXPECT_EQ(a.find("__builtin_exp(-"), std::string::npos);
    EXPECT_EQ(a.find("*__builtin_cos(omega_d_"), std::string::npos);
    EXPECT_EQ(b.find("hsnc_sincos4("), std::string::npos);
    EXPECT_NE(b.find("= __builtin_cos(omega_d_1*tau)"), std::string::npos);
    // A stuck mass splits the chain: seven modes take libm's values.
    const Derivation seven = derive(chain, Configuration::parse(chain, "stuck=m4"));
    EXPECT_FALSE(vector_factors(lower(seven).eval));
}

}  // namespace
}  // namespace hsnc
