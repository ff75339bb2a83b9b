// hsnc -- the model-independent core of every sweep kernel (generator/param_emitter.h):
// the types of the coefficient block, the eigen-solver, the modal decomposition and
// regimes, setup and eval.
//
// The generator does not include this file: CMake embeds the text after the marker line
// below into it (a raw string, generated sweep_kernel_core_text.cpp), and
// emit_sweep_kernel() prints that text verbatim into every sweep kernel, after the
// model's own declarations and before its configure(), which assembles M, K, C and the
// forces into State and calls decompose(). The declarations it relies on:
//   - "kernel_abi.h": HSNC_CONFIGURE_*, HSNC_SWITCH_*, hsnc_switch, hsnc_phase, hsnc_phi2;
//   - sizes N, NF, NH, NS, NS_STUCK, NR, NC and N1, NF1, NH1, NS1, NR1, NC1, NST1 (at least 1);
//   - tables free_dof[NF1], stuck_dof[NST1], free_of[N1], contact_a[NC1], contact_b[NC1],
//     contact_a_free[NC1], contact_b_free[NC1], rigid_member[NR1][NF1], switches[NS1];
//   - resonance_band: kResonanceBand of generator/derivation.h.
// tests/test_sweep_core.cpp compiles it with such declarations for small models and
// checks what decompose(), setup() and eval() compute against closed forms.
//
// Kernel code: __builtin_ math only, no allocation, no exceptions, nothing from std::.
// ---- printed into every sweep kernel from the next line on ----
// ---- The model-independent part (generator/sweep_kernel_core.h) ----
enum : int { R_UNDAMPED, R_UNDERDAMPED, R_CRITICAL, R_OVERDAMPED, R_RIGID, R_RIGID_DAMPED };

// What configure() computes from the parameters: the first part of the coefficient block.
struct State {
    double M[N1], K[N1][N1], C[N1][N1];  // masses, K(cfg), C = alpha M + beta K(cfg)
    double f_const[N1];                  // loads + contact preloads
    double mu_k_n[N1], mu_s_n[N1];       // mu_k N of sliding friction masses, mu_s N of friction masses
    double gap[NC1];                     // contact gaps
    double Omega[NH1], phase[NH1], F[NH1][N1];  // forcing harmonics
    double lambda[NF1], c[NF1], omega[NF1], sigma[NF1], kappa[NF1], omega_d[NF1], gamma[NF1], r1[NF1];
    int regime[NF1];
    double V[NF1][NF1], W[NF1][NF1];     // x_F = V q, q = W x_F
    double P[NF1][NH1], Pas[NF1][NH1], Pac[NF1][NH1];  // modal forcing, P a_s, P a_c
    bool resonant[NF1][NH1];
    double xs[NH1][NF1], xc[NH1][NF1];   // non-resonant particular in x: xs sin + xc cos
    double hx[N1], hv[N1];               // their magnitudes per mass
    double Hb[NS1][NF1], rigid_al[NS1][NF1], bconst[NS1], sec_slope[NS1], sec_off[NS1];  // bounds
    double max_step;
};
// What setup() computes for one segment.
struct Segment {
    double theta[NH1], s_theta[NH1], c_theta[NH1];
    double p[NF1], A[NF1], B[NF1], A1[NF1], B1[NF1], A2[NF1], B2[NF1];
    double x_st[NF1], x_fix[N1];
};
struct Block {
    State st;
    Segment sg;
};
constexpr int n_coef = static_cast<int>((sizeof(Block) + sizeof(double) - 1) / sizeof(double));

