/* hsnc -- the kernel ABI: the one header a generated kernel includes.
 *
 * A kernel is the closed-form solution of one configuration of one model
 * (runtime/solvers/segment_solver.h), specialised and emitted as C++ by the generator
 * (generator/emitter.h). It exports one `hsnc_kernel` object with C linkage.
 * This header is C-compatible and includes nothing, so an emitted kernel
 * compiles alone, fast, in-process or ahead of time.
 *
 * setup/eval have exactly the semantics of SegmentSolver::setup/eval:
 *   setup(coef, t0, t0_lo, x0, v0, sgn)  fixes the segment from the full
 *       state at absolute time t0 + t0_lo (t0_lo: the rounding of the start
 *       instant, |t0_lo| <= ulp(t0)/2, used for the forcing phase); x0 holds
 *       the masses' positions, then each Jenkins element's slider position;
 *       sgn[i] in {-1, 0, +1} is the direction of motion of
 *       each sliding friction mass (0 for stuck or frictionless masses).
 *       Writes n_coef doubles into coef (the caller owns them).
 *   eval(coef, tau, x, v, a, g, dg, bound, scale)  at tau = t - t0 >= 0:
 *       x: n_dof + n_slider doubles (stuck masses at their fixed x, then the
 *       sliders); v, a: n_dof doubles (v = a = 0 for stuck masses);
 *       g, dg: the n_switch switch functions and their first derivatives, in
 *       the order of `switches` (= switch_functions() of model/switch_function.h);
 *       bound[f] >= |g_f''(s)| for every s in [tau, tau + max_step];
 *       scale[f] = sum of |terms| summed into g_f.
 * Neither allocates, throws or touches global state.
 *
 * Sweep kernels (`hsnc generate --params k1,m2`) keep some model parameters
 * as run-time arguments: n_param > 0, param_names[] names them in the order
 * --params gave them (for `--params all`, the model's parameter order: the
 * file's, implicit g first), which is the order configure takes their values
 * in, and configure must be called before setup:
 *   configure(coef, params, max_step)  computes everything that depends on the
 *       parameters (matrices, modes and their regimes, forcing responses) into
 *       the first doubles of coef (the same n_coef block setup and eval use;
 *       setup never overwrites that part) and writes the validity of `bound`
 *       to *max_step (it replaces the field max_step, which is then NaN).
 *       Returns HSNC_CONFIGURE_OK, or a HSNC_CONFIGURE_* code when the values
 *       are not a valid model or change what the kernel was generated for;
 *       coef is then not usable.
 * Folded kernels (every parameter a constant) have n_param = 0 and
 * configure = 0 (a null pointer).
 */
#ifndef HSNC_KERNEL_ABI_H
#define HSNC_KERNEL_ABI_H

