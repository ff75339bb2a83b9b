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

/** Switch-function kinds; same values as hsnc::SwitchKind (model/switch_function.h). */
enum {
    HSNC_SWITCH_GAP = 0,         /**< contact gap G_c; element = contact index */
    HSNC_SWITCH_VELOCITY = 1,    /**< v_i of a sliding friction mass */
    HSNC_SWITCH_RELEASE_POS = 2, /**<  A_i - mu_s*N_i of a stuck mass */
    HSNC_SWITCH_RELEASE_NEG = 3  /**< -A_i - mu_s*N_i of a stuck mass */
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

#ifdef __cplusplus
} /* extern "C" */
#endif

#endif /* HSNC_KERNEL_ABI_H */