// Cyclic Jacobi eigenvalue algorithm for the symmetric a (Golub & Van Loan,
// Matrix Computations, Alg. 8.5.3): on return a is diagonal to rounding and
// a_in = vec diag(a) vec^T. An off-diagonal entry below 1e-18 of its diagonal
// pair is already below their rounding and is set to zero; the sweeps end when
// one changes nothing. False when 100 sweeps do not get there.
bool jacobi(double (&a)[NF1][NF1], double (&vec)[NF1][NF1]) {
    for (int p = 0; p < NF; ++p)
        for (int q = 0; q < NF; ++q) vec[p][q] = p == q ? 1.0 : 0.0;
    for (int sweep = 0; sweep < 100; ++sweep) {
        bool rotated = false;
        for (int p = 0; p < NF; ++p)
            for (int q = p + 1; q < NF; ++q) {
                const double apq = a[p][q];
                if (apq == 0.0) continue;
                if (__builtin_fabs(apq) <= 1e-18 * (__builtin_fabs(a[p][p]) + __builtin_fabs(a[q][q]))) {
                    a[p][q] = a[q][p] = 0.0;
                    continue;
                }
                rotated = true;
                // tan of the rotation angle, the smaller root of t^2 + 2 theta t - 1 = 0.
                const double theta = (a[q][q] - a[p][p]) / (2.0 * apq);
                const double t = __builtin_fabs(theta) > 1e150
                                     ? 0.5 / theta
                                     : (theta >= 0.0 ? 1.0 : -1.0) /
                                           (__builtin_fabs(theta) + __builtin_sqrt(theta * theta + 1.0));
                const double c = 1.0 / __builtin_sqrt(t * t + 1.0), s = t * c;
                for (int k = 0; k < NF; ++k) {  // a <- a J
                    const double akp = a[k][p], akq = a[k][q];
                    a[k][p] = c * akp - s * akq;
                    a[k][q] = s * akp + c * akq;
                }
                for (int k = 0; k < NF; ++k) {  // a <- J^T a
                    const double apk = a[p][k], aqk = a[q][k];
                    a[p][k] = c * apk - s * aqk;
                    a[q][k] = s * apk + c * aqk;
                }
                a[p][q] = a[q][p] = 0.0;
                for (int k = 0; k < NF; ++k) {  // vec <- vec J
                    const double vkp = vec[k][p], vkq = vec[k][q];
                    vec[k][p] = c * vkp - s * vkq;
                    vec[k][q] = s * vkp + c * vkq;
                }
            }
        if (!rotated) return true;
    }
    return false;
}

