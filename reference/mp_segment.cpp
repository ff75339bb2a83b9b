#include "mp_segment.h"

#include <algorithm>
#include <cmath>
#include <string>

#include <cln/integer.h>
#include <cln/rational.h>
#include <cln/real.h>

#include "assembly.h"
#include "elements/contact.h"
#include "elements/friction.h"
#include "elements/jenkins.h"
#include "elements/spring.h"
#include "elements/motion.h"
#include "switch_derivative.h"
#include "error.h"
#include "free_components.h"

namespace hsnc::reference {
namespace {

using cln::cl_I;
using cln::cl_RA;

bool is_zero(const cl_F& x) { return cln::zerop(x); }
cl_F sq(const cl_F& x) { return x * x; }

// phi_1(x) = (e^x - 1)/x and phi_2(x) = (e^x - 1 - x)/x^2 at N digits (the double
// code's one phi_2 is hsnc_phi2, kernels/kernel_abi.h; the reference keeps its own), by their Taylor
// series where the subtraction would cancel (|x| < 1/2), summed until the term
// drops below the format's roundoff.
cl_F phi1(const MpModel& mp, const cl_F& x) {
    if (cln::abs(x) < mp.half) {
        cl_F term = mp.one, sum = mp.one;  // x^k/(k+1)!
        for (long k = 1; k < 2000; ++k) {
            term = term * x / cl_I(k + 1);
            sum = sum + term;
            if (cln::abs(term) <= mp.eps * cln::abs(sum)) break;
        }
        return sum;
    }
    return (cln::exp(x) - mp.one) / x;
}
cl_F phi2(const MpModel& mp, const cl_F& x) {
    if (cln::abs(x) < mp.half) {
        cl_F term = mp.half, sum = mp.half;  // x^k/(k+2)!
        for (long k = 1; k < 2000; ++k) {
            term = term * x / cl_I(k + 2);
            sum = sum + term;
            if (cln::abs(term) <= mp.eps * cln::abs(sum)) break;
        }
        return sum;
    }
    return (cln::exp(x) - mp.one - x) / (x * x);
}

using CosSin = MpSegment::CosSin;

// The real and imaginary parts of z as floats of the format (an exact 0 included).
cl_F re_of(const MpModel& mp, const cln::cl_N& z) { return cln::cl_float(cln::realpart(z), mp.format); }
cl_F im_of(const MpModel& mp, const cln::cl_N& z) { return cln::cl_float(cln::imagpart(z), mp.format); }
CosSin cos_sin_of(const cl_F& x) {
    const cln::cos_sin_t cs = cln::cos_sin(x);
    return {cln::the<cl_F>(cs.cos), cln::the<cl_F>(cs.sin)};
}

// Cyclic Jacobi for the symmetric matrix A (n x n): A = V diag(d) V^T.
// Rotations as in Golub & Van Loan 8.5.2 (the smaller rotation angle); sweeps
// until every off-diagonal entry is below eps * the Frobenius norm.
bool jacobi(const MpModel& mp, std::vector<std::vector<cl_F>> A, std::vector<cl_F>& d,
            std::vector<std::vector<cl_F>>& V) {
    const std::size_t n = A.size();
    V.assign(n, std::vector<cl_F>(n, mp.zero));
    for (std::size_t i = 0; i < n; ++i) V[i][i] = mp.one;
    cl_F norm = mp.zero;
    for (std::size_t i = 0; i < n; ++i)
        for (std::size_t j = 0; j < n; ++j) norm = norm + sq(A[i][j]);
    const cl_F tol = sq(mp.eps) * norm;  // off-diagonal squared
    bool converged = n <= 1;
    for (int sweep = 0; sweep < 100 && !converged; ++sweep) {
        cl_F off = mp.zero;
        for (std::size_t p = 0; p < n; ++p)
            for (std::size_t q = p + 1; q < n; ++q) off = off + sq(A[p][q]);
        if (off <= tol) {
            converged = true;
            break;
        }
        for (std::size_t p = 0; p < n; ++p)
            for (std::size_t q = p + 1; q < n; ++q) {
                if (is_zero(A[p][q])) continue;
                // theta = (a_qq - a_pp)/(2 a_pq), t = sgn(theta)/(|theta| + sqrt(theta^2 + 1)).
                const cl_F theta = (A[q][q] - A[p][p]) / (mp.two * A[p][q]);
                cl_F t = mp.one / (cln::abs(theta) + cln::sqrt(sq(theta) + mp.one));
                if (cln::minusp(theta)) t = -t;
                const cl_F c = mp.one / cln::sqrt(sq(t) + mp.one), s = t * c;
                for (std::size_t k = 0; k < n; ++k) {  // A <- A J (columns p, q)
                    const cl_F akp = A[k][p], akq = A[k][q];
                    A[k][p] = c * akp - s * akq;
                    A[k][q] = s * akp + c * akq;
                }
                for (std::size_t k = 0; k < n; ++k) {  // A <- J^T A (rows p, q)
                    const cl_F apk = A[p][k], aqk = A[q][k];
                    A[p][k] = c * apk - s * aqk;
                    A[q][k] = s * apk + c * aqk;
                }
                A[p][q] = A[q][p] = mp.zero;
                for (std::size_t k = 0; k < n; ++k) {  // V <- V J
                    const cl_F vkp = V[k][p], vkq = V[k][q];
                    V[k][p] = c * vkp - s * vkq;
                    V[k][q] = s * vkp + c * vkq;
                }
            }
    }
    d.resize(n, mp.zero);
    for (std::size_t i = 0; i < n; ++i) d[i] = A[i][i];
    return converged;
}

// Solves M x = b in place (b becomes x) by Gaussian elimination with partial
// pivoting, in the arithmetic of T (cl_F or cl_N); false on an exactly zero pivot.
template <class T>
bool solve_in_place(std::vector<std::vector<T>> M, std::vector<T>& b) {
    const std::size_t n = M.size();
    for (std::size_t c = 0; c < n; ++c) {
        std::size_t p = c;
        for (std::size_t r = c + 1; r < n; ++r)
            if (cln::abs(M[r][c]) > cln::abs(M[p][c])) p = r;
        if (cln::zerop(M[p][c])) return false;
        std::swap(M[c], M[p]);
        std::swap(b[c], b[p]);
        for (std::size_t r = c + 1; r < n; ++r) {
            const T f = M[r][c] / M[c][c];
            for (std::size_t k = c; k < n; ++k) M[r][k] = M[r][k] - f * M[c][k];
            b[r] = b[r] - f * b[c];
        }
    }
    for (std::size_t c = n; c-- > 0;) {
        T x = b[c];
        for (std::size_t k = c + 1; k < n; ++k) x = x - M[c][k] * b[k];
        b[c] = x / M[c][c];
    }
    return true;
}

using Matrix = std::vector<std::vector<cl_F>>;

Matrix product(const MpModel& mp, const Matrix& A, const Matrix& B) {
    const std::size_t n = A.size();
    Matrix C(n, std::vector<cl_F>(n, mp.zero));
    for (std::size_t i = 0; i < n; ++i)
        for (std::size_t k = 0; k < n; ++k) {
            if (is_zero(A[i][k])) continue;
            for (std::size_t j = 0; j < n; ++j) C[i][j] = C[i][j] + A[i][k] * B[k][j];
        }
    return C;
}

cl_F norm_inf(const MpModel& mp, const Matrix& A) {
    cl_F m = mp.zero;
    for (const auto& row : A) {
        cl_F s = mp.zero;
        for (const cl_F& a : row) s = s + cln::abs(a);
        m = cln::max(m, s);
    }
    return m;
}

// exp(A) by scaling and squaring: A / 2^s with norm at most 1/2, its Taylor
// series summed until a term drops below the roundoff of the sum, squared s times.
Matrix expm(const MpModel& mp, Matrix A) {
    const std::size_t n = A.size();
    int s = 0;
    for (cl_F nrm = norm_inf(mp, A); nrm > mp.half; nrm = nrm * mp.half) ++s;
    const cl_F scale = cln::scale_float(mp.one, -s);
    for (auto& row : A)
        for (cl_F& a : row) a = a * scale;
    Matrix E(n, std::vector<cl_F>(n, mp.zero)), term = E;
    for (std::size_t i = 0; i < n; ++i) E[i][i] = term[i][i] = mp.one;
    for (long k = 1; k < 1000; ++k) {
        term = product(mp, term, A);
        for (auto& row : term)
            for (cl_F& a : row) a = a / cl_I(k);
        for (std::size_t i = 0; i < n; ++i)
            for (std::size_t j = 0; j < n; ++j) E[i][j] = E[i][j] + term[i][j];
        if (norm_inf(mp, term) <= mp.eps * norm_inf(mp, E)) break;
    }
    for (int k = 0; k < s; ++k) E = product(mp, E, E);
    return E;
}

// L of A = L L^T (A symmetric positive definite), at the format's precision.
Matrix cholesky(const MpModel& mp, const Matrix& A) {
    const std::size_t n = A.size();
    Matrix L(n, std::vector<cl_F>(n, mp.zero));
    for (std::size_t j = 0; j < n; ++j) {
        cl_F d = A[j][j];
        for (std::size_t k = 0; k < j; ++k) d = d - L[j][k] * L[j][k];
        if (!cln::plusp(d)) throw RunError("reference: the mass matrix of the free dofs is not positive definite");
        L[j][j] = cln::sqrt(d);
        for (std::size_t i = j + 1; i < n; ++i) {
            cl_F v = A[i][j];
            for (std::size_t k = 0; k < j; ++k) v = v - L[i][k] * L[j][k];
            L[i][j] = v / L[j][j];
        }
    }
    return L;
}

// L^-1 of a lower triangular L (itself lower triangular).
Matrix lower_inverse(const MpModel& mp, const Matrix& L) {
    const std::size_t n = L.size();
    Matrix W(n, std::vector<cl_F>(n, mp.zero));
    for (std::size_t j = 0; j < n; ++j) {
        W[j][j] = mp.one / L[j][j];
        for (std::size_t i = j + 1; i < n; ++i) {
            cl_F v = mp.zero;
            for (std::size_t k = j; k < i; ++k) v = v - L[i][k] * W[k][j];
            W[i][j] = v / L[i][i];
        }
    }
    return W;
}

}  // namespace

// ---------------------------------------------------------------- MpModel

MpModel::MpModel(const Model& model, int digits)
    : format(cln::float_format(static_cast<unsigned long>(digits))),
      zero(cln::cl_float(0, format)),
      one(cln::cl_float(1, format)),
      two(cln::cl_float(2, format)),
      half(cln::cl_float(cl_RA(1) / 2, format)),
      eps(cln::cl_float(cln::expt(cl_RA(2), 1 - static_cast<long>(cln::float_digits(one))), format)),
      pi(cln::pi(format)) {
    if (model.coupled_mass() && !model.proportional_damping())  // init_damped divides by the masses
        throw InputError("the reference (--precision mp:N): model '" + model.name +
                         "' has a coupled (non-diagonal) mass matrix with non-proportional damping, which it does "
                         "not take yet");
    n = static_cast<int>(model.dof());
    g = F(model.g);
    alpha = F(model.alpha);
    beta = F(model.beta);
    for (std::size_t i = 0; i < model.dof(); ++i) {
        const Mass& ms = model.masses[i];
        const FrictionSlot& fs = model.friction_slot(i);
        m.push_back(F(ms.m));
        normal.push_back(fs.normal > 0.0 ? F(fs.normal) : F(ms.m) * g);  // an element's N as given, else m_i g here
        mu_k.push_back(F(fs.mu_k));
        mu_s.push_back(F(fs.mu_s));
        partner.push_back(fs.partner);
    }
    shared = model.shared_partner();
    if (model.coupled_mass()) {
        M.assign(static_cast<std::size_t>(n), std::vector<cl_F>(static_cast<std::size_t>(n), zero));
        for (std::size_t i = 0; i < model.dof(); ++i)
            for (std::size_t j = 0; j < model.dof(); ++j) M[i][j] = F(model.mass_entry(i, j));
    }
    for (const Spring& s : model.springs) springs.push_back({s.a, s.b, F(s.k), zero, zero, {}});
    for (const Contact& c : model.contacts) contacts.push_back({c.a, c.b, F(c.k), F(c.gap), F(c.c), c.weights});
    for (const Jenkins& e : model.jenkins) jenkins.push_back({e.a, e.b, F(e.k), F(e.slip_force), zero, e.weights});
    for (const Damper& d : model.dampers) dampers.push_back({d.a, d.b, F(d.c), zero, zero, {}});
    f_const.assign(static_cast<std::size_t>(n), zero);
    for (int i = 0; i < n; ++i)
        if (static_cast<std::size_t>(i) < model.load.size()) f_const[i] = F(model.load[i]);
    for (const Harmonic& h : model.forcing) {
        if (h.omega == 0.0) {  // a constant force amplitude*sin(phase)
            const cl_F s = cln::sin(F(h.phase));
            for (int i = 0; i < n; ++i) f_const[i] = f_const[i] + F(h.amplitude[i]) * s;
            continue;
        }
        // sin(-|W| t + ph) = sin(|W| t + pi - ph)
        h_omega.push_back(F(std::fabs(h.omega)));
        h_phase.push_back(h.omega > 0 ? F(h.phase) : pi - F(h.phase));
        std::vector<cl_F> amp;
        for (int i = 0; i < n; ++i) amp.push_back(F(h.amplitude[i]));
        h_amp.push_back(amp);
    }
    t0 = F(model.t0);
    for (int i = 0; i < n; ++i) {
        x0.push_back(F(model.x0[i]));
        v0.push_back(F(model.v0[i]));
    }
    auto along_x0 = [&](const Link& e) {  // u = w^T x0
        const cl_F* rows[] = {x0.data()};
        return along(e.direction(), RowsMotion<cl_F, decltype(rows)>(rows, nullptr, zero), 0);
    };
    for (std::size_t j = 0; j < model.jenkins.size(); ++j)  // the sliders after the masses: unstretched, or slider0
        x0.push_back(model.slider0.empty() ? along_x0(jenkins[j]) : F(model.slider0[j]));
}

cl_F MpModel::against_partner(int i, const cl_F& ai, const cl_F& ap) const {
    const cl_F &mi = m[i], &mp = m[partner[i]];
    return (mp * ai - mi * ap) / (mi + mp);
}
cl_F MpModel::against_partner_magnitude(int i, const cl_F& mag_i, const cl_F& mag_p) const {
    const cl_F &mi = m[i], &mp = m[partner[i]];
    return (mp * mag_i + mi * mag_p) / (mi + mp);
}

cl_F MpModel::mass(int i, int j) const {
    if (coupled()) return M[static_cast<std::size_t>(i)][static_cast<std::size_t>(j)];
    return i == j ? m[static_cast<std::size_t>(i)] : zero;
}
cl_F MpModel::mass_times(int i, const std::vector<cl_F>& y) const {
    if (!coupled()) return m[static_cast<std::size_t>(i)] * y[static_cast<std::size_t>(i)];
    cl_F s = zero;
    for (int j = 0; j < n; ++j) s = s + M[static_cast<std::size_t>(i)][static_cast<std::size_t>(j)] * y[static_cast<std::size_t>(j)];
    return s;
}

namespace {

// Per dof: its free coordinate (a rider its partner's, held_mass.h), -1 when held.
std::vector<int> held_columns(const MpModel& mp, const std::vector<char>& held, std::vector<int>& free) {
    std::vector<int> column(static_cast<std::size_t>(mp.n), -1);
    for (int i = 0; i < mp.n; ++i)
        if (!held[static_cast<std::size_t>(i)])
            column[static_cast<std::size_t>(i)] = static_cast<int>(free.size()), free.push_back(i);
    for (int i = 0; i < mp.n; ++i) {
        if (!held[static_cast<std::size_t>(i)]) continue;
        int p = mp.partner[static_cast<std::size_t>(i)];
        while (p != kGround && held[static_cast<std::size_t>(p)]) p = mp.partner[static_cast<std::size_t>(p)];
        if (p != kGround) column[static_cast<std::size_t>(i)] = column[static_cast<std::size_t>(p)];
    }
    return column;
}

}  // namespace

std::vector<std::vector<cl_F>> MpModel::held_inverse(const std::vector<char>& held) const {
    std::vector<int> free;
    const std::vector<int> column = held_columns(*this, held, free);
    const std::size_t nf = free.size();
    Matrix MF(nf, std::vector<cl_F>(nf, zero));
    for (int i = 0; i < n; ++i)
        for (int j = 0; j < n; ++j)
            if (column[static_cast<std::size_t>(i)] >= 0 && column[static_cast<std::size_t>(j)] >= 0) {
                cl_F& e = MF[static_cast<std::size_t>(column[static_cast<std::size_t>(i)])]
                            [static_cast<std::size_t>(column[static_cast<std::size_t>(j)])];
                e = e + mass(i, j);
            }
    const Matrix W = lower_inverse(*this, cholesky(*this, MF));  // (T^T M T)^-1 = W^T W
    std::vector<std::vector<cl_F>> inv(static_cast<std::size_t>(n), std::vector<cl_F>(static_cast<std::size_t>(n), zero));
    for (int i = 0; i < n; ++i)
        for (int j = 0; j < n; ++j) {
            const int r = column[static_cast<std::size_t>(i)], c = column[static_cast<std::size_t>(j)];
            if (r < 0 || c < 0) continue;
            cl_F sum = zero;
            for (std::size_t k = static_cast<std::size_t>(std::max(r, c)); k < nf; ++k)
                sum = sum + W[k][static_cast<std::size_t>(r)] * W[k][static_cast<std::size_t>(c)];
            inv[static_cast<std::size_t>(i)][static_cast<std::size_t>(j)] = sum;
        }
    return inv;
}

std::vector<cl_F> MpModel::held_row(const std::vector<std::vector<cl_F>>& inverse, const std::vector<char>& held,
                                    int i) const {
    // P = s - T (T^T M T)^-1 T^T M s, s the indicator of the dofs stuck friction i carries (held_mass.h).
    std::vector<char> carried(static_cast<std::size_t>(n), 0);
    carried[static_cast<std::size_t>(i)] = 1;
    for (int k = 0; k < n; ++k) {
        if (!held[static_cast<std::size_t>(k)] || k == i) continue;
        for (int p = partner[static_cast<std::size_t>(k)]; p != kGround; p = partner[static_cast<std::size_t>(p)]) {
            if (p == i) carried[static_cast<std::size_t>(k)] = 1;
            if (p == i || !held[static_cast<std::size_t>(p)]) break;
        }
    }
    std::vector<cl_F> Ms(static_cast<std::size_t>(n), zero);  // M s
    for (int r = 0; r < n; ++r)
        for (int k = 0; k < n; ++k)
            if (carried[static_cast<std::size_t>(k)])
                Ms[static_cast<std::size_t>(r)] = Ms[static_cast<std::size_t>(r)] + mass(r, k);
    std::vector<cl_F> P(static_cast<std::size_t>(n), zero);
    for (int q = 0; q < n; ++q) {
        cl_F s = carried[static_cast<std::size_t>(q)] ? one : zero;
        for (int r = 0; r < n; ++r)
            s = s - Ms[static_cast<std::size_t>(r)] * inverse[static_cast<std::size_t>(r)][static_cast<std::size_t>(q)];
        P[static_cast<std::size_t>(q)] = s;
    }
    return P;
}

std::vector<cl_F> MpModel::kinetic(const std::vector<char>& held, const std::vector<signed char>& sgn) const {
    std::vector<cl_F> fr(static_cast<std::size_t>(n), zero);
    for (std::size_t i = 0; i < fr.size(); ++i)
        if (!held[i] && sgn[i] != 0) fr[i] = sgn[i] > 0 ? -(mu_k[i] * normal[i]) : mu_k[i] * normal[i];
    for (std::size_t i = 0; i < fr.size(); ++i)  // the reaction on the partner of a friction between two bodies
        if (!held[i] && sgn[i] != 0 && partner[i] != kGround)
            fr[static_cast<std::size_t>(partner[i])] = fr[static_cast<std::size_t>(partner[i])] - fr[i];
    return fr;
}

cl_F MpModel::F(double d) const { return cln::cl_float(d, format); }
cl_F MpModel::I(long i) const { return cln::cl_float(cl_I(i), format); }

cl_F MpModel::gap(int c, const std::vector<cl_F>& x) const {
    const Link& k = contacts[static_cast<std::size_t>(c)];
    const cl_F* rows[] = {x.data()};
    return contact::gap_value(k.direction(), k.gap, RowsMotion<cl_F, decltype(rows)>(rows, nullptr, zero), 0);
}
cl_F MpModel::gap_rate(int c, const std::vector<cl_F>& v) const {
    const Link& k = contacts[static_cast<std::size_t>(c)];
    const cl_F* rows[] = {nullptr, v.data()};
    return contact::gap_value(k.direction(), k.gap, RowsMotion<cl_F, decltype(rows)>(rows, nullptr, zero), 1);
}

namespace {

// The force on body i of the elements' links and constant forces, and of
// their time derivative (order 1: the constant forces drop out), from the
// motion's rows 0 (x) and 1 (v), or 1 and 2 (v, a).
struct ForceOnBody {
    const MpModel& mp;
    int i;
    const std::vector<cl_F>& y0;
    const std::vector<cl_F>& y1;
    bool rate;
    cl_F sum;
    void link(const Direction& d, const cl_F& k, const cl_F& c, const cl_F& length) {
        if (!acts_on(d, i)) return;
        const cl_F dx = rate ? mp.body(y0, d.a) - mp.body(y0, d.b) : mp.body(y0, d.a) - mp.body(y0, d.b) - length;
        const cl_F f = -(k * dx) - c * (mp.body(y1, d.a) - mp.body(y1, d.b));  // on a
        add(d, f);
    }
    void force(const Direction& d, const cl_F& f) {
        if (!rate && acts_on(d, i)) add(d, f);
    }
    const cl_F& zero() const { return mp.zero; }
    void add(const Direction& d, const cl_F& f) {
        if (d.a == d.b) return;  // a link from a body to itself does nothing
        sum = d.a == i ? sum + f : sum - f;
    }
};

}  // namespace

cl_F MpModel::force_on_mass(const Configuration& cfg, int i, const cl_F& t, const std::vector<cl_F>& x,
                            const std::vector<cl_F>& v) const {
    // A_i = sum over the elements' links touching i of -k (u - length) - c u' and their constant
    // forces, - alpha m_i v_i + f_i + sum_h F_hi sin(Omega_h t + phase_h).
    ForceOnBody on{*this, i, x, v, false, f_const[i] - (coupled() ? alpha * mass_times(i, v) : alpha * m[i] * v[i])};
    each_force(cfg, [&](std::size_t j) { return x[static_cast<std::size_t>(n) + j]; }, on);
    cl_F A = on.sum;
    for (std::size_t h = 0; h < h_omega.size(); ++h) A = A + h_amp[h][i] * cln::sin(h_omega[h] * t + h_phase[h]);
    return A;
}

cl_F MpModel::force_rate_on_mass(const Configuration& cfg, int i, const cl_F& t, const std::vector<cl_F>& v,
                                 const std::vector<cl_F>& a) const {
    ForceOnBody on{*this, i, v, a, true, -(coupled() ? alpha * mass_times(i, a) : alpha * m[i] * a[i])};
    each_force(cfg, [&](std::size_t) { return zero; }, on);  // a stuck slider's length drops out
    cl_F dA = on.sum;
    for (std::size_t h = 0; h < h_omega.size(); ++h)
        dA = dA + h_amp[h][i] * h_omega[h] * cln::cos(h_omega[h] * t + h_phase[h]);
    return dA;
}

// ---------------------------------------------------------------- MpSegment

namespace {

// Stamps an element's links into K (with their lengths' preload into f) and its
// constant forces into f (model/elements/direction.h).
struct Stamp {
    std::vector<std::vector<cl_F>>& K;
    std::vector<cl_F>& f;
    const cl_F& z;
    void link(const Direction& d, const cl_F& k, const cl_F&, const cl_F& length) {
        if (cln::zerop(k)) return;  // a dashpot (C is built apart)
        if (d.a != kGround) K[d.a][d.a] = K[d.a][d.a] + k;
        if (d.b != kGround) K[d.b][d.b] = K[d.b][d.b] + k;
        if (d.a != kGround && d.b != kGround) {
            K[d.a][d.b] = K[d.a][d.b] - k;
            K[d.b][d.a] = K[d.b][d.a] - k;
        }
        if (cln::zerop(length)) return;  // -k (u - length): +k length on a, -k length on b
        if (d.a != kGround) f[d.a] = f[d.a] + k * length;
        if (d.b != kGround) f[d.b] = f[d.b] - k * length;
    }
    void force(const Direction& d, const cl_F& fa) {
        if (d.a != kGround) f[d.a] = f[d.a] + fa;
        if (d.b != kGround) f[d.b] = f[d.b] - fa;
    }
    const cl_F& zero() const { return z; }
};

}  // namespace

void MpSegment::undamped_modes(const Model& model, const std::vector<std::vector<cl_F>>& Kf, int n_rigid) {
    const MpModel& mp = mp_;
    const cl_F& Z0 = mp.zero;
    // A = W K_F W^T = V diag(lambda) V^T, Phi = W^T V (M-orthonormal): W = M^-1/2 for a
    // lumped M, L^-1 of M_F = L L^T (Cholesky at N digits) for a coupled one.
    std::vector<std::vector<cl_F>> Wm(nf_, std::vector<cl_F>(nf_, Z0));
    if (mp.coupled()) {
        mass_matrix_.assign(nf_, std::vector<cl_F>(nf_, Z0));
        for (int r = 0; r < nf_; ++r)
            for (int s = 0; s < nf_; ++s) mass_matrix_[r][s] = mp.M[free_[r]][free_[s]];
        Wm = lower_inverse(mp, cholesky(mp, mass_matrix_));
    } else {
        for (int r = 0; r < nf_; ++r) Wm[r][r] = mp.one / cln::sqrt(mass_[r]);
    }
    std::vector<std::vector<cl_F>> A(nf_, std::vector<cl_F>(nf_, Z0)), V;
    for (int r = 0; r < nf_; ++r)
        for (int s = 0; s < nf_; ++s) {
            if (!mp.coupled()) {
                A[r][s] = Wm[r][r] * Kf[r][s] * Wm[s][s];
                continue;
            }
            for (int p = 0; p <= r; ++p)
                for (int q = 0; q <= s; ++q) A[r][s] = A[r][s] + Wm[r][p] * Kf[p][q] * Wm[s][q];
        }
    std::vector<cl_F> d;
    if (!jacobi(mp, A, d, V))
        throw RunError("reference::MpSegment(): Jacobi eigen-solver did not converge in configuration '" +
                       cfg_.spec(model) + "'");
    std::vector<int> order(nf_);
    for (int j = 0; j < nf_; ++j) order[j] = j;
    std::sort(order.begin(), order.end(), [&](int a, int b) { return d[a] < d[b]; });
    phi_.assign(nf_, std::vector<cl_F>(nf_, Z0));
    lambda_.assign(nf_, Z0);
    for (int j = 0; j < nf_; ++j) {
        lambda_[j] = j < n_rigid ? Z0 : d[order[j]];  // structural zeros, exactly
        if (cln::minusp(lambda_[j])) lambda_[j] = Z0;
        for (int r = 0; r < nf_; ++r)
            for (int p = r; p < nf_; ++p) {  // (W^T V)_rj: W lower triangular (diagonal when lumped)
                if (!mp.coupled() && p != r) break;
                phi_[r][j] = phi_[r][j] + Wm[p][r] * V[p][order[j]];
            }
    }
}

// The switch functions as modal combinations g = W q + Z q' + D sin + const
// (for the bounds; a release function's from D_i, MpModel::held_row when M is coupled).
void MpSegment::switch_rows() {
    const MpModel& mp = mp_;
    const cl_F& Z0 = mp.zero;
    const int ns = static_cast<int>(switches_.size());
    W_.assign(ns, std::vector<cl_F>(nf_, Z0));
    Z_ = W_;
    D_.assign(ns, std::vector<cl_F>(nh_, Z0));
    for (int f = 0; f < ns; ++f) {
        const SwitchFunction& sf = switches_[f];
        if (sf.kind == SwitchKind::gap) {
            const auto& ct = mp.contacts[sf.element];
            for (int j = 0; j < nf_; ++j) {
                cl_F w = Z0;
                for_each_term(ct.direction(), [&](int body, double wi) {
                    if (slot_[body] >= 0) w = w + mp.F(wi) * phi_[slot_[body]][j];
                });
                W_[f][j] = w;
            }
        } else if (sf.kind == SwitchKind::velocity) {
            const int p = mp.partner[sf.element];  // w = v_e - v_partner (a partner held still: v_partner = 0)
            for (int j = 0; j < nf_; ++j)
                Z_[f][j] = p == kGround || slot_[p] < 0 ? phi_[slot_[sf.element]][j]
                                                        : phi_[slot_[sf.element]][j] - phi_[slot_[p]][j];
        } else if (sf.kind == SwitchKind::slip_pos || sf.kind == SwitchKind::slip_neg ||
                   sf.kind == SwitchKind::slip_velocity) {
            // +-k (u - s) - F_s (the slider fixed) on q; u' on q' (u = x_a - x_b, or w^T x).
            const auto& e = mp.jenkins[static_cast<std::size_t>(sf.element)];
            const cl_F c = sf.kind == SwitchKind::slip_neg ? -e.k : sf.kind == SwitchKind::slip_pos ? e.k : mp.one;
            for (int j = 0; j < nf_; ++j) {
                cl_F w = Z0;
                for_each_term(e.direction(), [&](int body, double wi) {
                    if (slot_[body] >= 0) w = w + mp.F(wi) * phi_[slot_[body]][j];
                });
                (sf.kind == SwitchKind::slip_velocity ? Z_ : W_)[f][j] = c * w;
            }
        } else {
            // +-A_i on the modes, A_i = -(K x)_i - (C v)_i + ... over every moving mass;
            // against a partner p, D_i = (m_p A_i - m_i A_p)/(m_i + m_p).
            const bool pos = sf.kind == SwitchKind::release_pos;
            const int i = sf.element, p = mp.partner[i];
            auto rows = [&](int b, int j, cl_F& kw, cl_F& cz) {
                kw = cz = Z0;
                for (int k = 0; k < n_; ++k) {
                    if (slot_[k] < 0) continue;
                    kw = kw + K_[b][k] * phi_[slot_[k]][j];
                    cz = cz + C_[b][k] * phi_[slot_[k]][j];
                }
            };
            if (mp.coupled_friction()) {  // D_i = P_i . A (MpModel::held_row)
                if (release_rows_.empty()) {
                    const auto inverse = mp.held_inverse(cfg_.stuck);
                    release_rows_.assign(static_cast<std::size_t>(n_), {});
                    for (int s = 0; s < n_; ++s)
                        if (cfg_.stuck[static_cast<std::size_t>(s)])
                            release_rows_[static_cast<std::size_t>(s)] = mp.held_row(inverse, cfg_.stuck, s);
                }
                const std::vector<cl_F>& P = release_rows_[static_cast<std::size_t>(i)];
                for (int j = 0; j < nf_; ++j) {
                    cl_F kw = Z0, cz = Z0;
                    for (int q = 0; q < n_; ++q) {
                        cl_F kq, cq;
                        rows(q, j, kq, cq);
                        kw = kw + P[static_cast<std::size_t>(q)] * kq;
                        cz = cz + P[static_cast<std::size_t>(q)] * cq;
                    }
                    W_[f][j] = pos ? -kw : kw;
                    Z_[f][j] = pos ? -cz : cz;
                }
                for (int h = 0; h < nh_; ++h) {
                    cl_F F = Z0;
                    for (int q = 0; q < n_; ++q) F = F + P[static_cast<std::size_t>(q)] * mp.h_amp[h][q];
                    D_[f][h] = pos ? F : -F;
                }
                continue;
            }
            for (int j = 0; j < nf_; ++j) {
                cl_F kw, cz;
                rows(i, j, kw, cz);
                if (p != kGround) {
                    cl_F kp, cp;
                    rows(p, j, kp, cp);
                    kw = mp.against_partner(i, kw, kp);
                    cz = mp.against_partner(i, cz, cp);
                }
                W_[f][j] = pos ? -kw : kw;
                Z_[f][j] = pos ? -cz : cz;
            }
            for (int h = 0; h < nh_; ++h) {
                const cl_F F = p == kGround ? mp.h_amp[h][i] : mp.against_partner(i, mp.h_amp[h][i], mp.h_amp[h][p]);
                D_[f][h] = pos ? F : -F;
            }
        }
    }
}

MpSegment::MpSegment(const Model& model, const MpModel& mp, const Configuration& cfg)
    : mp_(mp), cfg_(cfg), switches_(switch_functions(model, cfg)), max_step_(mp.zero) {
    n_ = mp.n;
    nh_ = static_cast<int>(mp.h_omega.size());
    const cl_F& Z0 = mp.zero;
    // K(cfg), C = alpha M + beta K, constant force with contact preloads (assembly.h).
    K_.assign(n_, std::vector<cl_F>(n_, Z0));
    f_const_ = mp.f_const;
    // Every element's links (K, with their lengths' preload; a stuck slider's is per
    // segment, setup) and constant forces (f_const).
    mp.each_force(cfg, [&](std::size_t) { return Z0; }, Stamp{K_, f_const_, Z0});  // sliders: per segment
    C_ = K_;
    for (int i = 0; i < n_; ++i)
        for (int k = 0; k < n_; ++k) C_[i][k] = mp.beta * K_[i][k] + mp.alpha * mp.mass(i, k);

    // Free masses, and the structural count of rigid-body modes (free_components.h: the
    // rule the double code uses; a structure, so nothing to compute at N digits).
    const FreeComponents fc = free_components(model, cfg);
    free_ = fc.free;
    slot_.assign(n_, -1);
    for (std::size_t r = 0; r < free_.size(); ++r) slot_[free_[r]] = static_cast<int>(r);
    nf_ = static_cast<int>(free_.size());
    // Masses stuck to their friction partner ride its coordinate: the coordinate's
    // mass and stiffness gather theirs (T^T M T, T^T K T of x = T q + e).
    mass_.assign(nf_, Z0);
    for (int r = 0; r < nf_; ++r) mass_[r] = mp.m[free_[r]];
    for (int i = 0; i < n_; ++i)
        if (mp.rides(cfg, i)) {
            riders_.push_back(i);
            slot_[i] = slot_[mp.carrier(cfg, i)];
            mass_[slot_[i]] = mass_[slot_[i]] + mp.m[i];
        }
    std::vector<std::vector<cl_F>> Kf(nf_, std::vector<cl_F>(nf_, Z0));
    for (int i = 0; i < n_; ++i)
        for (int k = 0; k < n_; ++k)
            if (slot_[i] >= 0 && slot_[k] >= 0) Kf[slot_[i]][slot_[k]] = Kf[slot_[i]][slot_[k]] + K_[i][k];
    const int n_rigid = fc.n_floating();
    bool contact_damped = false;  // a closed contact's own c w w^T (contact.h)
    for (std::size_t c = 0; c < mp.contacts.size(); ++c) {
        const MpModel::Link& l = mp.contacts[c];
        if (!cfg.closed[c] || cln::zerop(l.c)) continue;
        contact_damped = true;
        for_each_term(l.direction(), [&](int i, double wi) {
            for_each_term(l.direction(), [&](int j, double wj) { C_[i][j] = C_[i][j] + l.c * mp.F(wi) * mp.F(wj); });
        });
    }
    if (!mp.dampers.empty() || contact_damped) {
        for (const MpModel::Link& d : mp.dampers) {  // C as K takes a spring
            if (d.a != kGround) C_[d.a][d.a] = C_[d.a][d.a] + d.k;
            if (d.b != kGround) C_[d.b][d.b] = C_[d.b][d.b] + d.k;
            if (d.a != kGround && d.b != kGround) {
                C_[d.a][d.b] = C_[d.a][d.b] - d.k;
                C_[d.b][d.a] = C_[d.b][d.a] - d.k;
            }
        }
        if (n_rigid > 0)
            throw RunError("reference::MpSegment(): configuration '" + cfg.spec(model) +
                           "': rigid-body modes under dampers are not taken by the reference yet");
        if (!riders_.empty())  // the model reader refuses friction between two bodies with dampers
            throw RunError("reference::MpSegment(): a stuck friction pair under dampers");
        init_damped(model);
        return;
    }

    undamped_modes(model, Kf, n_rigid);

    // Regimes.
    regime_.assign(nf_, Regime::rigid);
    omega_.assign(nf_, Z0);
    c_.assign(nf_, Z0);
    sigma_.assign(nf_, Z0);
    omega_d_.assign(nf_, Z0);
    gamma_.assign(nf_, Z0);
    r1_.assign(nf_, Z0);
    for (int j = 0; j < nf_; ++j) {
        const cl_F& lam = lambda_[j];
        omega_[j] = cln::sqrt(lam);
        c_[j] = mp.alpha + mp.beta * lam;
        sigma_[j] = c_[j] * mp.half;
        const cl_F &w = omega_[j], &s = sigma_[j];
        if (is_zero(lam)) {
            regime_[j] = Regime::rigid;
        } else if (s < w) {
            regime_[j] = Regime::underdamped;
            omega_d_[j] = cln::sqrt((w - s) * (w + s));
        } else if (s > w) {
            regime_[j] = Regime::overdamped;
            gamma_[j] = cln::sqrt((s - w) * (s + w));
            r1_[j] = -(lam / (s + gamma_[j]));  // -sigma + gamma without cancellation
        } else {
            regime_[j] = Regime::critical;
        }
    }

    // Modal forcing and particular solutions.
    P_.assign(nf_, std::vector<cl_F>(nh_, Z0));
    pa_ = pb_ = P_;
    secular_.assign(nf_, std::vector<char>(nh_, 0));
    for (int j = 0; j < nf_; ++j)
        for (int h = 0; h < nh_; ++h) {
            cl_F P = Z0;
            for (int i = 0; i < n_; ++i)
                if (slot_[i] >= 0) P = P + phi_[slot_[i]][j] * mp.h_amp[h][i];
            P_[j][h] = P;
            const cl_F& W = mp.h_omega[h];
            const cl_F det = lambda_[j] - W * W, cw = c_[j] * W;
            const cl_F D = det * det + cw * cw;
            if (is_zero(D)) {
                secular_[j][h] = 1;  // exact undamped resonance
                const cl_F period = mp.two * mp.pi / W;
                max_step_ = has_max_step_ ? cln::min(max_step_, period) : period;
                has_max_step_ = true;
            } else {
                pa_[j][h] = -(P * cw) / D;
                pb_[j][h] = P * det / D;
            }
        }

    switch_rows();
    const int ns = static_cast<int>(switches_.size());
    // The standard particular parts of harmonic h add up in g_f to one sinusoid
    // A cos + B sin; its second derivative has amplitude Omega^2 sqrt(A^2 + B^2).
    bound_sin_.assign(ns, Z0);
    for (int f = 0; f < ns; ++f)
        for (int h = 0; h < nh_; ++h) {
            const cl_F& W = mp.h_omega[h];
            cl_F A = Z0, B = D_[f][h];
            for (int j = 0; j < nf_; ++j) {
                if (secular_[j][h]) continue;
                A = A + W_[f][j] * pa_[j][h] + Z_[f][j] * W * pb_[j][h];
                B = B + W_[f][j] * pb_[j][h] - Z_[f][j] * W * pa_[j][h];
            }
            bound_sin_[f] = bound_sin_[f] + W * W * cln::sqrt(A * A + B * B);
        }
    x_fix_.assign(n_, Z0);
    theta_.assign(nh_, Z0);
    p_.assign(nf_, Z0);
    u0_.assign(nf_, Z0);
    ud0_.assign(nf_, Z0);
}

// ---------------------------------------------------------------- dampers

void MpSegment::init_damped(const Model& model) {
    const MpModel& mp = mp_;
    const cl_F& Z0 = mp.zero;
    damped_ = true;
    const std::size_t nf = static_cast<std::size_t>(nf_);
    S_.assign(2 * nf, std::vector<cl_F>(2 * nf, Z0));
    for (std::size_t r = 0; r < nf; ++r) {
        const int i = free_[r];
        S_[r][nf + r] = mp.one;
        for (std::size_t c = 0; c < nf; ++c) {
            S_[nf + r][c] = -(K_[i][free_[c]] / mp.m[i]);
            S_[nf + r][nf + c] = -(C_[i][free_[c]] / mp.m[i]);
        }
    }
    Matrix KF(nf, std::vector<cl_F>(nf, Z0));
    for (std::size_t r = 0; r < nf; ++r)
        for (std::size_t c = 0; c < nf; ++c) KF[r][c] = K_[free_[r]][free_[c]];
    Kinv_.assign(nf, std::vector<cl_F>(nf, Z0));
    for (std::size_t c = 0; c < nf; ++c) {
        std::vector<cl_F> e(nf, Z0);
        e[c] = mp.one;
        if (!solve_in_place(KF, e))
            throw RunError("reference::MpSegment(): configuration '" + cfg_.spec(model) + "': singular stiffness");
        for (std::size_t r = 0; r < nf; ++r) Kinv_[r][c] = e[r];
    }
    X_.assign(static_cast<std::size_t>(nh_), {});
    for (int h = 0; h < nh_; ++h) {
        const cl_F& W = mp.h_omega[h];
        std::vector<std::vector<cln::cl_N>> Zm(nf, std::vector<cln::cl_N>(nf));
        std::vector<cln::cl_N> X(nf);
        for (std::size_t r = 0; r < nf; ++r) {
            const int i = free_[r];
            X[r] = mp.h_amp[h][i];
            for (std::size_t c = 0; c < nf; ++c)
                Zm[r][c] = cln::complex(K_[i][free_[c]] - (r == c ? W * W * mp.m[i] : Z0), W * C_[i][free_[c]]);
        }
        if (!solve_in_place(Zm, X))
            throw RunError("reference::MpSegment(): configuration '" + cfg_.spec(model) +
                           "': forced at a frequency of an undamped mode");
        X_[h] = X;
    }
    // Each switch function as rows on (x_F, v_F), plus its harmonic amplitudes G_fh:
    // the part of g from harmonic h is Im(G_fh e^{i(W tau + theta_h)}).
    const std::size_t ns = switches_.size();
    Lx_.assign(ns, std::vector<cl_F>(nf, Z0));
    Lv_ = Lx_;
    G_.assign(ns, std::vector<cln::cl_N>(static_cast<std::size_t>(nh_), Z0));
    auto on = [&](std::vector<cl_F>& row, int body, const cl_F& c) {
        if (body != kGround && slot_[body] >= 0) row[slot_[body]] = row[slot_[body]] + c;
    };
    for (std::size_t f = 0; f < ns; ++f) {
        const SwitchFunction& sf = switches_[f];
        const int e = sf.element;
        if (sf.kind == SwitchKind::gap) {
            for_each_term(mp.contacts[e].direction(), [&](int body, double w) { on(Lx_[f], body, mp.F(w)); });
        } else if (sf.kind == SwitchKind::velocity) {
            on(Lv_[f], e, mp.one);
        } else if (sf.kind == SwitchKind::slip_pos || sf.kind == SwitchKind::slip_neg) {
            const MpModel::Link& el = mp.jenkins[static_cast<std::size_t>(e)];
            const cl_F k = sf.kind == SwitchKind::slip_pos ? el.k : -el.k;
            for_each_term(el.direction(), [&](int body, double w) { on(Lx_[f], body, k * mp.F(w)); });
        } else if (sf.kind == SwitchKind::slip_velocity) {
            const MpModel::Link& el = mp.jenkins[static_cast<std::size_t>(e)];
            for_each_term(el.direction(), [&](int body, double w) { on(Lv_[f], body, mp.F(w)); });
        } else {  // +-A_e, A = -K x - C v + ... + F sin
            const cl_F sg = sf.kind == SwitchKind::release_pos ? mp.one : -mp.one;
            for (std::size_t r = 0; r < nf; ++r) {
                Lx_[f][r] = -(sg * K_[e][free_[r]]);
                Lv_[f][r] = -(sg * C_[e][free_[r]]);
            }
            for (int h = 0; h < nh_; ++h) G_[f][h] = sg * mp.h_amp[h][e];
        }
        for (int h = 0; h < nh_; ++h)
            for (std::size_t r = 0; r < nf; ++r)  // x_p = Im(X e^{i arg}), v_p = Im(i W X e^{i arg})
                G_[f][h] = G_[f][h] + Lx_[f][r] * X_[h][r] + Lv_[f][r] * cln::complex(Z0, mp.h_omega[h]) * X_[h][r];
    }
    weight2_.resize(ns);
    for (std::size_t f = 0; f < ns; ++f) weight2_[f] = damped_weight(f, 2);
    fseg_ = f_const_;
    x_fix_.assign(n_, Z0);
    theta_.assign(nh_, Z0);
}

cl_F MpSegment::damped_weight(std::size_t f, int k) const {
    const MpModel& mp = mp_;
    const std::size_t nf = static_cast<std::size_t>(nf_);
    std::vector<cl_F> p = Lx_[f], q = Lv_[f];
    for (int r = 0; r < k; ++r) {  // (p, q) S = (-(q M^-1) K_F, p - (q M^-1) C_F)
        std::vector<cl_F> np(nf, mp.zero), nq = p;
        for (std::size_t i = 0; i < nf; ++i) {
            if (is_zero(q[i])) continue;
            const cl_F qi = q[i] / mp.m[free_[i]];
            for (std::size_t c = 0; c < nf; ++c) {
                np[c] = np[c] - qi * K_[free_[i]][free_[c]];
                nq[c] = nq[c] - qi * C_[free_[i]][free_[c]];
            }
        }
        p = np;
        q = nq;
    }
    cl_F pk = mp.zero, qm = mp.zero;
    for (std::size_t r = 0; r < nf; ++r) {
        qm = qm + q[r] * q[r] / mp.m[free_[r]];
        for (std::size_t c = 0; c < nf; ++c) pk = pk + p[r] * Kinv_[r][c] * p[c];
    }
    return cln::sqrt(cln::max(pk, mp.zero)) + cln::sqrt(qm);
}

void MpSegment::setup_damped(const std::vector<cl_F>& force, const std::vector<cl_F>& v0) {
    const MpModel& mp = mp_;
    const std::size_t nf = static_cast<std::size_t>(nf_);
    force_ = force;
    x_st_.assign(nf, mp.zero);
    zh0_.assign(2 * nf, mp.zero);
    for (std::size_t r = 0; r < nf; ++r)
        for (std::size_t c = 0; c < nf; ++c) x_st_[r] = x_st_[r] + Kinv_[r][c] * force[c];
    for (std::size_t r = 0; r < nf; ++r) {
        zh0_[r] = x_fix_[free_[r]] - x_st_[r];
        zh0_[nf + r] = v0[free_[r]];
    }
    for (int h = 0; h < nh_; ++h) {
        const CosSin cs = cos_sin_of(theta_[h]);
        const cl_F& W = mp.h_omega[h];
        for (std::size_t r = 0; r < nf; ++r) {
            const cl_F re = re_of(mp, X_[h][r]), im = im_of(mp, X_[h][r]);
            zh0_[r] = zh0_[r] - (re * cs.s + im * cs.c);
            zh0_[nf + r] = zh0_[nf + r] - W * (re * cs.c - im * cs.s);
        }
    }
    energy0_ = mp.zero;
    for (std::size_t r = 0; r < nf; ++r) {
        energy0_ = energy0_ + mp.m[free_[r]] * zh0_[nf + r] * zh0_[nf + r];
        for (std::size_t c = 0; c < nf; ++c) energy0_ = energy0_ + zh0_[r] * K_[free_[r]][free_[c]] * zh0_[c];
    }
    energy0_ = energy0_ * mp.half;
}

void MpSegment::setup(const cl_F& t0, const std::vector<cl_F>& x0, const std::vector<cl_F>& v0,
                      const std::vector<signed char>& sgn) {
    const MpModel& mp = mp_;
    x_fix_ = x0;
    v_start_ = v0;
    for (int h = 0; h < nh_; ++h) theta_[h] = mp.h_omega[h] * t0 + mp.h_phase[h];
    // The stuck sliders' preload k s (+ on a, - on b; k s w_i along a direction), s = x0[n + j].
    fseg_ = f_const_;
    slider_.assign(mp.jenkins.size(), mp.zero);
    for (std::size_t j = 0; j < mp.jenkins.size(); ++j) {
        if (cfg_.slip[j] != 0) continue;
        const MpModel::Link& e = mp.jenkins[j];
        slider_[j] = x0[static_cast<std::size_t>(n_) + j];
        const cl_F p = e.k * slider_[j];
        for_each_term(e.direction(), [&](int body, double w) { fseg_[body] = fseg_[body] + mp.F(w) * p; });
    }
    // Constant force on each coordinate, summed over its masses (T^T (f - K e)):
    // loads, preloads, the masses held still as supports (-K_FS x_S), the riders'
    // offsets (-K e), kinetic friction -mu_k N sgn and its reaction on a partner.
    offset_.clear();
    for (int q : riders_) offset_.push_back(x0[q] - x0[mp.carrier(cfg_, q)]);
    std::vector<cl_F>& fric = fric_;
    fric.assign(static_cast<std::size_t>(n_), mp.zero);
    for (int i = 0; i < n_; ++i) {
        if (sgn[i] == 0) continue;
        const cl_F fr = sgn[i] > 0 ? mp.mu_k[i] * mp.normal[i] : -(mp.mu_k[i] * mp.normal[i]);
        fric[i] = fric[i] - fr;
        if (mp.partner[i] != kGround) fric[mp.partner[i]] = fric[mp.partner[i]] + fr;
    }
    std::vector<cl_F> force(nf_, mp.zero);
    for (int i = 0; i < n_; ++i) {
        if (slot_[i] < 0) continue;
        cl_F f = fseg_[i] + fric[i];
        for (int s = 0; s < n_; ++s)
            if (mp.fixed(cfg_, s)) f = f - K_[i][s] * x0[s];
        for (std::size_t r = 0; r < riders_.size(); ++r) f = f - K_[i][riders_[r]] * offset_[r];
        force[slot_[i]] = force[slot_[i]] + f;
    }
    if (damped_) {
        setup_damped(force, v0);
        return;
    }
    for (int j = 0; j < nf_; ++j) {
        // q0 = Phi^T M_F x0, qd0 = Phi^T M_F v0, p = Phi^T f.
        cl_F q0 = mp.zero, qd0 = mp.zero, p = mp.zero;
        for (int r = 0; r < nf_; ++r) {
            const int i = free_[r];
            if (mp.coupled()) {  // (Phi^T M_F)_jr = sum_c phi_cj M_cr
                cl_F pm = mp.zero;
                for (int c = 0; c < nf_; ++c) pm = pm + phi_[c][j] * mass_matrix_[c][r];
                q0 = q0 + pm * x0[i];
                qd0 = qd0 + pm * v0[i];
            } else {
                q0 = q0 + phi_[r][j] * mass_[r] * x0[i];
                qd0 = qd0 + phi_[r][j] * mass_[r] * v0[i];
            }
            p = p + phi_[r][j] * force[r];
        }
        p_[j] = p;
        cl_F qp0 = mp.zero, qpd0 = mp.zero;  // particular parts at tau = 0
        for (int h = 0; h < nh_; ++h) {
            const CosSin cs = cos_sin_of(theta_[h]);
            const cl_F& W = mp.h_omega[h];
            if (secular_[j][h]) {  // q_p = -P tau cos(W tau + theta)/(2W)
                qpd0 = qpd0 - P_[j][h] * cs.c / (mp.two * W);
                continue;
            }
            qp0 = qp0 + pa_[j][h] * cs.c + pb_[j][h] * cs.s;
            qpd0 = qpd0 + W * (pb_[j][h] * cs.c - pa_[j][h] * cs.s);
        }
        u0_[j] = regime_[j] == Regime::rigid ? q0 - qp0 : q0 - p / lambda_[j] - qp0;
        ud0_[j] = qd0 - qpd0;
    }
}

void MpSegment::eval_damped(const cl_F& tau, MpEval& out, std::vector<cl_F>& xm, std::vector<cl_F>& vm,
                            cl_F& energy) const {
    const MpModel& mp = mp_;
    const std::size_t nf = static_cast<std::size_t>(nf_);
    Matrix St = S_;
    for (auto& row : St)
        for (cl_F& a : row) a = a * tau;
    const Matrix E = expm(mp, St);
    std::vector<cl_F> zh(2 * nf, mp.zero);
    for (std::size_t i = 0; i < 2 * nf; ++i)
        for (std::size_t j = 0; j < 2 * nf; ++j) zh[i] = zh[i] + E[i][j] * zh0_[j];
    std::vector<CosSin> hcs(nh_);
    for (int h = 0; h < nh_; ++h) hcs[h] = cos_sin_of(mp.h_omega[h] * tau + theta_[h]);
    std::vector<cl_F> xf(nf), vf(nf);
    for (std::size_t r = 0; r < nf; ++r) {
        const int i = free_[r];
        cl_F x = x_st_[r] + zh[r], v = zh[nf + r];
        cl_F m = cln::abs(x_st_[r]) + cln::abs(zh[r]), dm = cln::abs(zh[nf + r]);
        for (int h = 0; h < nh_; ++h) {
            const cl_F re = re_of(mp, X_[h][r]), im = im_of(mp, X_[h][r]);
            const cl_F& W = mp.h_omega[h];
            const cl_F xp = re * hcs[h].s + im * hcs[h].c, vp = W * (re * hcs[h].c - im * hcs[h].s);
            x = x + xp;
            v = v + vp;
            m = m + cln::abs(xp);
            dm = dm + cln::abs(vp);
        }
        out.x[i] = xf[r] = x;
        out.v[i] = vf[r] = v;
        xm[i] = m;
        vm[i] = dm;
    }
    // a = M^-1 (f - K x - C v + sum_h F_h sin), f the segment's constant force (stuck masses: v = 0).
    for (std::size_t r = 0; r < nf; ++r) {
        const int i = free_[r];
        cl_F A = force_[r];
        for (std::size_t c = 0; c < nf; ++c) A = A - K_[i][free_[c]] * xf[c] - C_[i][free_[c]] * vf[c];
        for (int h = 0; h < nh_; ++h) A = A + mp.h_amp[h][i] * hcs[h].s;
        out.a[i] = A / mp.m[i];
    }
    energy = mp.zero;
    for (std::size_t r = 0; r < nf; ++r) {
        energy = energy + mp.m[free_[r]] * zh[nf + r] * zh[nf + r];
        for (std::size_t c = 0; c < nf; ++c) energy = energy + zh[r] * K_[free_[r]][free_[c]] * zh[c];
    }
    energy = cln::max(energy * mp.half, mp.zero);
}

void MpSegment::eval(const cl_F& tau, MpEval& out) const {
    const MpModel& mp = mp_;
    const cl_F& Z0 = mp.zero;
    std::vector<CosSin> hcs(nh_);
    for (int h = 0; h < nh_; ++h) hcs[h] = cos_sin_of(mp.h_omega[h] * tau + theta_[h]);
    out.x.assign(static_cast<std::size_t>(n_) + mp.jenkins.size(), Z0);
    out.v.assign(n_, Z0);
    out.a.assign(n_, Z0);
    std::vector<cl_F> xm(n_, Z0), vm(n_, Z0);
    for (int i = 0; i < n_; ++i) {
        out.x[i] = x_fix_[i];
        xm[i] = cln::abs(x_fix_[i]);
    }
    std::vector<cl_F> b2(nf_), b3(nf_);
    cl_F energy = Z0;
    if (damped_)
        eval_damped(tau, out, xm, vm, energy);
    else
        eval_modal(tau, hcs, out, xm, vm, b2, b3);
    for (std::size_t r = 0; r < riders_.size(); ++r) {  // with their partner, at their offset
        const int q = riders_[r], p = mp.carrier(cfg_, q);
        out.x[q] = out.x[p] + offset_[r];
        out.v[q] = out.v[p];
        out.a[q] = out.a[p];
        xm[q] = xm[p] + cln::abs(offset_[r]);
        vm[q] = vm[p];
    }
    // At the start the state is the one carried in, not its modal reconstruction (which
    // differs by the rounding of the modal transformation, times its condition): a switch
    // function that the last event left at zero (a Jenkins element's stretch at the slip
    // force, set from these positions) starts at zero here to its own rounding.
    if (cln::zerop(tau))
        for (int i = 0; i < n_; ++i) {
            out.x[i] = x_fix_[i];
            out.v[i] = mp.fixed(cfg_, i) ? Z0 : v_start_[i];
        }
    sliders_and_switches(out, xm, vm, hcs, [&](std::size_t f) {
        if (damped_) {
            cl_F B = weight2_[f] * cln::sqrt(mp.two * energy);
            for (int h = 0; h < nh_; ++h) B = B + mp.h_omega[h] * mp.h_omega[h] * cln::abs(G_[f][h]);
            return B;
        }
        cl_F B = bound_sin_[f];
        for (int j = 0; j < nf_; ++j) B = B + cln::abs(W_[f][j]) * b2[j] + cln::abs(Z_[f][j]) * b3[j];
        return B;
    });
}

void MpSegment::eval_modal(const cl_F& tau, const std::vector<CosSin>& hcs, MpEval& out, std::vector<cl_F>& xm,
                           std::vector<cl_F>& vm, std::vector<cl_F>& b2, std::vector<cl_F>& b3) const {
    const MpModel& mp = mp_;
    const cl_F& Z0 = mp.zero;
    std::vector<cl_F> q(nf_), qd(nf_), qdd(nf_), mag(nf_), dmag(nf_);

    for (int j = 0; j < nf_; ++j) {
        const cl_F &lam = lambda_[j], &c = c_[j], &sig = sigma_[j], &w = omega_[j], &p = p_[j];
        const cl_F &u0 = u0_[j], &ud0 = ud0_[j];
        cl_F qj, qdj, qddj, m, dm, bb2, bb3;
        if (regime_[j] == Regime::rigid) {
            // q = u0 + u0' tau phi1(-c tau) + p tau^2 phi2(-c tau); q'' = (p - c u0') e^{-c tau}.
            const cl_F x = -(c * tau), e = cln::exp(x), f1 = phi1(mp, x), f2 = phi2(mp, x);
            const cl_F t1 = ud0 * tau * f1, t2 = p * tau * tau * f2;
            qj = u0 + t1 + t2;
            qdj = ud0 * e + p * tau * f1;
            qddj = (p - c * ud0) * e;
            m = cln::abs(u0) + cln::abs(t1) + cln::abs(t2);
            dm = cln::abs(ud0 * e) + cln::abs(p * tau * f1);
            bb2 = cln::abs(qddj);  // decays from here on (c >= 0)
            bb3 = c * bb2;
        } else {
            // u = EC u0 + ES (u0' + sigma u0), u' = EC u0' - ES (lambda u0 + sigma u0').
            cl_F EC, ES;
            if (regime_[j] == Regime::underdamped) {
                const cl_F ed = is_zero(sig) ? mp.one : cln::exp(-(sig * tau));
                const CosSin cs = cos_sin_of(omega_d_[j] * tau);
                EC = ed * cs.c;
                ES = ed * cs.s / omega_d_[j];
            } else if (regime_[j] == Regime::overdamped) {
                // e^{-sigma tau} cosh(gamma tau) = e^{r1 tau}(1 + e^{-2 gamma tau})/2,
                // e^{-sigma tau} sinh(gamma tau)/gamma = e^{r1 tau} tau phi1(-2 gamma tau).
                const cl_F e1 = cln::exp(r1_[j] * tau), x = -(mp.two * gamma_[j] * tau);
                EC = e1 * (mp.one + cln::exp(x)) * mp.half;
                ES = e1 * tau * phi1(mp, x);
            } else {
                const cl_F ed = cln::exp(-(sig * tau));
                EC = ed;
                ES = ed * tau;
            }
            const cl_F v0 = ud0 + sig * u0, a0 = lam * u0 + sig * ud0;
            const cl_F u = EC * u0 + ES * v0, ud = EC * ud0 - ES * a0;
            const cl_F stat = p / lam;
            qj = stat + u;
            qdj = ud;
            qddj = -(c * ud) - lam * u;
            m = cln::abs(stat) + cln::abs(EC * u0) + cln::abs(ES * v0);
            dm = cln::abs(EC * ud0) + cln::abs(ES * a0);
            // E = (u'^2 + lambda u^2)/2 never grows (dE/dt = -c u'^2), so from here on
            // |u''| <= (c + omega) sqrt(2E), |u'''| <= (c (c + omega) + lambda) sqrt(2E).
            const cl_F e2 = cln::sqrt(ud * ud + lam * u * u);
            bb2 = (c + w) * e2;
            bb3 = (c * (c + w) + lam) * e2;
        }
        for (int h = 0; h < nh_; ++h) {
            const cl_F& W = mp.h_omega[h];
            const CosSin& cs = hcs[h];
            if (secular_[j][h]) {
                // q_p = A tau cos(phi), A = -P/(2W); q_p'' = -2AW sin - A W^2 tau cos.
                const cl_F A = -(P_[j][h] / (mp.two * W));
                const cl_F qp = A * tau * cs.c, qpd = A * cs.c - A * W * tau * cs.s;
                qj = qj + qp;
                qdj = qdj + qpd;
                qddj = qddj - mp.two * A * W * cs.s - A * W * W * tau * cs.c;
                m = m + cln::abs(qp);
                dm = dm + cln::abs(qpd);
                const cl_F s_end = tau + max_step_;
                bb2 = bb2 + cln::abs(A) * (mp.two * W + W * W * s_end);
                bb3 = bb3 + cln::abs(A) * (mp.I(3) * W * W + W * W * W * s_end);
                continue;
            }
            const cl_F qp = pa_[j][h] * cs.c + pb_[j][h] * cs.s;
            const cl_F qpd = W * (pb_[j][h] * cs.c - pa_[j][h] * cs.s);
            qj = qj + qp;
            qdj = qdj + qpd;
            qddj = qddj - W * W * qp;
            m = m + cln::abs(qp);
            dm = dm + cln::abs(qpd);
        }
        q[j] = qj;
        qd[j] = qdj;
        qdd[j] = qddj;
        mag[j] = m;
        dmag[j] = dm;
        b2[j] = bb2;
        b3[j] = bb3;
    }

    // x_F = Phi q (likewise v, a); stuck masses fixed (by eval()).
    for (int r = 0; r < nf_; ++r) {
        cl_F x = Z0, v = Z0, a = Z0, xmr = Z0, vmr = Z0;
        for (int j = 0; j < nf_; ++j) {
            const cl_F& ph = phi_[r][j];
            x = x + ph * q[j];
            v = v + ph * qd[j];
            a = a + ph * qdd[j];
            xmr = xmr + cln::abs(ph) * mag[j];
            vmr = vmr + cln::abs(ph) * dmag[j];
        }
        const int i = free_[r];
        out.x[i] = x;
        out.v[i] = v;
        out.a[i] = a;
        xm[i] = xmr;
        vm[i] = vmr;
    }
}

template <class Bound>
void MpSegment::sliders_and_switches(MpEval& out, const std::vector<cl_F>& xm, const std::vector<cl_F>& vm,
                                     const std::vector<CosSin>& hcs, Bound&& bound) const {
    const MpModel& mp = mp_;
    const cl_F& Z0 = mp.zero;
    // The motion the element files read (model/elements/): x, v, a and the magnitudes of x and v.
    const cl_F* rows[] = {out.x.data(), out.v.data(), out.a.data()};
    const cl_F* mags[] = {xm.data(), vm.data(), nullptr};
    const RowsMotion<cl_F, decltype(rows)> motion(rows, &mags, Z0);
    for (std::size_t j = 0; j < mp.jenkins.size(); ++j) {
        const MpModel::Link& e = mp.jenkins[j];
        cl_F& s = out.x[static_cast<std::size_t>(n_) + j];
        if (cfg_.slip[j] == 0) {
            s = slider_[j];
        } else {  // the stretch held at slip F_s / k
            const cl_F held = jenkins::held_stretch(cfg_.slip[j], e.k, e.gap);
            s = along(e.direction(), motion, 0) - held;
        }
    }

    const std::size_t ns = switches_.size();
    out.g.resize(ns, Z0);
    out.dg.resize(ns, Z0);
    out.bound.resize(ns, Z0);
    out.scale.resize(ns, Z0);
    for (std::size_t f = 0; f < ns; ++f) {
        const SwitchFunction& sf = switches_[f];
        const int e = sf.element;
        cl_F g, dg, scale;
        if (!is_release(sf.kind)) {
            const auto p = mp_elements(mp, [&](int j) { return out.x[static_cast<std::size_t>(n_ + j)]; });
            g = switch_derivative(p, sf, motion, 0);
            dg = switch_derivative(p, sf, motion, 1);
            scale = switch_magnitude(p, sf, motion, 0);
        } else {
            // A_i = -(K x)_i - (C v)_i + f_i + F_i(t), with the full K(cfg), C(cfg), f with the sliders' preload;
            // against a partner p, D_i = (m_p A_i - m_i A_p)/(m_i + m_p).
            auto force = [&](int b, cl_F& A, cl_F& dA, cl_F& m) {
                A = fseg_[b], dA = Z0, m = cln::abs(fseg_[b]);
                for (int k = 0; k < n_; ++k) {
                    A = A - K_[b][k] * out.x[k] - C_[b][k] * out.v[k];
                    dA = dA - K_[b][k] * out.v[k] - C_[b][k] * out.a[k];
                    m = m + cln::abs(K_[b][k]) * xm[k] + cln::abs(C_[b][k]) * vm[k];
                }
                for (int h = 0; h < nh_; ++h) {
                    A = A + mp.h_amp[h][b] * hcs[h].s;
                    dA = dA + mp.h_amp[h][b] * mp.h_omega[h] * hcs[h].c;
                    m = m + cln::abs(mp.h_amp[h][b] * hcs[h].s);
                }
            };
            cl_F A, dA, m;
            if (mp.coupled_friction()) {  // D_e = P_e . (A + kinetic friction) (MpModel::held_row)
                const std::vector<cl_F>& P = release_rows_[static_cast<std::size_t>(e)];
                A = dA = m = Z0;
                for (int q = 0; q < n_; ++q) {
                    cl_F Aq, dAq, mq;
                    force(q, Aq, dAq, mq);
                    const cl_F& w = P[static_cast<std::size_t>(q)];
                    A = A + w * (Aq + fric_[static_cast<std::size_t>(q)]);
                    dA = dA + w * dAq;
                    m = m + cln::abs(w) * (mq + cln::abs(fric_[static_cast<std::size_t>(q)]));
                }
            } else {
                force(e, A, dA, m);
            }
            if (const int p = mp.partner[e]; !mp.coupled_friction() && p != kGround) {
                cl_F Ap, dAp, mpart;
                force(p, Ap, dAp, mpart);
                A = mp.against_partner(e, A, Ap);
                dA = mp.against_partner(e, dA, dAp);
                m = mp.against_partner_magnitude(e, m, mpart);
            }
            const cl_F mu_n = mp.mu_s[e] * mp.normal[e];
            const int sigma = sf.kind == SwitchKind::release_pos ? 1 : -1;
            g = friction::release_value(sigma, A, mu_n, 0);
            dg = friction::release_value(sigma, dA, mu_n, 1);
            scale = friction::release_magnitude(m, mu_n, 0);
        }
        out.g[f] = g;
        out.dg[f] = dg;
        out.bound[f] = bound(f);
        out.scale[f] = scale;
    }
}

cl_F MpSegment::derivative_bound(std::size_t f, int k, const cl_F& horizon) const {
    const MpModel& mp = mp_;
    if (damped_) {
        cl_F B = damped_weight(f, k) * cln::sqrt(mp.two * energy0_);
        for (int h = 0; h < nh_; ++h) {
            cl_F Wk = mp.one;
            for (int r = 0; r < k; ++r) Wk = Wk * mp.h_omega[h];
            B = B + Wk * cln::abs(G_[f][h]);
        }
        return B;
    }
    // Bounds on |q_j^(i)| for i = k and k + 1 (the Z terms carry q').
    auto mode_bound = [&](int j, int i) {
        const cl_F &lam = lambda_[j], &c = c_[j];
        cl_F b = mp.zero;
        if (regime_[j] == Regime::rigid) {
            // q'' = (p - c u0') e^{-c tau}, so q^(i) = (-c)^(i-2) q''(0) e^{-c tau}.
            cl_F ci = mp.one;
            for (int r = 2; r < i; ++r) ci = ci * c;
            b = ci * cln::abs(p_[j] - c * ud0_[j]);
        } else {
            // u^(r+2) = -c u^(r+1) - lambda u^(r); |u^(i)| <= sqrt(u^(i)(0)^2 + lambda u^(i-1)(0)^2).
            cl_F a0 = u0_[j], a1 = ud0_[j];
            for (int r = 1; r < i; ++r) {
                const cl_F a2 = -(c * a1) - lam * a0;
                a0 = a1;
                a1 = a2;
            }
            b = cln::sqrt(a1 * a1 + lam * a0 * a0);
        }
        for (int h = 0; h < nh_; ++h) {
            if (!secular_[j][h]) continue;
            const cl_F& W = mp.h_omega[h];
            cl_F Wi1 = mp.one;  // W^(i-1)
            for (int r = 1; r < i; ++r) Wi1 = Wi1 * W;
            b = b + cln::abs(P_[j][h] / (mp.two * W)) * (horizon * Wi1 * W + mp.I(i) * Wi1);
        }
        return b;
    };
    cl_F B = mp.zero;
    for (int j = 0; j < nf_; ++j) {
        if (!is_zero(W_[f][j])) B = B + cln::abs(W_[f][j]) * mode_bound(j, k);
        if (!is_zero(Z_[f][j])) B = B + cln::abs(Z_[f][j]) * mode_bound(j, k + 1);
    }
    for (int h = 0; h < nh_; ++h) {  // the standard particular parts and direct forcing, one sinusoid a harmonic
        const cl_F& W = mp.h_omega[h];
        cl_F A = mp.zero, Bs = D_[f][h];
        for (int j = 0; j < nf_; ++j) {
            if (secular_[j][h]) continue;
            A = A + W_[f][j] * pa_[j][h] + Z_[f][j] * W * pb_[j][h];
            Bs = Bs + W_[f][j] * pb_[j][h] - Z_[f][j] * W * pa_[j][h];
        }
        cl_F Wk = mp.one;
        for (int r = 0; r < k; ++r) Wk = Wk * W;
        B = B + Wk * cln::sqrt(A * A + Bs * Bs);
    }
    return B;
}

cl_F MpSegment::fastest_rate() const {
    cl_F r = mp_.zero;
    if (damped_)
        r = norm_inf(mp_, S_);  // every |eigenvalue| of S is below it
    else
        for (int j = 0; j < nf_; ++j) r = cln::max(r, cln::max(omega_[j], cln::abs(c_[j])));
    for (const cl_F& W : mp_.h_omega) r = cln::max(r, W);
    return r;
}

}  // namespace hsnc::reference