#ifdef __cplusplus
extern "C" {
#endif

/** Bumped whenever the layout or the meaning of hsnc_kernel changes. */
#define HSNC_KERNEL_ABI_VERSION 4

/** Switch-function kinds; the values of hsnc::SwitchKind (model/switch_function.h
    HSNC_SWITCH_KINDS, checked by static_assert in runtime/solvers/kernel_solver.cpp). */
enum {
    HSNC_SWITCH_GAP = 0,           /**< contact gap G_c; element = contact index */
    HSNC_SWITCH_VELOCITY = 1,      /**< v_i of a sliding friction mass */
    HSNC_SWITCH_RELEASE_POS = 2,   /**<  A_i - mu_s*N_i of a stuck mass */
    HSNC_SWITCH_RELEASE_NEG = 3,   /**< -A_i - mu_s*N_i of a stuck mass */
    HSNC_SWITCH_SLIP_POS = 4,      /**<  k e - F_s of a stuck Jenkins element; element = its index */
    HSNC_SWITCH_SLIP_NEG = 5,      /**< -k e - F_s of a stuck Jenkins element */
    HSNC_SWITCH_SLIP_VELOCITY = 6, /**< v[a] - v[b] of a slipping Jenkins element */
    HSNC_SWITCH_KINDS_END = 7      /**< one past the last kind */
};

/** Results of hsnc_configure_fn. */
enum {
    HSNC_CONFIGURE_OK = 0,
    HSNC_CONFIGURE_INVALID = 1,    /**< not a valid model: m <= 0, k < 0, mu_s < mu_k, damping < 0, omega <= 0, ... */
    HSNC_CONFIGURE_STRUCTURE = 2,  /**< a spring or contact stiffness moved between zero and positive: the
                                        rigid-body modes the kernel was generated for no longer hold */
    HSNC_CONFIGURE_EIGEN = 3       /**< the eigen-solver did not converge, or a mode is not positive */
};

typedef struct hsnc_switch {
    int kind;    /**< HSNC_SWITCH_* */
    int element; /**< contact index (gap) or mass index (the others) */
} hsnc_switch;

typedef void (*hsnc_setup_fn)(double* coef, double t0, double t0_lo, const double* x0, const double* v0,
                              const signed char* sgn);
typedef void (*hsnc_eval_fn)(const double* coef, double tau, double* x, double* v, double* a,
                             double* g, double* dg, double* bound, double* scale);

typedef int (*hsnc_configure_fn)(double* coef, const double* params, double* max_step);

typedef struct hsnc_kernel {
    int abi_version;                /**< HSNC_KERNEL_ABI_VERSION of the emitter */
    const char* model_name;         /**< Model::name */
    unsigned long long model_hash;  /**< model_hash() of the model it was generated from */
    const char* config_spec;        /**< Configuration::spec(), "closed=c1 stuck=m2" */
    const char* config_key;         /**< Configuration::key(), "c1_s01" */
    const char* generator_version;  /**< HSNC_VERSION of the generator */
    int n_dof;                      /**< masses of the model (v0, v, a sizes) */
    int n_slider;                   /**< Jenkins elements (ABI version 4): x0 and x hold n_dof + n_slider
                                         doubles, each slider's position after the masses' */
    int n_switch;                   /**< switch functions (g, dg, bound, scale sizes) */
    const hsnc_switch* switches;    /**< n_switch entries */
    int n_coef;                     /**< doubles that setup writes and eval reads */
    double max_step;                /**< validity of `bound`; +inf unless secular terms */
    hsnc_setup_fn setup;
    hsnc_eval_fn eval;
    /* ABI version 2: sweep kernels. Folded kernels leave these zero (an
       aggregate initialiser that stops at `eval` value-initialises them). */
    int n_param;                    /**< parameters given to configure (0: folded kernel) */
    const char* const* param_names; /**< n_param names, in the order of --params */
    hsnc_configure_fn configure;    /**< null for folded kernels */
} hsnc_kernel;

/* ---- Helpers shared by the printed kernels and the interpreter ----
 * The closed forms are straight-line code (kernels/program.h); what branches
 * on data lives here, once, so that a kernel compiled by GCC (AOT), by Clang
 * (JIT) and the interpreter (runtime/solvers/interpreted_solver.cpp) run the same
 * code. Compiled with -ffp-contract=off everywhere: every fma below is
 * written out. */

/** Omega (t0 + t0_lo) + phase reduced to [-pi, pi]: the product's rounding
 *  kept (fma) and 2 pi in two parts (Cody-Waite), so a large t0 costs no
 *  phase accuracy beyond its own. */
static inline double hsnc_phase(double omega, double t0, double t0_lo, double phase) {
    const double hi = omega * t0;
    const double lo = __builtin_fma(omega, t0, -hi) + omega * t0_lo;
    const double n = __builtin_nearbyint(hi / 6.283185307179586);
    double r = __builtin_fma(-n, 6.283185307179586, hi);
    r = __builtin_fma(-n, 2.4492935982947064e-16, r);
    return __builtin_remainder(r + lo + phase, 6.283185307179586);
}

/** phi2(x) = (e^x - 1 - x)/x^2, phi2(0) = 1/2; its Taylor series where the
 *  subtraction cancels (|x| < 0.5, 20 terms). */
static inline double hsnc_phi2(double x) {
    if (__builtin_fabs(x) < 0.5) {
        double term = 0.5, sum = 0.5; /* x^k/(k+2)! */
        for (int k = 1; k < 20; ++k) {
            term *= x / (k + 2);
            sum += term;
        }
        return sum;
    }
    return (__builtin_expm1(x) - x) / (x * x);
}

/* ---- e^{-sigma tau} and sin, cos(omega_d tau) of four modes at once ----
 * Every instant of a switch search evaluates, per mode, an exponential and a
 * sine and cosine. A configuration with many modes (kernels/program.h,
 * kVectorFactorsFrom) computes them here, four in the lanes of a vector (one
 * AVX register, or two SSE2 ones), each lane by the same operations, so that
 * a lane's bits depend on its own argument alone: the interpreter and a
 * printed kernel may group the modes as they like and still agree to the
 * last bit. Against libm one at a time: 4.1 against 11.8 ns a mode with AVX2
 * (exp and sincos), when the calls of a configuration's modes overlap.
 * Accuracy (tests/test_kernel_math.cpp, against long double): within 1 ulp.
 *
 * The argument is reduced by the nearest multiple k of pi/2 (of ln 2 for
 * exp), the multiple in parts whose products with k are exact (Cody-Waite),
 * the reduction's rounding carried as a tail; the reduced functions are their
 * Taylor series on [-pi/4, pi/4] ([-ln2/2, ln2/2]), truncated where the next
 * term is below 2^-60 of the result, the coefficients 1/n! rounded to double.
 * Arguments beyond |x| <= 2^20 (sin, cos) or |x| <= 700 (exp), and non-finite
 * ones, take libm's value. */
typedef double hsnc_v4d __attribute__((vector_size(32)));
typedef long long hsnc_v4l __attribute__((vector_size(32)));

/** Adding it rounds |y| < 2^51 to an integer, which the sum's low bits hold. */
#define HSNC_ROUND_MAGIC 0x1.8p52

/** s[i] = sin(x[i]), c[i] = cos(x[i]) for i = 0..3. */
static inline __attribute__((always_inline)) void hsnc_sincos4(const double* x_in, double* s, double* c) {
    hsnc_v4d x, big, k;
    hsnc_v4l bits;
    int i;
    __builtin_memcpy(&x, x_in, sizeof x);
    big = x * 0x1.45f306dc9c883p-1 + HSNC_ROUND_MAGIC; /* 2/pi */
    k = big - HSNC_ROUND_MAGIC;
    __builtin_memcpy(&bits, &big, sizeof bits);
    {
        /* pi/2 = p1 + p2 + p3, p1 and p2 of 33 bits: k*p1, k*p2 and x - k*p1 are exact. */
        const hsnc_v4d r1 = x - k * 0x1.921fb544p0;
        const hsnc_v4d w = k * 0x1.0b4611a6p-34;
        const hsnc_v4d y0 = r1 - w;
        const hsnc_v4d bb = y0 - r1; /* two-sum: y0 + err = r1 - w exactly */
        const hsnc_v4d err = (r1 - (y0 - bb)) + (-w - bb);
        const hsnc_v4d y1 = err - k * 0x1.3198a2e037073p-69;
        const hsnc_v4d hi = y0 + y1, lo = (y0 - hi) + y1; /* x - k pi/2 = hi + lo */
        const hsnc_v4d z = hi * hi;
        const hsnc_v4d ps =
            -0x1.5555555555555p-3 +
            z * (0x1.1111111111111p-7 +
                 z * (-0x1.a01a01a01a01ap-13 +
                      z * (0x1.71de3a556c734p-19 +
                           z * (-0x1.ae64567f544e4p-26 +
                                z * (0x1.6124613a86d09p-33 +
                                     z * (-0x1.ae7f3e733b81fp-41 +
                                          z * (0x1.952c77030ad4ap-49 + z * -0x1.2f49b46814157p-57)))))));
        const hsnc_v4d pc =
            0x1.5555555555555p-5 +
            z * (-0x1.6c16c16c16c17p-10 +
                 z * (0x1.a01a01a01a01ap-16 +
                      z * (-0x1.27e4fb7789f5cp-22 +
                           z * (0x1.1eed8eff8d898p-29 +
                                z * (-0x1.93974a8c07c9dp-37 +
                                     z * (0x1.ae7f3e733b81fp-45 +
                                          z * (-0x1.6827863b97d97p-53 + z * 0x1.e542ba4020225p-62)))))));
        /* sin(hi + lo) = sin hi + lo cos hi, cos(hi + lo) = cos hi - lo sin hi;
           1 - z/2 rounds, and its rounding is added back. */
        const hsnc_v4d sn = hi + (hi * z * ps + lo * (1.0 - 0.5 * z));
        const hsnc_v4d hz = 0.5 * z, one_hz = 1.0 - hz;
        const hsnc_v4d cs = one_hz + (((1.0 - one_hz) - hz) + (z * z * pc - hi * lo));
        /* Quadrant k mod 4: odd ones swap sin and cos, 2 and 3 negate sin, 1 and 2 negate cos. */
        const hsnc_v4l swap = (bits & 1) != 0;
        const hsnc_v4l sign_bit = {(long long)0x8000000000000000ull, (long long)0x8000000000000000ull,
                                   (long long)0x8000000000000000ull, (long long)0x8000000000000000ull};
        hsnc_v4l sn_bits, cs_bits, s_bits, c_bits;
        __builtin_memcpy(&sn_bits, &sn, sizeof sn_bits);
        __builtin_memcpy(&cs_bits, &cs, sizeof cs_bits);
        s_bits = ((swap & cs_bits) | (~swap & sn_bits)) ^ (((bits & 2) != 0) & sign_bit);
        c_bits = ((swap & sn_bits) | (~swap & cs_bits)) ^ ((((bits + 1) & 2) != 0) & sign_bit);
        __builtin_memcpy(s, &s_bits, sizeof s_bits);
        __builtin_memcpy(c, &c_bits, sizeof c_bits);
    }
    for (i = 0; i < 4; ++i)
        if (!(__builtin_fabs(x_in[i]) <= 0x1p20)) s[i] = __builtin_sin(x_in[i]), c[i] = __builtin_cos(x_in[i]);
}

/** e[i] = e^{x[i]} for i = 0..3. */
static inline __attribute__((always_inline)) void hsnc_exp4(const double* x_in, double* e) {
    hsnc_v4d x, big, k;
    hsnc_v4l bits;
    int i;
    __builtin_memcpy(&x, x_in, sizeof x);
    big = x * 0x1.71547652b82fep0 + HSNC_ROUND_MAGIC; /* 1/ln 2 */
    k = big - HSNC_ROUND_MAGIC;
    __builtin_memcpy(&bits, &big, sizeof bits);
    {
        /* ln 2 = l1 + l2, l1 of 32 bits: k*l1 and x - k*l1 are exact. */
        const hsnc_v4d r = (x - k * 0x1.62e42feep-1) - k * 0x1.a39ef35793c76p-33;
        const hsnc_v4d p =
            0x1p-1 +
            r * (0x1.5555555555555p-3 +
                 r * (0x1.5555555555555p-5 +
                      r * (0x1.1111111111111p-7 +
                           r * (0x1.6c16c16c16c17p-10 +
                                r * (0x1.a01a01a01a01ap-13 +
                                     r * (0x1.a01a01a01a01ap-16 +
                                          r * (0x1.71de3a556c734p-19 +
                                               r * (0x1.27e4fb7789f5cp-22 +
                                                    r * (0x1.ae64567f544e4p-26 +
                                                         r * (0x1.1eed8eff8d898p-29 +
                                                              r * (0x1.6124613a86d09p-33 +
                                                                   r * (0x1.93974a8c07c9dp-37 +
                                                                        r * 0x1.ae7f3e733b81fp-41))))))))))));
        const hsnc_v4d er = 1.0 + (r + r * r * p);
        /* 2^k from k's bits: the exponent field k + 1023 (|k| <= 1010 here). */
        const hsnc_v4l scale_bits = (bits - 0x4338000000000000ll + 1023) << 52;
        hsnc_v4d scale, ev;
        __builtin_memcpy(&scale, &scale_bits, sizeof scale);
        ev = er * scale;
        __builtin_memcpy(e, &ev, sizeof ev);
    }
    for (i = 0; i < 4; ++i)
        if (!(__builtin_fabs(x_in[i]) <= 700.0)) e[i] = __builtin_exp(x_in[i]);
}

#ifdef __cplusplus
} /* extern "C" */
#endif

#endif /* HSNC_KERNEL_ABI_H */