// decompose: the part of configure after the assembly of M, K, C, the forces and the
// forcing into st (alpha, beta: the Rayleigh damping): modes, regimes, forcing
// responses, switch-bound coefficients. HSNC_CONFIGURE_OK, or HSNC_CONFIGURE_EIGEN.
int decompose(State& st, double alpha, double beta, double* max_step) {
    // ---- Modal decomposition of Kt = M_F^-1/2 K_FF M_F^-1/2 (M is diagonal) ----
    double sqm[NF1], a[NF1][NF1], vec[NF1][NF1];
    for (int r = 0; r < NF; ++r) sqm[r] = __builtin_sqrt(st.M[free_dof[r]]);
    for (int r = 0; r < NF; ++r)
        for (int s = 0; s < NF; ++s) a[r][s] = st.K[free_dof[r]][free_dof[s]] / (sqm[r] * sqm[s]);
    if (!jacobi(a, vec)) return HSNC_CONFIGURE_EIGEN;
    int order[NF1];  // eigenvalues ascending (insertion sort: stable, no allocation)
    for (int j = 0; j < NF; ++j) {
        int k = j;
        while (k > 0 && a[order[k - 1]][order[k - 1]] > a[j][j]) {
            order[k] = order[k - 1];
            --k;
        }
        order[k] = j;
    }
    // Rigid-body modes (the NR floating components, fixed at generation) replace the
    // NR smallest eigenpairs: lambda = 0, shape sqrt(m) / sqrt(component mass); the
    // elastic shapes are made orthogonal to them (one Gram-Schmidt pass) and renormalised.
    double shape[NF1][NF1];  // shape[j][r] = Phi_rj (orthonormal)
    for (int j = 0; j < NF; ++j) {
        if (j < NR) {
            double mt = 0.0;
            for (int r = 0; r < NF; ++r)
                if (rigid_member[j][r]) mt += st.M[free_dof[r]];
            for (int r = 0; r < NF; ++r) shape[j][r] = rigid_member[j][r] ? sqm[r] / __builtin_sqrt(mt) : 0.0;
            st.lambda[j] = 0.0;
        } else {
            for (int r = 0; r < NF; ++r) shape[j][r] = vec[r][order[j]];
            for (int i = 0; i < NR; ++i) {
                double d = 0.0;
                for (int r = 0; r < NF; ++r) d += shape[i][r] * shape[j][r];
                for (int r = 0; r < NF; ++r) shape[j][r] -= d * shape[i][r];
            }
            double nn = 0.0;
            for (int r = 0; r < NF; ++r) nn += shape[j][r] * shape[j][r];
            if (NR > 0)
                for (int r = 0; r < NF; ++r) shape[j][r] /= __builtin_sqrt(nn);
            st.lambda[j] = a[order[j]][order[j]];
            if (!(st.lambda[j] > 0.0)) return HSNC_CONFIGURE_EIGEN;  // a mode not detected as rigid
        }
        // Deterministic sign: the largest component is positive.
        int big = 0;
        for (int r = 1; r < NF; ++r)
            if (__builtin_fabs(shape[j][r]) > __builtin_fabs(shape[j][big]) + 1e-6) big = r;
        if (shape[j][big] < 0.0)
            for (int r = 0; r < NF; ++r) shape[j][r] = -shape[j][r];
        for (int r = 0; r < NF; ++r) {
            st.V[r][j] = shape[j][r] / sqm[r];  // x_F = V q
            st.W[j][r] = shape[j][r] * sqm[r];  // q = W x_F
        }
    }

    // ---- Regime of each mode: q'' + c q' + lambda q, c = alpha + beta lambda ----
    // e^{-sigma tau} times (cos, sin/omega_d), (1, tau) or (cosh, sinh/gamma); the
    // root differences (omega - sigma)(omega + sigma) never cancel near xi = 1.
    for (int j = 0; j < NF; ++j) {
        const double lam = st.lambda[j], c = alpha + beta * lam;
        st.c[j] = c;
        st.omega[j] = st.omega_d[j] = st.gamma[j] = st.r1[j] = 0.0;
        if (lam == 0.0) {
            if (c == 0.0) {
                st.regime[j] = R_RIGID;
                st.sigma[j] = st.kappa[j] = 0.0;
            } else {  // q = A + B (1 - e^{-c tau})/c: the overdamped form with lambda = 0
                st.regime[j] = R_RIGID_DAMPED;
                st.sigma[j] = st.gamma[j] = 0.5 * c;
                st.kappa[j] = -st.sigma[j] * st.sigma[j];
            }
            continue;
        }
        const double w = __builtin_sqrt(lam), s = 0.5 * c;
        st.omega[j] = w;
        st.sigma[j] = s;
        if (c == 0.0) {
            st.regime[j] = R_UNDAMPED;
            st.kappa[j] = lam;
            st.omega_d[j] = w;
        } else if (s < w && (w - s) * (w + s) > 0.0) {
            st.regime[j] = R_UNDERDAMPED;
            st.kappa[j] = (w - s) * (w + s);
            st.omega_d[j] = __builtin_sqrt(st.kappa[j]);
        } else if (s > w && (s - w) * (s + w) > 0.0) {
            st.regime[j] = R_OVERDAMPED;
            st.kappa[j] = -((s - w) * (s + w));
            st.gamma[j] = __builtin_sqrt(-st.kappa[j]);
            st.r1[j] = -lam / (s + st.gamma[j]);  // slow root -sigma + gamma without cancellation
        } else {
            st.regime[j] = R_CRITICAL;
            st.kappa[j] = 0.0;
        }
    }

    // ---- Forcing: modal amplitudes P_jh = sum_r V_rj F_h,r and particular solutions ----
    // q_p = P (a_s sin + a_c cos)(Omega tau + theta), a_s = (lambda - Omega^2)/D,
    // a_c = -c Omega/D, D = (lambda - Omega^2)^2 + (c Omega)^2; an undamped mode with
    // |Omega - omega| <= resonance_band omega uses the resonance-stable form from rest
    // instead (bounds then hold for one forcing period: max_step).
    st.max_step = __builtin_inf();
    for (int h = 0; h < NH; ++h)
        for (int r = 0; r < NF; ++r) st.xs[h][r] = st.xc[h][r] = 0.0;
    for (int j = 0; j < NF; ++j)
        for (int h = 0; h < NH; ++h) {
            const double W = st.Omega[h], lam = st.lambda[j], c = st.c[j];
            double P = 0.0;
            for (int r = 0; r < NF; ++r) P += st.V[r][j] * st.F[h][free_dof[r]];
            st.P[j][h] = P;
            st.resonant[j][h] = st.regime[j] == R_UNDAMPED && __builtin_fabs(W - st.omega[j]) <= resonance_band * st.omega[j];
            st.Pas[j][h] = st.Pac[j][h] = 0.0;
            if (st.resonant[j][h]) {
                const double period = 2.0 * 3.14159265358979323846 / W;
                if (period < st.max_step) st.max_step = period;
                continue;
            }
            const double det = lam - W * W, den = det * det + c * c * W * W;
            st.Pas[j][h] = P * (det / den);
            st.Pac[j][h] = P * (-c * W / den);
            for (int r = 0; r < NF; ++r) {
                st.xs[h][r] += st.V[r][j] * st.Pas[j][h];
                st.xc[h][r] += st.V[r][j] * st.Pac[j][h];
            }
        }
    for (int i = 0; i < N; ++i) st.hx[i] = st.hv[i] = 0.0;
    for (int r = 0; r < NF; ++r)
        for (int h = 0; h < NH; ++h) {
            const double m = __builtin_fabs(st.xs[h][r]) + __builtin_fabs(st.xc[h][r]);
            st.hx[free_dof[r]] += m;
            st.hv[free_dof[r]] += st.Omega[h] * m;
        }

    // ---- Switch functions as g_f = sum_j (al_fj q_j + be_fj q_j') + sum_h (Gs sin + Gc cos) + const ----
    // for the bound |g''| <= sum_j Hb_fj sqrt(2 E_j) + bconst_f (+ rigid and secular terms):
    // Hb = |al| (c + omega) + |be| (c (c + omega) + lambda), bconst = sum_h Omega^2 sqrt(Gs^2 + Gc^2).
    for (int f = 0; f < NS; ++f) {
        double al[NF1], be[NF1], Gs[NH1], Gc[NH1];
        for (int j = 0; j < NF; ++j) al[j] = be[j] = 0.0;
        for (int h = 0; h < NH; ++h) Gs[h] = Gc[h] = 0.0;
        const int e = switches[f].element;
        if (switches[f].kind == HSNC_SWITCH_GAP) {
            const int ra = contact_a_free[e], rb = contact_b_free[e];
            for (int j = 0; j < NF; ++j) al[j] = (ra >= 0 ? st.V[ra][j] : 0.0) - (rb >= 0 ? st.V[rb][j] : 0.0);
            for (int h = 0; h < NH; ++h) {
                Gs[h] = (ra >= 0 ? st.xs[h][ra] : 0.0) - (rb >= 0 ? st.xs[h][rb] : 0.0);
                Gc[h] = (ra >= 0 ? st.xc[h][ra] : 0.0) - (rb >= 0 ? st.xc[h][rb] : 0.0);
            }
        } else if (switches[f].kind == HSNC_SWITCH_VELOCITY) {
            const int r = free_of[e];
            for (int j = 0; j < NF; ++j) be[j] = st.V[r][j];
            for (int h = 0; h < NH; ++h) {
                Gs[h] = -st.Omega[h] * st.xc[h][r];
                Gc[h] = st.Omega[h] * st.xs[h][r];
            }
        } else {  // A_i = -K x - C v + f + sum_h F_h sin of a stuck mass i
            for (int j = 0; j < NF; ++j)
                for (int r = 0; r < NF; ++r) {
                    al[j] -= st.K[e][free_dof[r]] * st.V[r][j];
                    be[j] -= st.C[e][free_dof[r]] * st.V[r][j];
                }
            for (int h = 0; h < NH; ++h) {
                Gs[h] = st.F[h][e];
                for (int r = 0; r < NF; ++r) {
                    const double Kik = st.K[e][free_dof[r]], Cik = st.C[e][free_dof[r]];
                    Gs[h] += -Kik * st.xs[h][r] + Cik * st.Omega[h] * st.xc[h][r];
                    Gc[h] += -Kik * st.xc[h][r] - Cik * st.Omega[h] * st.xs[h][r];
                }
            }
        }
        double konst = 0.0, slope = 0.0, off = 0.0;
        for (int h = 0; h < NH; ++h)
            konst += __builtin_sqrt(Gs[h] * Gs[h] + Gc[h] * Gc[h]) * st.Omega[h] * st.Omega[h];
        for (int j = 0; j < NF; ++j) {
            const double c = st.c[j], w = st.omega[j], aa = __builtin_fabs(al[j]), bb = __builtin_fabs(be[j]);
            st.Hb[f][j] = aa * (c + w) + bb * (c * (c + w) + st.lambda[j]);
            // rigid-body modes: |q_p''| <= |p|, |q_p^(3)| <= c |p|
            st.rigid_al[f][j] = st.regime[j] == R_RIGID || st.regime[j] == R_RIGID_DAMPED ? aa + bb * c : 0.0;
            for (int h = 0; h < NH; ++h) {
                if (!st.resonant[j][h] || (aa == 0.0 && bb == 0.0)) continue;
                // |y''| <= Q ((h^2 + wbar^2) s + 2 wbar + omega),
                // |y'''| <= Q (wbar^3 s + 3 wbar^2 + 3 h wbar + h^2 + omega^2)
                const double W = st.Omega[h], Q = __builtin_fabs(st.P[j][h] / (w + W));
                const double hw = __builtin_fabs(W - w) / 2.0, wb = (W + w) / 2.0;
                slope += aa * Q * (hw * hw + wb * wb) + bb * Q * wb * wb * wb;
                off += aa * Q * (2.0 * wb + w) + bb * Q * (3.0 * wb * wb + 3.0 * hw * wb + hw * hw + st.lambda[j]);
            }
        }
        st.bconst[f] = konst;
        st.sec_slope[f] = slope;
        st.sec_off[f] = off;
    }
    *max_step = st.max_step;
    return HSNC_CONFIGURE_OK;
}

