#include "derivation.h"

#include <cln/cln.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <numeric>
#include <utility>

#include "assembly.h"
#include "elements/contact.h"
#include "elements/friction.h"
#include "elements/jenkins.h"
#include "elements/motion.h"
#include "switch_derivative.h"
#include "error.h"
#include "free_components.h"
#include "mp_complex_eigen.h"
#include "mp_eigen.h"

namespace hsnc {

using GiNaC::ex;
using GiNaC::numeric;

const char* regime_name(Regime r) {
    switch (r) {
        case Regime::undamped: return "undamped";
        case Regime::underdamped: return "underdamped";
        case Regime::critical: return "critically damped";
        case Regime::overdamped: return "overdamped";
        case Regime::rigid: return "rigid body";
        case Regime::rigid_damped: return "rigid body, damped";
    }
    return "?";
}

numeric exact(double v) { return numeric(cln::rational(cln::cl_DF(v))); }

numeric exact(const DD& v) { return exact(v.hi()) + exact(v.lo()); }

numeric exact_normal(const Model& model, std::size_t i) {
    const double n = model.friction_slot(i).normal;
    return n > 0.0 ? exact(n) : exact(model.masses[i].m) * exact(model.g);
}

DD to_dd(const numeric& v) {
    const double hi = v.to_double();
    return DD(hi) + DD((v - exact(hi)).to_double());
}

int Derivation::free_index(int mass) const {
    const auto it = std::find(free_dofs.begin(), free_dofs.end(), mass);
    return it == free_dofs.end() ? -1 : static_cast<int>(it - free_dofs.begin());
}

bool Derivation::rides(int mass) const { return std::find(riders.begin(), riders.end(), mass) != riders.end(); }

int Derivation::coordinate(int mass) const {
    if (mass == kGround) return -1;
    return rides(mass) ? free_index(carrier(*model, cfg, static_cast<std::size_t>(mass))) : free_index(mass);
}

namespace {

const numeric kZero(0);

numeric to_float(const numeric& x) { return GiNaC::ex_to<numeric>(x.evalf()); }

/// A DD as a GiNaC float of the current Digits (symbolic_segment's numbers).
numeric lf(const DD& x) { return to_float(exact(x)); }
numeric lfc(const DDComplex& z) { return GiNaC::ex_to<numeric>((exact(z.re) + exact(z.im) * GiNaC::I).evalf()); }


/// A harmonic's frequency, phase and amplitudes, exactly (Omega > 0).
HarmonicData harmonic_data(const Harmonic& h) {
    HarmonicData hd;
    hd.omega = DD(h.omega);
    hd.phase = DD(h.phase);
    for (double a : h.amplitude) hd.amplitude.push_back(DD(a));
    return hd;
}

/// The folded matrix T^T X T of the free coordinates: entry (r, s) sums X
/// over the masses of coordinates r and s (a coordinate's free mass and its riders).
std::vector<std::vector<DD>> folded(const std::vector<std::vector<DD>>& X, const std::vector<std::vector<int>>& group) {
    const std::size_t nf = group.size();
    std::vector<std::vector<DD>> out(nf, std::vector<DD>(nf));
    for (std::size_t r = 0; r < nf; ++r)
        for (std::size_t s = 0; s < nf; ++s)
            for (int i : group[r])
                for (int k : group[s]) {
                    const DD& x = X[static_cast<std::size_t>(i)][static_cast<std::size_t>(k)];
                    if (!x.is_zero()) out[r][s] += x;  // an exact zero adds nothing (and most entries are)
                }
    return out;
}

/// (M_FF)_rc: M between free coordinates r and c (a coupled M has no riders).
double free_mass(const Derivation& d, std::size_t r, std::size_t c) {
    return d.model->mass_entry(static_cast<std::size_t>(d.free_dofs[r]), static_cast<std::size_t>(d.free_dofs[c]));
}

/// M_FF = L L^T of a coupled M over the free dofs, in DD (L lower
/// triangular); NotDerivable where a pivot is not positive.
std::vector<std::vector<DD>> mass_cholesky(const Derivation& d, const std::string& where) {
    const std::size_t nf = d.free_dofs.size();
    std::vector<std::vector<DD>> L(nf, std::vector<DD>(nf));
    for (std::size_t r = 0; r < nf; ++r)
        for (std::size_t c = 0; c <= r; ++c) {
            DD sum(free_mass(d, r, c));
            for (std::size_t k = 0; k < c; ++k) sum -= L[r][k] * L[c][k];
            if (r == c) {
                if (!(sum > DD(0.0))) throw NotDerivable(where + "the free dofs' mass matrix is not positive definite");
                L[r][r] = sqrt(sum);
            } else {
                L[r][c] = sum / L[c][c];
            }
        }
    return L;
}

/// L^-1 b (forward substitution).
std::vector<DD> lower_solve(const std::vector<std::vector<DD>>& L, std::vector<DD> b) {
    for (std::size_t r = 0; r < b.size(); ++r) {
        for (std::size_t k = 0; k < r; ++k) b[r] -= L[r][k] * b[k];
        b[r] = b[r] / L[r][r];
    }
    return b;
}

/// L^-T b (back substitution).
std::vector<DD> upper_solve(const std::vector<std::vector<DD>>& L, std::vector<DD> b) {
    for (std::size_t r = b.size(); r-- > 0;) {
        for (std::size_t k = r + 1; k < b.size(); ++k) b[r] -= L[k][r] * b[k];
        b[r] = b[r] / L[r][r];
    }
    return b;
}

/// The lower Cholesky factor of a symmetric A, or none where A is not positive
/// definite or is regular by rounding only (a diagonal of the factor below 1e-7
/// of its largest).
std::vector<std::vector<DD>> cholesky(const std::vector<std::vector<DD>>& A) {
    const std::size_t n = A.size();
    std::vector<std::vector<DD>> L(n, std::vector<DD>(n));
    double lo = INFINITY, hi = 0.0;
    for (std::size_t r = 0; r < n; ++r)
        for (std::size_t c = 0; c <= r; ++c) {
            DD sum = A[r][c];
            for (std::size_t k = 0; k < c; ++k) sum -= L[r][k] * L[c][k];
            if (r != c) {
                L[r][c] = sum / L[c][c];
                continue;
            }
            if (!(sum > DD(0.0))) return {};
            L[r][r] = sqrt(sum);
            lo = std::min(lo, L[r][r].to_double());
            hi = std::max(hi, L[r][r].to_double());
        }
    if (!(lo > 1e-7 * hi)) return {};
    return L;
}

/// The state matrix in the energy scaling (state_space_solver.h): with K = Uk^T Uk and
/// M = Um^T Um (Lk, Lm their lower factors, U = L^T), zb = (Uk x, Um v) obeys zb' = S zb,
/// S = [0, G; -G^T, -Um^-T C Um^-1], G = Uk Um^-1: skew-symmetric but for the damping, so that
/// the eigenvectors' condition measures closeness to critical damping, not the spread of the
/// natural frequencies (in (x, v/s) a finite-element structure's read as defective). False
/// (nothing set) where K is singular.
bool energy_scaled(const std::vector<std::vector<DD>>& K, const std::vector<std::vector<DD>>& C,
                   const std::vector<std::vector<DD>>& M, std::vector<std::vector<DD>>& Lk,
                   std::vector<std::vector<DD>>& Lm, std::vector<std::vector<DD>>& S) {
    const std::size_t nf = K.size();
    Lk = cholesky(K);
    Lm = cholesky(M);
    if (nf == 0 || Lk.empty() || Lm.empty()) return false;
    std::vector<std::vector<DD>> Uminv(nf);  // columns of Um^-1 = Lm^-T
    for (std::size_t c = 0; c < nf; ++c) {
        std::vector<DD> e(nf);
        e[c] = DD(1.0);
        Uminv[c] = upper_solve(Lm, std::move(e));
    }
    std::vector<std::vector<DD>> CU(nf, std::vector<DD>(nf));  // C Um^-1, by columns
    for (std::size_t c = 0; c < nf; ++c)
        for (std::size_t a = 0; a < nf; ++a)
            for (std::size_t b = 0; b <= c; ++b) CU[c][a] += C[a][b] * Uminv[c][b];  // Um^-1 is upper
    S.assign(2 * nf, std::vector<DD>(2 * nf));
    for (std::size_t r = 0; r < nf; ++r)
        for (std::size_t c = 0; c < nf; ++c) {
            DD g(0.0), cb(0.0);
            for (std::size_t k = r; k < nf; ++k) g += Lk[k][r] * Uminv[c][k];  // (Uk Um^-1)[r][c]
            for (std::size_t a = 0; a <= r; ++a) cb += Uminv[r][a] * CU[c][a];  // (Um^-T C Um^-1)[r][c]
            S[r][nf + c] = g;
            S[nf + c][r] = -g;
            S[nf + r][nf + c] = -cb;
        }
    return true;
}

/// Eigenvectors and the inverse's rows of energy_scaled()'s S back to z = (x, v): psi =
/// (Uk^-1 psi_x, Um^-1 psi_v), l = (l_x Uk, l_v Um).
void energy_unscaled(const std::vector<std::vector<DD>>& Lk, const std::vector<std::vector<DD>>& Lm,
                     DdComplexEigen& eig) {
    const std::size_t nf = Lk.size();
    auto part = [&](const std::vector<DDComplex>& z, std::size_t at, bool im) {
        std::vector<DD> p(nf);
        for (std::size_t i = 0; i < nf; ++i) p[i] = im ? z[at + i].im : z[at + i].re;
        return p;
    };
    for (std::size_t k = 0; k < eig.vectors.size(); ++k) {
        std::vector<DDComplex>& v = eig.vectors[k];
        std::vector<DDComplex>& l = eig.inverse[k];
        for (std::size_t half = 0; half < 2; ++half) {
            const auto& L = half == 0 ? Lk : Lm;
            const std::size_t at = half * nf;
            const std::vector<DD> re = upper_solve(L, part(v, at, false)), im = upper_solve(L, part(v, at, true));
            const std::vector<DD> lre = part(l, at, false), lim = part(l, at, true);
            for (std::size_t c = 0; c < nf; ++c) {
                v[at + c] = DDComplex(re[c], im[c]);
                DD a(0.0), b(0.0);  // (l U)_c = sum_{r <= c} l_r L[c][r]
                for (std::size_t r = 0; r <= c; ++r) a += lre[r] * L[c][r], b += lim[r] * L[c][r];
                l[at + c] = DDComplex(a, b);
            }
        }
    }
}

/// The pseudo-modes, static inverse and harmonic particular parts of a
/// configuration with dampers (StateSpaceData, derivation.h), in DD.
void derive_state_space(Derivation& d, const std::vector<std::vector<int>>& group, const std::vector<DD>& mass) {
    const Model& model = *d.model;
    const std::size_t nf = group.size(), ns = 2 * nf;
    const std::string where = "derivation::derive(): configuration " + d.cfg.spec(model) + ": ";
    if (!free_components(model, d.cfg).floating_members().empty())
        throw NotDerivable(where + "rigid-body modes under dampers");
    d.state_space = true;
    const auto K = folded(d.k_dd, group), C = folded(d.c_dd, group);
    // Coupled M (no riders there: group[r] = {free_dofs[r]}): M_FF^-1 K and M_FF^-1 C by its Cholesky factor.
    const bool coupled = model.coupled_mass();
    std::vector<std::vector<DD>> MK, MC, Mff;
    if (coupled) {
        const auto L = mass_cholesky(d, where);
        MK.assign(nf, std::vector<DD>(nf)), MC = MK, Mff = MK;
        for (std::size_t c = 0; c < nf; ++c) {
            std::vector<DD> k(nf), cc(nf);
            for (std::size_t r = 0; r < nf; ++r) {
                k[r] = K[r][c], cc[r] = C[r][c];
                Mff[r][c] = DD(free_mass(d, r, c));
            }
            k = upper_solve(L, lower_solve(L, std::move(k)));
            cc = upper_solve(L, lower_solve(L, std::move(cc)));
            for (std::size_t r = 0; r < nf; ++r) MK[r][c] = k[r], MC[r][c] = cc[r];
        }
    }
    // Balanced as the state-space solver balances it: in the energy scaling where K_FF is
    // regular (energy_scaled()), else y = (x, v / s), s the power of 2 nearest the largest
    // sqrt(K_rr / m_r) (else C_rr / m_r), so that the eigenvectors' condition measures the
    // modes, not the units (unbalanced, a 16-mass chain's configurations went from condition
    // ~10 to above 200).
    double w2 = 0.0, rate = 0.0;
    for (std::size_t r = 0; r < nf; ++r) {
        w2 = std::max(w2, (K[r][r] / mass[r]).to_double());
        rate = std::max(rate, (C[r][r] / mass[r]).to_double());
    }
    const double s_double = w2 > 0.0 ? std::sqrt(w2) : rate > 0.0 ? rate : 1.0;
    // Where K_FF is regular, the energy scaling instead (energy_scaled()), s = 1.
    std::vector<std::vector<DD>> S(ns, std::vector<DD>(ns)), Lk, Lm, Mfull = Mff;
    if (!coupled) {
        Mfull.assign(nf, std::vector<DD>(nf));
        for (std::size_t r = 0; r < nf; ++r) Mfull[r][r] = mass[r];
    }
    const bool scaled = energy_scaled(K, C, Mfull, Lk, Lm, S);
    const DD s_scale(scaled ? 1.0 : std::ldexp(1.0, static_cast<int>(std::lround(std::log2(s_double)))));  // exact
    double norm = 0.0;
    for (std::size_t r = 0; r < nf && !scaled; ++r) {
        S[r][nf + r] = s_scale;
        for (std::size_t c = 0; c < nf; ++c) {
            if (coupled) {
                S[nf + r][c] = -MK[r][c] / s_scale;
                S[nf + r][nf + c] = -MC[r][c];
                continue;
            }
            if (!K[r][c].is_zero()) S[nf + r][c] = -K[r][c] / (mass[r] * s_scale);
            if (!C[r][c].is_zero()) S[nf + r][nf + c] = -C[r][c] / mass[r];
        }
    }
    for (const auto& row : S)
        for (const DD& e : row) norm = std::max(norm, std::fabs(e.to_double()));
    DdComplexEigen eig;
    try {
        eig = dd_complex_eigen(S);
    } catch (const RunError& e) {
        throw NotDerivable(where + e.what());
    }
    if (scaled) energy_unscaled(Lk, Lm, eig);
    StateSpaceData& st = d.state;
    for (std::size_t k = 0; k < ns; ++k) {  // back to z = (x, v): Psi_v = s Psi_y,v, L_v = L_y,v / s
        st.values.push_back(eig.values[k]);
        st.vectors.emplace_back();
        st.inverse.emplace_back();
        for (std::size_t i = 0; i < ns; ++i) {
            const DDComplex &v = eig.vectors[k][i], &l = eig.inverse[k][i];
            st.vectors[k].push_back(i < nf ? v : DDComplex(v.re * s_scale, v.im * s_scale));
            st.inverse[k].push_back(i < nf ? l : DDComplex(l.re / s_scale, l.im / s_scale));
        }
    }
    // Pseudo-modes in ascending |mu| (then Im mu): one per real mu, two per pair.
    std::vector<std::size_t> order;
    for (std::size_t k = 0; k < ns; ++k)
        if (st.values[k].im >= DD(0.0)) order.push_back(k);
    auto mag2 = [](const DDComplex& z) { return z.re * z.re + z.im * z.im; };
    std::stable_sort(order.begin(), order.end(), [&](std::size_t a, std::size_t b) {
        const DD ma = mag2(st.values[a]), mb = mag2(st.values[b]);
        return ma != mb ? ma < mb : st.values[a].im < st.values[b].im;
    });
    // A real part within the refinement's rounding (1024 units of 2^-104 of max |S|)
    // is zero: the mode is undamped; below that it grows.
    const DD undamped_tol(1e-25 * norm);
    for (std::size_t k : order) {
        const DDComplex mu = st.values[k];
        const DD sigma = -mu.re, om = mu.im;
        if (sigma < -undamped_tol)
            throw RunError(where + "a state-space mode grows (Re mu = " + std::to_string(mu.re.to_double()) + ")");
        const std::vector<DDComplex>& psi = st.vectors[k];
        const std::vector<DDComplex>& L = st.inverse[k];
        for (int part = 0; part < (om.is_zero() ? 1 : 2); ++part) {
            // part 0: Re (u), part 1: Im (w) of c e^{mu tau}.
            auto take = [&](const DDComplex& z) { return part == 0 ? z.re : z.im; };
            Mode m;
            if (om.is_zero()) {
                if (!(sigma > DD(0.0))) throw NotDerivable(where + "a zero state-space eigenvalue under dampers");
                m.regime = Regime::critical;
                m.sigma = sigma;
                m.lambda = m.sigma * m.sigma;
                m.omega = m.sigma;
                m.xi = DD(1.0);
                m.kappa = DD(0.0);
            } else {
                const bool undamped = abs(sigma) <= undamped_tol;
                m.regime = undamped ? Regime::undamped : Regime::underdamped;
                m.sigma = undamped ? DD(0.0) : sigma;
                m.omega_d = om;
                m.kappa = m.omega_d * m.omega_d;
                m.lambda = m.sigma * m.sigma + m.kappa;
                m.omega = sqrt(m.lambda);
                m.xi = m.sigma / m.omega;
            }
            m.c = DD(2.0) * m.sigma;
            for (std::size_t r = 0; r < nf; ++r) {
                // x = sum (psi c e^{mu tau} + its conjugate) = 2 Re(psi) u - 2 Im(psi) w; a real mu: psi u.
                m.v.push_back(om.is_zero() ? psi[r].re : part == 0 ? DD(2.0) * psi[r].re : DD(-2.0) * psi[r].im);
                m.w.push_back(take(L[r]));
                m.w_v.push_back(take(L[nf + r]));
                m.dw_x.push_back(take(mu * L[r]));
                m.dw_v.push_back(take(mu * L[nf + r]));
            }
            d.modes.push_back(std::move(m));
        }
    }
    // K_FF^-1, column by column.
    std::vector<std::vector<DDComplex>> Kf(nf, std::vector<DDComplex>(nf));
    for (std::size_t r = 0; r < nf; ++r)
        for (std::size_t c = 0; c < nf; ++c) Kf[r][c] = K[r][c];
    st.static_inverse.assign(nf, std::vector<DD>(nf));
    for (std::size_t c = 0; c < nf; ++c) {
        std::vector<DDComplex> e(nf);
        e[c] = DD(1.0);
        if (!dd_solve(Kf, e)) throw NotDerivable(where + "a singular stiffness under dampers");
        for (std::size_t r = 0; r < nf; ++r) st.static_inverse[r][c] = e[r].re;
    }
    // Harmonics: X = (K - Omega^2 M + i Omega C)^-1 F.
    d.max_step = std::numeric_limits<double>::infinity();
    for (const Harmonic& h : model.forcing) {
        if (h.omega == 0.0) continue;
        HarmonicData hd = harmonic_data(h);
        const DD W = hd.omega;
        for (const Mode& m : d.modes) {
            if (m.regime == Regime::undamped && abs(W - m.omega) <= DD(kResonanceBand) * m.omega)
                throw NotDerivable(where + "forcing at " + std::to_string(h.omega) +
                                   " rad/s within 1% of an undamped state-space mode (" +
                                   std::to_string(m.omega.to_double()) + " rad/s)");
            hd.modal.push_back(ModalHarmonic{});
        }
        std::vector<std::vector<DDComplex>> Z(nf, std::vector<DDComplex>(nf));
        std::vector<DDComplex> X(nf);
        for (std::size_t r = 0; r < nf; ++r) {
            for (int i : group[r]) X[r].re += hd.amplitude[static_cast<std::size_t>(i)];
            for (std::size_t c = 0; c < nf; ++c)
                Z[r][c] = DDComplex(K[r][c] - (coupled ? W * W * Mff[r][c] : r == c ? W * W * mass[r] : DD(0.0)), W * C[r][c]);
        }
        if (!dd_solve(Z, X)) throw NotDerivable(where + "a singular dynamic stiffness at " + std::to_string(h.omega) + " rad/s");
        for (std::size_t r = 0; r < nf; ++r) {
            hd.xs.push_back(X[r].re);
            hd.xc.push_back(X[r].im);
        }
        d.harmonics.push_back(std::move(hd));
    }
}

}  // namespace

ex slider_preload(const Derivation& d, const SegmentInputs& in, int i) {
    const Model& model = *d.model;
    ex f = 0;
    for (std::size_t j = 0; j < model.jenkins.size(); ++j) {
        if (d.cfg.slip[j] != 0) continue;
        const Jenkins& e = model.jenkins[j];
        const ex p = exact(e.k) * in.x0[model.dof() + j];
        for_each_term(e.direction(), [&](int body, double w) {  // k s w_i (+-k s between two bodies)
            if (body == i) f += exact(w) * p;
        });
    }
    return f;
}

ex segment_force(const Derivation& d, const SegmentInputs& in, int i) {
    const Model& model = *d.model;
    ex f = d.f_const[i] - d.mu_k_n[i] * in.sgn[i] + slider_preload(d, in, i);
    for (std::size_t q = 0; q < model.dof(); ++q)  // a sliding friction pair: the opposite force on the partner
        if (model.friction_slot(q).partner == i) f += d.mu_k_n[q] * in.sgn[q];
    for (int s : d.stuck_dofs) f -= d.K(i, s) * in.x0[s];
    for (int r : d.riders)  // at its offset from the body it rides (a chain's: the first not stuck)
        f -= d.K(i, r) * (in.x0[r] - in.x0[carrier(model, d.cfg, static_cast<std::size_t>(r))]);
    return f;
}

ex coordinate_force(const Derivation& d, const SegmentInputs& in, std::size_t r) {
    const int p = d.free_dofs[r];
    ex f = segment_force(d, in, p);
    for (int q : d.riders)
        if (carrier(*d.model, d.cfg, static_cast<std::size_t>(q)) == p) f += segment_force(d, in, q);
    return f;
}

namespace {

// The free, stuck and riding masses of cfg (d.free_dofs, d.stuck_dofs,
// d.riders), and the masses of each free coordinate: its free mass, then its
// riders (T of x = T q + e). A coupled M has no riders (the reader refuses
// friction between two dofs on it).
std::vector<std::vector<int>> coordinates(const Model& model, const Configuration& cfg, Derivation& d,
                                          std::vector<int>& free_index) {
    const std::size_t n = model.dof();
    free_index.assign(n, -1);
    for (std::size_t i = 0; i < n; ++i) {
        if (fixed_in(model, cfg, i)) {
            d.stuck_dofs.push_back(static_cast<int>(i));
        } else if (rides_partner(model, cfg, i)) {
            d.riders.push_back(static_cast<int>(i));
        } else {
            free_index[i] = static_cast<int>(d.free_dofs.size());
            d.free_dofs.push_back(static_cast<int>(i));
        }
    }
    if (model.coupled_mass() && !d.riders.empty())
        throw NotDerivable("derivation::derive(): configuration " + cfg.spec(model) +
                           ": a friction between two dofs of a coupled (non-diagonal) mass matrix");
    std::vector<std::vector<int>> group(d.free_dofs.size());
    for (std::size_t r = 0; r < d.free_dofs.size(); ++r) group[r].push_back(d.free_dofs[r]);
    for (int q : d.riders)
        group[static_cast<std::size_t>(free_index[carrier(model, cfg, static_cast<std::size_t>(q))])].push_back(q);
    return group;
}

/// The symmetric A = L^-1 K_FF L^-T of a coupled M = L L^T (the generalized
/// eigenproblem K v = lambda M v as A y = lambda y, v = L^-T y).
std::vector<std::vector<DD>> coupled_kt(const std::vector<std::vector<DD>>& K, const std::vector<std::vector<DD>>& L) {
    const std::size_t nf = K.size();
    std::vector<std::vector<DD>> B(nf), A(nf, std::vector<DD>(nf));  // B[c] = L^-1 K e_c; A = L^-1 B^T
    for (std::size_t c = 0; c < nf; ++c) {
        std::vector<DD> col(nf);
        for (std::size_t r = 0; r < nf; ++r) col[r] = K[r][c];
        B[c] = lower_solve(L, std::move(col));
    }
    for (std::size_t r = 0; r < nf; ++r) {
        std::vector<DD> row(nf);
        for (std::size_t c = 0; c < nf; ++c) row[c] = B[c][r];  // (L^-1 K)^T's column r
        const std::vector<DD> a = lower_solve(L, std::move(row));
        for (std::size_t c = 0; c < nf; ++c) A[c][r] = a[c];
    }
    for (std::size_t r = 0; r < nf; ++r)  // symmetric to the last bit: the mean of the two rounded halves
        for (std::size_t c = r + 1; c < nf; ++c) A[r][c] = A[c][r] = (A[r][c] + A[c][r]) / DD(2.0);
    return A;
}

/// The eigenpairs of the symmetric kt in ascending order (value[j], vector[j][r]):
/// mp_eigen.h refined, else (or when it does not converge) Jacobi, which
/// diagonalises kt in place.
void symmetric_eigenpairs(std::vector<std::vector<DD>>& kt, EigenMethod method, DerivationCache* cache,
                          std::vector<DD>& eig_value, std::vector<std::vector<DD>>& eig_vector) {
    const std::size_t nf = kt.size();
    eig_value.assign(nf, DD());
    eig_vector.assign(nf, {});
    bool solved = false;
    if (method == EigenMethod::refined) {
        try {
            std::vector<DdEigenpair> pairs = dd_symmetric_eigen(kt, cache ? &cache->eigen : nullptr);
            for (std::size_t j = 0; j < nf; ++j) {
                eig_value[j] = pairs[j].value;
                eig_vector[j] = std::move(pairs[j].vector);
            }
            solved = true;
        } catch (const RunError&) {
            // Not converged (never seen): Jacobi below, slower but unconditional.
        }
    }
    if (!solved) {
        std::vector<std::vector<DD>> phi;
        dd_jacobi_eigen(kt, phi);
        std::vector<std::size_t> order(nf);
        std::iota(order.begin(), order.end(), 0);
        std::stable_sort(order.begin(), order.end(),
                         [&](std::size_t p, std::size_t q) { return kt[p][p] < kt[q][q]; });
        for (std::size_t j = 0; j < nf; ++j) {
            eig_value[j] = kt[order[j]][order[j]];
            eig_vector[j].resize(nf);
            for (std::size_t r = 0; r < nf; ++r) eig_vector[j][r] = phi[r][order[j]];
        }
    }
}

/// The regime of mode m from its lambda and c (u'' + c u' + lambda u = ...), and
/// the constants of its closed form.
void set_regime(Mode& m, const DD& critical_tol) {
    if (m.lambda.is_zero()) {
        m.omega = DD(0.0);
        m.xi = DD(0.0);
        if (m.c.is_zero()) {
            m.regime = Regime::rigid;
            m.sigma = m.kappa = m.omega_d = m.gamma = m.r1 = DD(0.0);
        } else {
            // u = A + B (1 - e^{-c tau})/c as the overdamped form with lambda = 0.
            m.regime = Regime::rigid_damped;
            m.sigma = m.gamma = m.c / DD(2.0);
            m.kappa = -m.sigma * m.sigma;
            m.r1 = DD(0.0);
            m.omega_d = DD(0.0);
        }
    } else {
        m.omega = sqrt(m.lambda);
        m.sigma = m.c / DD(2.0);
        m.xi = m.sigma / m.omega;
        m.kappa = m.lambda - m.sigma * m.sigma;
        if (m.c.is_zero()) {
            m.regime = Regime::undamped;
            m.omega_d = m.omega;
        } else if (abs(m.xi - DD(1.0)) <= critical_tol) {
            m.regime = Regime::critical;
            m.kappa = DD(0.0);
        } else if (m.xi < DD(1.0)) {
            m.regime = Regime::underdamped;
            m.omega_d = sqrt(m.kappa);
        } else {
            m.regime = Regime::overdamped;
            m.gamma = sqrt(-m.kappa);
            m.r1 = -m.lambda / (m.sigma + m.gamma);  // = -sigma + gamma without cancellation
        }
    }
}

/// Rigid-body mode j of a coupled M in the coordinates y = L^T x: L^T e_c of
/// the component's members, made orthonormal to the rigid modes 0..j-1.
std::vector<DD> rigid_shape(const std::vector<std::vector<DD>>& L, const std::vector<int>& members,
                            const std::vector<int>& free_index, const std::vector<std::vector<DD>>& before, std::size_t j) {
    const std::size_t nf = L.size();
    std::vector<DD> y(nf);
    for (int i : members) {
        const std::size_t r = static_cast<std::size_t>(free_index[static_cast<std::size_t>(i)]);
        for (std::size_t k = 0; k <= r; ++k) y[k] += L[r][k];
    }
    for (std::size_t p = 0; p < j; ++p) {
        DD dot;
        for (std::size_t k = 0; k < nf; ++k) dot += y[k] * before[p][k];
        for (std::size_t k = 0; k < nf; ++k) y[k] -= dot * before[p][k];
    }
    DD norm2;
    for (const DD& e : y) norm2 += e * e;
    const DD inv = DD(1.0) / sqrt(norm2);
    for (DD& e : y) e = e * inv;
    return y;
}

/// mu N of each friction mass into the cache, exact products (GiNaC
/// arithmetic: once per run with a cache).
void friction_limits(const Model& model, DerivationCache& mu) {
    const std::size_t n = model.dof();
    if (mu.mu_k_n.size() == n) return;
    mu.mu_k_n.assign(n, kZero);
    mu.mu_k_n_double.assign(n, 0.0);
    mu.mu_s_n.assign(n, 0.0);
    for (std::size_t i = 0; i < n; ++i) {
        if (!model.has_friction(i)) continue;
        const numeric N = exact_normal(model, i);
        mu.mu_k_n[i] = exact(model.friction_slot(i).mu_k) * N;
        mu.mu_k_n_double[i] = mu.mu_k_n[i].to_double();
        mu.mu_s_n[i] = (exact(model.friction_slot(i).mu_s) * N).to_double();
    }
}

/// Derivation::held of a coupled M = L L^T over the free dofs: per stuck dof
/// i, c = M_FF^-1 M_Fi by two triangular solves.
void held_rows(Derivation& d, const std::vector<std::vector<DD>>& L) {
    const std::size_t nf = d.free_dofs.size();
    for (int i : d.stuck_dofs) {
        std::vector<DD> b(nf);
        for (std::size_t r = 0; r < nf; ++r)
            b[r] = DD(d.model->mass_entry(static_cast<std::size_t>(d.free_dofs[r]), static_cast<std::size_t>(i)));
        d.held.push_back(nf > 0 ? upper_solve(L, lower_solve(L, std::move(b))) : std::move(b));
    }
}

/// A harmonic with Omega = 0 is the constant force F sin(phase): added to
/// d.f_const exactly, the sums rounded once into d.f_const_double.
void add_static_forcing(const Model& model, Derivation& d) {
    const std::size_t n = model.dof();
    bool static_forcing = false;
    for (const Harmonic& h : model.forcing) {
        if (h.omega != 0.0) continue;
        const numeric s = GiNaC::sin(exact(h.phase));
        for (std::size_t i = 0; i < n; ++i) d.f_const[i] += exact(h.amplitude[i]) * s;
        static_forcing = true;
    }
    if (static_forcing)
        for (std::size_t i = 0; i < n; ++i) d.f_const_double[i] = d.f_const[i].to_double();
}

// C += c w w^T of every contact closed in cfg with a damping c of its own
// (contact.h), exactly and in double-double: non-proportional damping.
void add_contact_damping(const Model& model, const Configuration& cfg, Derivation& d) {
    for (std::size_t e = 0; e < model.contacts.size(); ++e) {
        const Contact& ct = model.contacts[e];
        if (!cfg.closed[e] || ct.c == 0.0) continue;
        for_each_term(ct.direction(), [&](int i, double wi) {
            for_each_term(ct.direction(), [&](int j, double wj) {
                d.C(i, j) = d.C(i, j) + exact(ct.c) * exact(wi) * exact(wj);
                d.c_dd[static_cast<std::size_t>(i)][static_cast<std::size_t>(j)] += DD(ct.c) * DD(wi) * DD(wj);
            });
        });
    }
}

}  // namespace

Derivation derive(const Model& model, const Configuration& cfg, EigenMethod method, ExactMatrices exact_matrices,
                  DerivationCache* cache) {
    GiNaC::Digits = kDerivationDigits;
    Derivation d;
    d.model = &model;
    d.cfg = cfg;
    d.switches = switch_functions(model, cfg);
    const std::size_t n = model.dof();
    std::vector<int> free_index;  // per mass: its free coordinate, or -1
    const std::vector<std::vector<int>> group = coordinates(model, cfg, d, free_index);

    // Full K(cfg), C = alpha M + beta K(cfg), constant forces, as exact rationals.
    const Eigen::MatrixXd K = stiffness_matrix(model, cfg);
    const Eigen::VectorXd f0 = constant_force(model, cfg);
    const bool with_exact = exact_matrices == ExactMatrices::yes || !model.proportional_damping();
    if (with_exact) {
        d.K = GiNaC::matrix(n, n);
        d.C = GiNaC::matrix(n, n);
    }
    d.k_dd.assign(n, std::vector<DD>(n));
    d.c_dd.assign(n, std::vector<DD>(n));
    const numeric alpha = exact(model.alpha), beta = exact(model.beta);
    const bool coupled = model.coupled_mass();
    for (std::size_t i = 0; i < n; ++i)
        for (std::size_t j = 0; j < n; ++j) {
            const double mij = model.mass_entry(i, j);
            if (i != j && K(i, j) == 0.0 && mij == 0.0) continue;  // both stay the exact 0 they start as
            if (with_exact) {
                const numeric kij = exact(K(i, j));
                d.K(i, j) = kij;
                d.C(i, j) = beta * kij + (i == j || coupled ? alpha * exact(mij) : kZero);
            }
            d.k_dd[i][j] = DD(K(i, j));
            d.c_dd[i][j] = DD(model.beta) * DD(K(i, j)) + (i == j || coupled ? DD(model.alpha) * DD(mij) : DD(0.0));
        }
    add_contact_damping(model, cfg, d);
    for (const Damper& dm : model.dampers) {  // non-proportional damping: added as K adds a spring
        const numeric c = exact(dm.c);
        for (int a : {dm.a, dm.b})
            if (a != kGround) d.C(a, a) = d.C(a, a) + c, d.c_dd[a][a] += DD(dm.c);
        if (dm.a != kGround && dm.b != kGround) {
            d.C(dm.a, dm.b) = d.C(dm.a, dm.b) - c;
            d.C(dm.b, dm.a) = d.C(dm.b, dm.a) - c;
            d.c_dd[dm.a][dm.b] -= DD(dm.c);
            d.c_dd[dm.b][dm.a] -= DD(dm.c);
        }
    }
    d.f_const.resize(n);
    DerivationCache local;
    DerivationCache& mu = cache ? *cache : local;
    friction_limits(model, mu);
    d.mu_k_n.assign(n, kZero);
    d.mu_k_n_double.assign(n, 0.0);
    d.mu_s_n = mu.mu_s_n;
    d.f_const_double.resize(n);
    for (std::size_t i = 0; i < n; ++i) {
        d.f_const[i] = exact(f0(i));
        d.f_const_double[i] = f0(i) + 0.0;  // what the exact value of f0(i) rounds to (-0 is 0 there)
        if (model.has_friction(i) && !cfg.stuck[i])
            d.mu_k_n[i] = mu.mu_k_n[i], d.mu_k_n_double[i] = mu.mu_k_n_double[i];
    }
    add_static_forcing(model, d);

    // Modal decomposition of Kt = M^-1/2 K_FF M^-1/2, in DD.
    const std::size_t nf = d.free_dofs.size();
    std::vector<DD> mass_dd(nf), sqm(nf);
    d.mass.assign(nf, kZero);
    for (std::size_t r = 0; r < nf; ++r) {
        for (int i : group[r]) {
            d.mass[r] += exact(model.masses[static_cast<std::size_t>(i)].m);
            mass_dd[r] += DD(model.masses[static_cast<std::size_t>(i)].m);
        }
        sqm[r] = sqrt(mass_dd[r]);
    }
    const std::string where = "derivation::derive(): configuration " + cfg.spec(model) + ": ";
    const std::vector<std::vector<DD>> chol = coupled ? mass_cholesky(d, where) : std::vector<std::vector<DD>>{};
    if (coupled) held_rows(d, chol);
    if (!model.proportional_damping()) {
        derive_state_space(d, group, mass_dd);
        return d;
    }
    // Coupled M: A = L^-1 K_FF L^-T (M_FF = L L^T). Lumped: T^T K T / sqrt(m_r m_s).
    std::vector<std::vector<DD>> kt = folded(d.k_dd, group);
    if (coupled) {
        kt = coupled_kt(kt, chol);
    } else {
        for (std::size_t r = 0; r < nf; ++r)
            for (std::size_t s = 0; s < nf; ++s)
                if (!kt[r][s].is_zero()) kt[r][s] = kt[r][s] / (sqm[r] * sqm[s]);  // a zero stays the exact 0
    }
    // Stiffness over mass beyond double's range (k/m = 1e400): no constant of
    // the program could hold it; the Eigen solver takes the configuration and
    // the engine says what is wrong (the motion too fast to resolve).
    for (std::size_t r = 0; r < nf; ++r)
        for (std::size_t s = 0; s < nf; ++s)
            if (!std::isfinite(kt[r][s].to_double()))
                throw NotDerivable("derivation::derive(): configuration " + cfg.spec(model) +
                                   ": stiffness over mass beyond the range of double");
    // eig_value[j], eig_vector[j][r]: the eigenpairs of Kt in ascending order.
    std::vector<DD> eig_value;
    std::vector<std::vector<DD>> eig_vector;
    symmetric_eigenpairs(kt, method, cache, eig_value, eig_vector);

    // Rigid-body modes replace the smallest eigenpairs: lambda = 0, shape sqrt(m) on the component
    // (coupled M: y = L^T e_c, orthonormalised against the rigid modes before it, as M may couple components).
    const auto comps = free_components(model, cfg).floating_members();  // free_components.h
    std::vector<DD> lambda(nf);
    std::vector<std::vector<DD>> shape(nf);  // shape[j][r] = Phi_rj
    std::vector<std::vector<std::size_t>> support(nf);             // r with shape[j][r] != 0, ascending
    for (std::size_t j = 0; j < nf; ++j) {
        if (j < comps.size() && coupled) {
            shape[j] = rigid_shape(chol, comps[j], free_index, shape, j);
            lambda[j] = DD(0.0);
        } else if (j < comps.size()) {
            DD m_total;
            for (int i : comps[j]) m_total += mass_dd[static_cast<std::size_t>(free_index[i])];
            const DD inv = DD(1.0) / sqrt(m_total);
            shape[j].assign(nf, DD());
            for (int i : comps[j]) shape[j][free_index[i]] = sqm[free_index[i]] * inv;
            lambda[j] = DD(0.0);
        } else {
            lambda[j] = eig_value[j];
            shape[j] = std::move(eig_vector[j]);
            if (lambda[j] <= DD(0.0))
                throw RunError("derivation::derive(): eigenvalue " + std::to_string(lambda[j].to_double()) +
                               " <= 0 in a mode not detected as rigid (configuration " + cfg.spec(model) + ")");
        }
        // The mode's support: the free coordinates of its block, where its shape is
        // nonzero (mp_eigen.h solves each block apart; elsewhere the shape is the
        // exact 0). The loops below visit the support alone: a zero entry's terms
        // are exact zeros, which change no sum, so the numbers are those of the
        // dense loops, at a cost that grows with the blocks rather than with nf^2.
        for (std::size_t r = 0; r < nf; ++r)
            if (!shape[j][r].is_zero()) support[j].push_back(r);
        // Deterministic sign: the largest component is positive (a zero never is).
        std::size_t big = 0;
        for (std::size_t r : support[j])
            if (r > 0 && abs(shape[j][r]) > abs(shape[j][big]) + DD(1e-6)) big = r;
        if (shape[j][big] < DD(0.0))
            for (std::size_t r : support[j]) shape[j][r] = -shape[j][r];
    }

    const DD critical_tol(1e-20), alpha_dd(model.alpha), beta_dd(model.beta);
    // 1 / sqrt(m_r) once per coordinate, not a division per entry of V (in
    // double-double: the doubles V rounds to are those of the division but
    // where the two straddle a midpoint, about one in 1e16).
    std::vector<DD> inv_sqm(nf);
    for (std::size_t r = 0; r < nf; ++r) inv_sqm[r] = DD(1.0) / sqm[r];
    for (std::size_t j = 0; j < nf; ++j) {
        Mode m;
        m.lambda = lambda[j];
        m.c = alpha_dd + beta_dd * lambda[j];
        m.v.resize(nf);
        m.w.resize(nf);
        if (coupled) {  // v = L^-T y (V^T M V = I), w = L y = M v (q = W x): dense
            m.v = upper_solve(chol, shape[j]);
            for (std::size_t r = 0; r < nf; ++r)
                for (std::size_t k = 0; k <= r; ++k) m.w[r] += chol[r][k] * shape[j][k];
            support[j].resize(nf);
            std::iota(support[j].begin(), support[j].end(), std::size_t{0});
        } else {
            for (std::size_t r : support[j]) {
                m.v[r] = shape[j][r] * inv_sqm[r];
                m.w[r] = shape[j][r] * sqm[r];
            }
        }
        set_regime(m, critical_tol);
        d.modes.push_back(std::move(m));
    }

    // Forcing harmonics: modal amplitudes and particular solutions.
    d.max_step = std::numeric_limits<double>::infinity();
    for (const Harmonic& h : model.forcing) {
        if (h.omega == 0.0) continue;
        HarmonicData hd = harmonic_data(h);
        hd.xs.assign(nf, DD(0.0));
        hd.xc.assign(nf, DD(0.0));
        const DD& W = hd.omega;
        for (std::size_t j = 0; j < d.modes.size(); ++j) {
            const Mode& m = d.modes[j];
            ModalHarmonic mh;
            for (std::size_t r : support[j])
                for (int i : group[r]) mh.P += m.v[r] * hd.amplitude[static_cast<std::size_t>(i)];
            mh.resonant = m.regime == Regime::undamped && abs(W - m.omega) <= DD(kResonanceBand) * m.omega;
            if (mh.resonant) {
                d.max_step = std::min(d.max_step, 2 * 3.14159265358979323846 / h.omega);
            } else {
                // u_p = P [(lambda - W^2) sin - c W cos] / ((lambda - W^2)^2 + (c W)^2)
                const DD det = m.lambda - W * W, den = det * det + m.c * m.c * W * W;
                mh.a_s = det / den;
                mh.a_c = -m.c * W / den;
                for (std::size_t r : support[j]) {
                    hd.xs[r] += m.v[r] * mh.P * mh.a_s;
                    hd.xc[r] += m.v[r] * mh.P * mh.a_c;
                }
            }
            hd.modal.push_back(mh);
        }
        d.harmonics.push_back(std::move(hd));
    }
    return d;
}

namespace {

/// The free coordinates' x(tau) of a configuration with dampers, in the
/// textbook form z(tau) = z_p(tau) + sum_k Psi_k e^{mu_k tau} L_k (z(0) - z_p(0)),
/// each conjugate pair written with e^{-sigma tau} cos and sin: independent of
/// the pseudo-modes (only the eigenpairs are shared), with x_st and each
/// harmonic's particular part solved exactly from the folded K, C, M by GiNaC.
std::vector<ex> state_space_response(const Derivation& d, const SegmentInputs& in, const std::vector<ex>& f,
                                     const std::vector<ex>& theta, const GiNaC::symbol& tau) {
    const std::size_t nf = d.n_free();
    GiNaC::matrix K(nf, nf), C(nf, nf);
    for (std::size_t i = 0; i < d.model->dof(); ++i)
        for (std::size_t k = 0; k < d.model->dof(); ++k) {
            const int r = d.coordinate(static_cast<int>(i)), s = d.coordinate(static_cast<int>(k));
            if (r < 0 || s < 0) continue;
            K(r, s) = K(r, s) + d.K(i, k);
            C(r, s) = C(r, s) + d.C(i, k);
        }
    GiNaC::matrix fv(nf, 1);
    for (std::size_t r = 0; r < nf; ++r) fv(r, 0) = f[r];
    const GiNaC::matrix x_st = K.inverse().mul(fv);
    std::vector<ex> x(nf), xh(nf), vh(nf);
    for (std::size_t r = 0; r < nf; ++r) {
        x[r] = x_st(r, 0);
        xh[r] = in.x0[d.free_dofs[r]] - x_st(r, 0);
        vh[r] = in.v0[d.free_dofs[r]];
    }
    for (std::size_t h = 0; h < d.harmonics.size(); ++h) {
        const HarmonicData& hd = d.harmonics[h];
        const numeric W = lf(hd.omega);
        GiNaC::matrix Z(nf, nf), F(nf, 1);
        for (std::size_t r = 0; r < nf; ++r)
            for (std::size_t s = 0; s < nf; ++s) {
                const numeric m_rs = d.model->coupled_mass() ? exact(free_mass(d, r, s)) : r == s ? d.mass[r] : kZero;
                Z(r, s) = K(r, s) - W * W * m_rs + GiNaC::I * W * C(r, s);
            }
        for (std::size_t i = 0; i < d.model->dof(); ++i)
            if (const int r = d.coordinate(static_cast<int>(i)); r >= 0) F(r, 0) = F(r, 0) + lf(hd.amplitude[i]);
        const GiNaC::matrix X = Z.inverse().mul(F);
        for (std::size_t r = 0; r < nf; ++r) {
            const numeric X_r = GiNaC::ex_to<numeric>(X(r, 0).evalf());
            const numeric re = X_r.real(), im = X_r.imag();
            const ex arg = W * tau + theta[h];
            x[r] += re * GiNaC::sin(arg) + im * GiNaC::cos(arg);
            xh[r] -= re * GiNaC::sin(theta[h]) + im * GiNaC::cos(theta[h]);
            vh[r] -= W * (re * GiNaC::cos(theta[h]) - im * GiNaC::sin(theta[h]));
        }
    }
    const StateSpaceData& st = d.state;
    for (std::size_t k = 0; k < st.values.size(); ++k) {
        const numeric mu = lfc(st.values[k]);
        if (mu.imag() < kZero) continue;  // the conjugate of a pair, written with its first
        const bool pair = mu.imag() > kZero;
        for (std::size_t r = 0; r < nf; ++r) {
            ex re = 0, im = 0;  // Psi_rk L_k z_h(0), real and imaginary parts
            for (std::size_t j = 0; j < 2 * nf; ++j) {
                const numeric pl = lfc(st.vectors[k][r]) * lfc(st.inverse[k][j]);
                const ex& zj = j < nf ? xh[j] : vh[j - nf];
                re += pl.real() * zj;
                im += pl.imag() * zj;
            }
            if (pair)
                x[r] += 2 * GiNaC::exp(mu.real() * tau) * (re * GiNaC::cos(mu.imag() * tau) - im * GiNaC::sin(mu.imag() * tau));
            else
                x[r] += GiNaC::exp(mu.real() * tau) * re;
        }
    }
    return x;
}

}  // namespace

SymbolicSegment symbolic_segment(const Derivation& d, const SegmentInputs& in, const GiNaC::symbol& tau) {
    GiNaC::Digits = kDerivationDigits;
    const Model& model = *d.model;
    const std::size_t n = model.dof(), nf = d.n_free();
    SymbolicSegment out;

    // Constant force on the free masses (paper Eq. 7-9).
    std::vector<ex> f(nf);
    for (std::size_t r = 0; r < nf; ++r) f[r] = coordinate_force(d, in, r);
    std::vector<ex> theta;
    for (const HarmonicData& h : d.harmonics) theta.push_back(lf(h.omega) * in.t0 + lf(h.phase));

    // The free coordinates' x(tau), when not from the modes below.
    std::vector<ex> xf;
    if (d.state_space) xf = state_space_response(d, in, f, theta, tau);
    for (std::size_t j = 0; j < d.modes.size() && !d.state_space; ++j) {
        const Mode& m = d.modes[j];
        const numeric lambda = lf(m.lambda), c = lf(m.c), omega = lf(m.omega), sigma = lf(m.sigma);
        const numeric omega_d = lf(m.omega_d), gamma = lf(m.gamma);
        ex p = 0, u0 = 0, du0 = 0;
        for (std::size_t r = 0; r < nf; ++r) {
            p += lf(m.v[r]) * f[r];
            u0 += lf(m.w[r]) * in.x0[d.free_dofs[r]];
            du0 += lf(m.w[r]) * in.v0[d.free_dofs[r]];
        }
        // Particular solution.
        ex up;
        if (m.regime == Regime::rigid) {
            up = p * GiNaC::pow(tau, 2) / 2;
        } else if (m.regime == Regime::rigid_damped) {
            up = p * tau / c;
        } else {
            up = p / lambda;
        }
        for (std::size_t h = 0; h < d.harmonics.size(); ++h) {
            const HarmonicData& hd = d.harmonics[h];
            const ModalHarmonic& mh = hd.modal[j];
            const numeric W = lf(hd.omega), P = lf(mh.P);
            const ex arg = W * tau + theta[h];
            const numeric det = lambda - W * W;
            // At (or within rounding of) exact resonance the textbook form is singular.
            if (mh.resonant && abs(det) <= lambda * numeric(1, 1000000000).power(3)) {
                up += -P * tau * GiNaC::cos(arg) / (2 * omega);  // exact resonance
            } else {
                const numeric den = det * det + c * c * W * W;
                up += P * (det * GiNaC::sin(arg) - c * W * GiNaC::cos(arg)) / den;
            }
        }
        const ex A = u0 - up.subs(tau == 0);
        const ex B = du0 - up.diff(tau).subs(tau == 0);  // u_h'(0)
        ex uh;
        switch (m.regime) {
            case Regime::undamped:
            case Regime::underdamped:
                uh = GiNaC::exp(-sigma * tau) *
                     (A * GiNaC::cos(omega_d * tau) + (B + sigma * A) / omega_d * GiNaC::sin(omega_d * tau));
                break;
            case Regime::critical:
                uh = GiNaC::exp(-sigma * tau) * (A + (B + sigma * A) * tau);
                break;
            case Regime::overdamped:
                uh = GiNaC::exp(-sigma * tau) *
                     (A * GiNaC::cosh(gamma * tau) + (B + sigma * A) / gamma * GiNaC::sinh(gamma * tau));
                break;
            case Regime::rigid:
                uh = A + B * tau;
                break;
            case Regime::rigid_damped:
                uh = A + B * (1 - GiNaC::exp(-c * tau)) / c;
                break;
        }
        out.u.push_back(uh + up);
    }

    const std::size_t nj = model.jenkins.size();
    out.x.assign(n + nj, 0);
    for (int s : d.stuck_dofs) out.x[s] = in.x0[s];
    for (std::size_t r = 0; r < nf; ++r) {
        if (d.state_space) out.x[d.free_dofs[r]] = xf[r];
        for (std::size_t j = 0; j < out.u.size(); ++j) out.x[d.free_dofs[r]] += lf(d.modes[j].v[r]) * out.u[j];
    }
    for (int q : d.riders) {  // at its segment-start offset from the body it rides
        const int p = carrier(model, d.cfg, static_cast<std::size_t>(q));
        out.x[q] = out.x[p] + (in.x0[q] - in.x0[p]);
    }
    for (std::size_t i = 0; i < n; ++i) {
        out.v.push_back(out.x[i].diff(tau));
        out.a.push_back(out.v[i].diff(tau));
    }
    // The motion the element files read (model/elements/): x(tau), v(tau).
    const ex* rows[] = {out.x.data(), out.v.data()};
    const RowsMotion<ex, decltype(rows)> motion(rows, nullptr, ex(0));
    // Sliders: fixed while stuck, the stretch held at slip F_s / k while slipping.
    for (std::size_t j = 0; j < nj; ++j) {
        const Jenkins& e = model.jenkins[j];
        out.x[n + j] = d.cfg.slip[j] == 0 ? in.x0[n + j]
                                          : along(e.direction(), motion, 0) -
                                                jenkins::held_stretch(d.cfg.slip[j], ex(exact(e.k)), ex(exact(e.slip_force)));
    }
    const auto elements = model_elements<ex>(model, [](double v) { return ex(exact(v)); },
                                             [&](int j) { return out.x[n + static_cast<std::size_t>(j)]; });
    for (const SwitchFunction& sf : d.switches) {
        ex g;
        if (!is_release(sf.kind)) {
            g = switch_derivative(elements, sf, motion, 0);
        } else {
            // A_i = -K x - C v + f_const + the stuck sliders' preload + forcing (interface.md section 2);
            // against a partner p, the force that holds the pair together,
            // D = (m_p A_i - m_i A_p)/(m_i + m_p) (assembly.h driving_force);
            // on a coupled M, D = A_i - M_iF a_F (model/held_mass.h).
            const int i = sf.element;
            auto force = [&](int b) {
                ex A = d.f_const[b] + slider_preload(d, in, b);
                for (std::size_t k = 0; k < n; ++k) A -= d.K(b, k) * out.x[k] + d.C(b, k) * out.v[k];
                for (std::size_t h = 0; h < d.harmonics.size(); ++h)
                    A += lf(d.harmonics[h].amplitude[b]) * GiNaC::sin(lf(d.harmonics[h].omega) * tau + theta[h]);
                return A;
            };
            ex A = force(i);
            if (model.shared_partner()) {
                // D_i = sum over S_i of f_k - m_k a_k (model/held_mass.h): f_k with the reactions of
                // the frictions sliding on k, a_k the body's acceleration (0 when held); a rider of a
                // partner carrying several: S_i = {i}, D = A_i - m_i a_i
                A = 0;
                for (int k : carried(model, d.cfg.stuck, i)) {
                    A += force(k) -
                         exact(model.masses[static_cast<std::size_t>(k)].m) * out.a[static_cast<std::size_t>(k)];
                    for (std::size_t q = 0; q < n; ++q)
                        if (model.friction_slot(q).partner == k && !d.cfg.stuck[q]) A += d.mu_k_n[q] * in.sgn[q];
                }
            } else if (const int p = model.friction_slot(static_cast<std::size_t>(i)).partner; p != kGround) {
                const numeric mi = exact(model.masses[static_cast<std::size_t>(i)].m), mp = exact(model.masses[static_cast<std::size_t>(p)].m);
                A = (mp * A - mi * force(p)) / (mi + mp);
            }
            if (model.coupled_mass())
                for (int r : d.free_dofs)
                    A -= exact(model.mass_entry(static_cast<std::size_t>(i), static_cast<std::size_t>(r))) * out.a[r];
            const numeric mu_s_n =
                exact(model.friction_slot(i).mu_s) * exact_normal(model, static_cast<std::size_t>(i));
            g = friction::release_value(sf.kind == SwitchKind::release_pos ? 1 : -1, A, ex(mu_s_n), 0);
        }
        out.g.push_back(g);
        out.dg.push_back(g.diff(tau));
    }
    return out;
}

}  // namespace hsnc