// setup: the segment from (t0, x0, v0, sgn), as the folded kernels do it.
void setup(double* coef, double t0, double t0_lo, const double* x0, const double* v0, const signed char* sgn) {
    const State& st = reinterpret_cast<const Block*>(coef)->st;
    Segment& sg = reinterpret_cast<Block*>(coef)->sg;
    // Constant force on the free masses: loads + preload - K_FS x_S - mu_k N sgn (Eq. 7-9).
    double f[NF1];
    for (int r = 0; r < NF; ++r) {
        const int i = free_dof[r];
        double fi = st.f_const[i];
        for (int k = 0; k < NS_STUCK; ++k) fi -= st.K[i][stuck_dof[k]] * x0[stuck_dof[k]];
        f[r] = fi - st.mu_k_n[i] * sgn[i];
    }
    // Modal forces p = V^T f.
    for (int j = 0; j < NF; ++j) {
        double p = 0.0;
        for (int r = 0; r < NF; ++r) p += st.V[r][j] * f[r];
        sg.p[j] = p;
    }
    // Forcing phases at the segment start: theta_h = Omega_h (t0 + t0_lo) + phase_h, reduced.
    for (int h = 0; h < NH; ++h) {
        sg.theta[h] = hsnc_phase(st.Omega[h], t0, t0_lo, st.phase[h]);
        sg.s_theta[h] = __builtin_sin(sg.theta[h]);
        sg.c_theta[h] = __builtin_cos(sg.theta[h]);
    }
    // Static offset x_st = V (p / lambda) over the elastic modes.
    for (int r = 0; r < NF; ++r) {
        double x = 0.0;
        for (int j = 0; j < NF; ++j)
            if (st.lambda[j] != 0.0) x += st.V[r][j] / st.lambda[j] * sg.p[j];
        sg.x_st[r] = x;
    }
    // Homogeneous part of the initial state in x: xh = x0 - x_p(0), vh = v0 - v_p(0) with
    // x_p = x_st + sum_h (xs sin + xc cos), exactly what eval adds back at tau = 0 (long double
    // sums); its modal coordinates q = W xh, refined once against the residuals xh - V q
    // (long double): removes the bias of V W = I + E.
    double xh[NF1], vh[NF1], q0[NF1], dq0[NF1], rx[NF1], rv[NF1];
    for (int r = 0; r < NF; ++r) {
        long double ex = static_cast<long double>(x0[free_dof[r]]) - sg.x_st[r];
        long double ev = v0[free_dof[r]];
        for (int h = 0; h < NH; ++h) {
            const double W = st.Omega[h];
            ex -= static_cast<long double>(st.xs[h][r]) * sg.s_theta[h] + static_cast<long double>(st.xc[h][r]) * sg.c_theta[h];
            ev -= static_cast<long double>(W * st.xs[h][r]) * sg.c_theta[h] -
                  static_cast<long double>(W * st.xc[h][r]) * sg.s_theta[h];
        }
        xh[r] = static_cast<double>(ex);
        vh[r] = static_cast<double>(ev);
    }
    for (int j = 0; j < NF; ++j) {
        double q = 0.0, dq = 0.0;
        for (int r = 0; r < NF; ++r) {
            q += st.W[j][r] * xh[r];
            dq += st.W[j][r] * vh[r];
        }
        q0[j] = q;
        dq0[j] = dq;
    }
    for (int r = 0; r < NF; ++r) {
        long double ex = xh[r], ev = vh[r];
        for (int j = 0; j < NF; ++j) {
            ex -= static_cast<long double>(st.V[r][j]) * q0[j];
            ev -= static_cast<long double>(st.V[r][j]) * dq0[j];
        }
        rx[r] = static_cast<double>(ex);
        rv[r] = static_cast<double>(ev);
    }
    for (int j = 0; j < NF; ++j) {
        double q = 0.0, dq = 0.0;
        for (int r = 0; r < NF; ++r) {
            q += st.W[j][r] * rx[r];
            dq += st.W[j][r] * rv[r];
        }
        q0[j] += q;
        dq0[j] += dq;
    }
    // One more refinement, against what eval will return at tau = 0: x(0) and v(0) summed
    // exactly as eval sums them, the residuals x0 - x(0), v0 - v(0) mapped back with W.
    // x(0) is a sum of terms larger than x itself (static offset, forcing response), so
    // without this its rounding depends on x0 only through its leading bits, and a state
    // restarted again and again moves the same way (tests/test_restart_drift.cpp).
    for (int r = 0; r < NF; ++r) {
        double xx = sg.x_st[r], vv = 0.0;
        for (int j = 0; j < NF; ++j) {
            xx += st.V[r][j] * q0[j];
            vv += st.V[r][j] * dq0[j];
        }
        for (int h = 0; h < NH; ++h) {
            const double W = st.Omega[h];
            xx += st.xs[h][r] * sg.s_theta[h] + st.xc[h][r] * sg.c_theta[h];
            vv += W * st.xs[h][r] * sg.c_theta[h] - W * st.xc[h][r] * sg.s_theta[h];
        }
        rx[r] = static_cast<double>(static_cast<long double>(x0[free_dof[r]]) - xx);
        rv[r] = static_cast<double>(static_cast<long double>(v0[free_dof[r]]) - vv);
    }
    for (int j = 0; j < NF; ++j) {
        double q = 0.0, dq = 0.0;
        for (int r = 0; r < NF; ++r) {
            q += st.W[j][r] * rx[r];
            dq += st.W[j][r] * rv[r];
        }
        q0[j] += q;
        dq0[j] += dq;
    }
    // Per mode: A = q_h(0), B = q_h'(0) + sigma A (every particular part starts at q_p(0) =
    // q_p'(0) = 0 or is in x_p) and the derivative pairs (A, B) -> (B - sigma A, -kappa A - sigma B).
    for (int j = 0; j < NF; ++j) {
        const double s = st.sigma[j], k = st.kappa[j];
        const double A = q0[j], B = dq0[j] + s * A;
        sg.A[j] = A;
        sg.B[j] = B;
        sg.A1[j] = B - s * A;
        sg.B1[j] = -k * A - s * B;
        sg.A2[j] = sg.B1[j] - s * sg.A1[j];
        sg.B2[j] = -k * sg.A1[j] - s * sg.B1[j];
    }
    for (int i = 0; i < N; ++i) sg.x_fix[i] = x0[i];
}

// eval: state, switch functions, bounds and term magnitudes at tau.
void eval(const double* coef, double tau, double* x, double* v, double* a, double* g, double* dg,
          double* bound, double* scale) {
    const State& st = reinterpret_cast<const Block*>(coef)->st;
    const Segment& sg = reinterpret_cast<const Block*>(coef)->sg;
    // Forcing harmonics: sin/cos(Omega_h tau + theta_h), once each.
    double sn[NH1], cs[NH1];
    for (int h = 0; h < NH; ++h) {
        const double arg = st.Omega[h] * tau + sg.theta[h];
        sn[h] = __builtin_sin(arg);
        cs[h] = __builtin_cos(arg);
    }
    // Secular terms are bounded at the end of the step, s_end = tau + max_step.
    const double s_end = tau + st.max_step;
    double q[NF1], dq[NF1], ddq[NF1], mq[NF1], mdq[NF1], rE[NF1];
    for (int j = 0; j < NF; ++j) {
        const double lam = st.lambda[j];
        double eC, eS;
        switch (st.regime[j]) {
            case R_UNDAMPED:  // eC = cos(omega tau), eS = sin(omega tau)/omega
                eC = __builtin_cos(st.omega_d[j] * tau);
                eS = __builtin_sin(st.omega_d[j] * tau) / st.omega_d[j];
                break;
            case R_UNDERDAMPED: {  // e^{-sigma tau} (cos, sin/omega_d)(omega_d tau)
                const double e = __builtin_exp(-st.sigma[j] * tau);
                eC = e * __builtin_cos(st.omega_d[j] * tau);
                eS = e * __builtin_sin(st.omega_d[j] * tau) / st.omega_d[j];
                break;
            }
            case R_CRITICAL:  // e^{-sigma tau} (1, tau)
                eC = __builtin_exp(-st.sigma[j] * tau);
                eS = tau * eC;
                break;
            case R_OVERDAMPED: {  // e^{r1 tau} (1 + E)/2, -e^{r1 tau} m/(2 gamma), m = expm1(-2 gamma tau)
                const double e = __builtin_exp(st.r1[j] * tau), m = __builtin_expm1(-2.0 * st.gamma[j] * tau);
                eC = e * (1.0 + 0.5 * m);
                eS = -e * m * (0.5 / st.gamma[j]);
                break;
            }
            case R_RIGID:  // 1, tau
                eC = 1.0;
                eS = tau;
                break;
            default: {  // rigid, damped: (1 + e^{-c tau})/2, (1 - e^{-c tau})/c
                const double m = __builtin_expm1(-st.c[j] * tau);
                eC = 1.0 + 0.5 * m;
                eS = -m / st.c[j];
                break;
            }
        }
        const double qh = sg.A[j] * eC + sg.B[j] * eS, dqh = sg.A1[j] * eC + sg.B1[j] * eS;
        double qq = qh, dd = dqh, aa = sg.A2[j] * eC + sg.B2[j] * eS;
        // sqrt(2E), E = (q_h'^2 + lambda q_h^2)/2 never grows (c >= 0).
        rE[j] = __builtin_sqrt(dqh * dqh + lam * qh * qh);
        double mag = __builtin_fabs(sg.A[j] * eC) + __builtin_fabs(sg.B[j] * eS);
        double dmag = __builtin_fabs(sg.A1[j] * eC) + __builtin_fabs(sg.B1[j] * eS) + __builtin_fabs(st.sigma[j] * sg.A[j] * eC);  // A1 = B - sigma A cancels to eps sigma A (emitter.cpp)
        if (st.regime[j] == R_RIGID || st.regime[j] == R_RIGID_DAMPED) {
            // q_p = p tau^2 phi2(-c tau) from rest (p tau^2/2 at c = 0): q_p' = p eS, q_p'' = p e^{-c tau}.
            // One form for every c >= 0: no p/c drift that cancels as c -> 0.
            const double p = sg.p[j], x = -st.c[j] * tau, qp = p * tau * tau * hsnc_phi2(x), dqp = p * eS;
            qq += qp;
            dd += dqp;
            aa += p * (x == 0.0 ? 1.0 : __builtin_exp(x));
            mag += __builtin_fabs(qp);
            dmag += __builtin_fabs(dqp);
        }
        for (int h = 0; h < NH; ++h) {
            if (!st.resonant[j][h]) continue;
            // Resonant response from rest, stable through Omega = omega:
            // y = Q [-w cos(wbar tau + theta) + cos(theta) sin(omega tau)/omega], Q = P/(omega + Omega),
            // w = sin(h tau)/h -> tau (h = (Omega - omega)/2, wbar = (Omega + omega)/2).
            const double W = st.Omega[h], w0 = st.omega[j], Q = st.P[j][h] / (w0 + W);
            const double hw = (W - w0) / 2.0, wb = (W + w0) / 2.0, ct = sg.c_theta[h];
            const double w = hw == 0.0 ? tau : __builtin_sin(hw * tau) / hw;
            const double dw = hw == 0.0 ? 1.0 : __builtin_cos(hw * tau);
            const double Cb = __builtin_cos(wb * tau + sg.theta[h]), Sb = __builtin_sin(wb * tau + sg.theta[h]);
            const double y = Q * (ct * eS - w * Cb);
            const double dy = Q * (ct * eC - dw * Cb + wb * w * Sb);
            const double ddy = Q * ((hw * hw + wb * wb) * w * Cb + 2.0 * wb * dw * Sb - lam * ct * eS);
            qq += y;
            dd += dy;
            aa += ddy;
            mag += __builtin_fabs(y);
            dmag += __builtin_fabs(dy);
        }
        q[j] = qq;
        dq[j] = dd;
        ddq[j] = aa;
        mq[j] = mag;
        mdq[j] = dmag;
    }
    // Physical state: x = x_st + V q + sum_h (xs_h sin + xc_h cos); stuck masses rest.
    double mx[N1], mv[N1];
    for (int i = 0; i < N; ++i) {
        x[i] = sg.x_fix[i];
        v[i] = a[i] = 0.0;
        mx[i] = __builtin_fabs(sg.x_fix[i]);
        mv[i] = 0.0;
    }
    for (int r = 0; r < NF; ++r) {
        const int i = free_dof[r];
        double xx = sg.x_st[r], vv = 0.0, ac = 0.0, xm = __builtin_fabs(sg.x_st[r]), vm = 0.0;
        for (int j = 0; j < NF; ++j) {
            xx += st.V[r][j] * q[j];
            vv += st.V[r][j] * dq[j];
            ac += st.V[r][j] * ddq[j];
            xm += __builtin_fabs(st.V[r][j]) * mq[j];
            vm += __builtin_fabs(st.V[r][j]) * mdq[j];
        }
        for (int h = 0; h < NH; ++h) {
            const double W = st.Omega[h], xs = st.xs[h][r], xc = st.xc[h][r];
            xx += xs * sn[h] + xc * cs[h];
            vv += W * xs * cs[h] - W * xc * sn[h];
            ac += -W * W * xs * sn[h] - W * W * xc * cs[h];
        }
        x[i] = xx;
        v[i] = vv;
        a[i] = ac;
        mx[i] = xm + st.hx[i];
        mv[i] = vm + st.hv[i];
    }
    // Switch functions (runtime/segment.h order), derivatives, bounds on |g''| and term magnitudes.
    for (int f = 0; f < NS; ++f) {
        const int e = switches[f].element;
        double gf, dgf, sc;
        if (switches[f].kind == HSNC_SWITCH_GAP) {  // G = x[a] - x[b] - gap
            const int ba = contact_a[e], bb = contact_b[e];
            gf = (ba >= 0 ? x[ba] : 0.0) - (bb >= 0 ? x[bb] : 0.0) - st.gap[e];
            dgf = (ba >= 0 ? v[ba] : 0.0) - (bb >= 0 ? v[bb] : 0.0);
            sc = (ba >= 0 ? mx[ba] : 0.0) + (bb >= 0 ? mx[bb] : 0.0) + __builtin_fabs(st.gap[e]);
        } else if (switches[f].kind == HSNC_SWITCH_VELOCITY) {
            gf = v[e];
            dgf = a[e];
            sc = mv[e];
        } else {  // +-A - mu_s N, A = -K x - C v + f + sum_h F_h sin (force but friction)
            double A = st.f_const[e], dA = 0.0, m = 0.0;
            for (int k = 0; k < N; ++k) {
                A -= st.K[e][k] * x[k];
                dA -= st.K[e][k] * v[k];
                m += __builtin_fabs(st.K[e][k]) * mx[k];
                if (free_of[k] >= 0) {
                    A -= st.C[e][k] * v[k];
                    dA -= st.C[e][k] * a[k];
                    m += __builtin_fabs(st.C[e][k]) * mv[k];
                }
            }
            double mc = __builtin_fabs(st.f_const[e]) + st.mu_s_n[e];
            for (int h = 0; h < NH; ++h) {
                A += st.F[h][e] * sn[h];
                dA += st.F[h][e] * st.Omega[h] * cs[h];
                mc += __builtin_fabs(st.F[h][e]);
            }
            const double sgn_f = switches[f].kind == HSNC_SWITCH_RELEASE_POS ? 1.0 : -1.0;
            gf = sgn_f * A - st.mu_s_n[e];
            dgf = sgn_f * dA;
            sc = m + mc;
        }
        double b = st.bconst[f];
        for (int j = 0; j < NF; ++j) b += st.Hb[f][j] * rE[j] + st.rigid_al[f][j] * __builtin_fabs(sg.p[j]);
        if (st.sec_slope[f] != 0.0 || st.sec_off[f] != 0.0) b += st.sec_slope[f] * s_end + st.sec_off[f];
        g[f] = gf;
        dg[f] = dgf;
        bound[f] = b;
        scale[f] = sc;
    }
}
