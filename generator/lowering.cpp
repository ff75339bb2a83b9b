#include "lowering.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <functional>
#include <stdexcept>
#include <initializer_list>
#include <map>
#include <memory>
#include <string>
#include <utility>
#include <vector>

#include "assembly.h"
#include "double_literal.h"
#include "elements/contact.h"
#include "elements/friction.h"
#include "elements/jenkins.h"
#include "ginac_lock.h"  // format_double, for comments
#include "switch_derivative.h"

namespace hsnc {

using GiNaC::numeric;

namespace {

double dbl(const numeric& x) { return x.to_double(); }
double dbl(const DD& x) { return x.to_double(); }
/// Entry (i, k) of K(cfg) or C(cfg) (Derivation::k_dd, c_dd).
const DD& entry(const std::vector<std::vector<DD>>& m, int i, int k) {
    return m[static_cast<std::size_t>(i)][static_cast<std::size_t>(k)];
}
std::string idx(std::size_t k) { return std::to_string(k + 1); }  // 1-based names: q_1, ...
std::string body_name(const Model& m, int b) { return b == kGround ? "ground" : m.masses[b].name; }

/// Terms of a linear combination in the order they are summed; exact zeros
/// are left out (in the printed kernel and the interpreter alike).
/// The first kInline terms live in the object itself: most rows are short (a
/// switch function's g has two or three terms), and a lowering builds
/// thousands of them, so only the long ones (a row over a block's modes)
/// allocate.
class Lin {
public:
    Lin& add(double c, std::uint32_t reg) {
        if (c == 0.0) return *this;
        if (n_ < kInline) {
            inline_[n_] = {c, reg};
        } else {
            if (n_ == kInline) {
                heap_.reserve(4 * kInline);
                heap_.assign(inline_, inline_ + kInline);
            }
            heap_.push_back({c, reg});
        }
        ++n_;
        return *this;
    }
    Lin& add(const numeric& c, std::uint32_t reg) { return add(dbl(c), reg); }
    Lin& add(const DD& c, std::uint32_t reg) { return add(dbl(c), reg); }
    const ProgramTerm* begin() const { return n_ <= kInline ? inline_ : heap_.data(); }
    const ProgramTerm* end() const { return begin() + n_; }
    std::size_t size() const { return n_; }

private:
    static constexpr std::size_t kInline = 12;
    ProgramTerm inline_[kInline];
    std::vector<ProgramTerm> heap_;  // every term once there are more than kInline
    std::size_t n_ = 0;
};

/// A linear combination of registers as a value (register 0 is the constant
/// 1.0), so that the formulas of the element files (model/elements/) build
/// the kernels' switch functions: u - gap, k (u - s) - F_s, ... term by term,
/// in the order they write them. A product needs one constant factor.
class LinValue {
public:
    LinValue() = default;
    LinValue(double c, std::uint32_t reg) { lin_.add(c, reg); }
    static LinValue constant(double c) { return {c, kOne}; }
    const Lin& lin() const { return lin_; }

    friend LinValue operator+(const LinValue& a, const LinValue& b) { return a.plus(b, 1.0); }
    friend LinValue operator-(const LinValue& a, const LinValue& b) { return a.plus(b, -1.0); }
    friend LinValue operator-(const LinValue& a) { return LinValue().plus(a, -1.0); }
    friend LinValue operator*(const LinValue& a, const LinValue& b) {
        return a.is_constant() ? LinValue().plus(b, a.value()) : LinValue().plus(a, b.constant_factor());
    }
    bool is_constant() const { return lin_.size() == 0 || (lin_.size() == 1 && lin_.begin()->reg == kOne); }
    double value() const { return lin_.size() == 0 ? 0.0 : lin_.begin()->c; }

    static constexpr std::uint32_t kOne = 0;

private:
    LinValue plus(const LinValue& b, double factor) const {
        LinValue r = *this;
        for (const ProgramTerm& t : b.lin_) r.lin_.add(factor * t.c, t.reg);
        return r;
    }
    double constant_factor() const {
        if (!is_constant()) throw std::logic_error("LinValue: a product of two non-constant combinations");
        return value();
    }
    Lin lin_;
};

/// The kernels' motion for the element files (model/elements/direction.h):
/// x, v, a of every body as the registers of the eval body, the magnitudes
/// of x and v as the registers that hold them; |s| of a slider is its
/// magnitude register.
class LinMotion {
public:
    using Reg = std::function<std::uint32_t(int)>;
    LinMotion(Reg x, Reg v, Reg a, const std::vector<std::uint32_t>& mx, const std::vector<std::uint32_t>& mv,
              std::map<std::uint32_t, std::uint32_t> magnitude_of)
        : x_{std::move(x), std::move(v), std::move(a)}, mx_(mx), mv_(mv), magnitude_of_(std::move(magnitude_of)) {}
    LinValue x(int k, int body) const {
        return body == kGround ? LinValue() : LinValue(1.0, x_[static_cast<std::size_t>(k)](body));
    }
    LinValue mag(int k, int body) const {
        if (body == kGround) return {};
        return {1.0, (k == 0 ? mx_ : mv_)[static_cast<std::size_t>(body)]};
    }
    LinValue weight(double w) const { return LinValue::constant(w); }
    LinValue abs(const LinValue& v) const {
        if (v.is_constant()) return LinValue::constant(std::fabs(v.value()));
        const auto it = magnitude_of_.find(v.lin().begin()->reg);
        if (v.lin().size() != 1 || v.lin().begin()->c != 1.0 || it == magnitude_of_.end())
            throw std::logic_error("LinMotion: the magnitude of a combination that is not a state register");
        return {1.0, it->second};
    }

private:
    Reg x_[3];
    const std::vector<std::uint32_t>& mx_;
    const std::vector<std::uint32_t>& mv_;
    std::map<std::uint32_t, std::uint32_t> magnitude_of_;
};

/// Appends registers and instructions to one body of a program.
class Builder {
public:
    Builder(Program& p, ProgramBody& b, bool named) : p_(p), b_(b), named_(named) {
        b_.kinds.reserve(2 * b_.code.capacity() + 64);  // registers: inputs, outputs and a temporary per instruction
        if (named_) b_.names.reserve(b_.kinds.capacity());
    }

    std::uint32_t reg(const std::string& name, RegisterKind kind) {
        if (named_) b_.names.push_back(name);
        b_.kinds.push_back(kind);
        return static_cast<std::uint32_t>(b_.kinds.size() - 1);
    }
    /// A register named prefix + number + suffix, the name formatted only for a named program.
    std::uint32_t reg(const char* prefix, std::size_t number, RegisterKind kind, const char* suffix = "") {
        if (!named_) return reg(std::string(), kind);
        return reg(prefix + std::to_string(number) + suffix, kind);
    }
    std::uint32_t temp(const std::string& name) { return reg(name, RegisterKind::temp); }
    std::uint32_t temp(const char* prefix, std::size_t number) { return reg(prefix, number, RegisterKind::temp); }

    ProgramInstr& emit(ProgramInstr in) {
        b_.code.push_back(std::move(in));
        return b_.code.back();
    }
    ProgramInstr& lin(std::uint32_t dst, const Lin& l, std::uint32_t base = kNoRegister) {
        ProgramInstr in{ProgramOp::lincomb};
        in.dst = dst;
        in.a = base;
        in.first = static_cast<std::uint32_t>(p_.terms.size());
        in.count = static_cast<std::uint32_t>(l.size());
        p_.terms.insert(p_.terms.end(), l.begin(), l.end());
        return emit(std::move(in));
    }
    ProgramInstr& lin_ld(std::uint32_t dst, const Lin& l) {
        ProgramInstr& in = lin(dst, l);
        in.op = ProgramOp::lincomb_ld;
        return in;
    }
    /// Sets an instruction's comment and note, in a named program (ProgramNames).
    ProgramInstr& annotate(ProgramInstr& in, const std::string& comment, const std::string& note = "") {
        if (!named_ || (comment.empty() && note.empty())) return in;
        in.text = static_cast<std::uint32_t>(b_.texts.size());
        b_.texts.push_back({comment, note});
        return in;
    }
    ProgramInstr& unary(ProgramOp op, std::uint32_t dst, std::uint32_t a) {
        ProgramInstr in{op};
        in.dst = dst;
        in.a = a;
        return emit(std::move(in));
    }

private:
    Program& p_;
    ProgramBody& b_;
    bool named_;
};

std::uint32_t constant(Program& p, double v, const std::string& name = "") {
    p.constants.push_back(v);
    p.constant_names.push_back(name);
    return static_cast<std::uint32_t>(p.constants.size() - 1);
}

/// The preload k_j s_j w_i of every Jenkins element stuck in cfg on mass i,
/// as fn(coefficient of s_j, j): +k_j where i is its a, -k_j where i is its
/// b, k_j w_i along a general direction.
template <class Fn>
void for_each_slider_preload(const Model& model, const Configuration& cfg, int i, Fn&& fn) {
    for (std::size_t j = 0; j < model.jenkins.size(); ++j) {
        if (cfg.slip[j] != 0) continue;
        const Jenkins& e = model.jenkins[j];
        for_each_term(e.direction(), [&](int body, double w) {
            if (body == i) fn(e.k * w, j);
        });
    }
}

/// The constants of each mode (ModeConstant layout) appended to p.constants;
/// the index of each mode's first.
std::vector<std::uint32_t> mode_constants(Program& p, const Derivation& d, bool named) {
    const std::size_t nm = d.modes.size();
    std::vector<std::uint32_t> mode_k(nm);
    for (std::size_t j = 0; j < nm; ++j) {
        const Mode& m = d.modes[j];
        const std::string J = named ? idx(j) : std::string();
        double k[kModeConstants] = {};
        std::string names[kModeConstants];  // printed names (a named program's only)
        auto name = [&](ModeConstant c, const char* prefix) {
            if (named) names[c] = prefix + J;
        };
        k[kModeLambda] = dbl(m.lambda), name(kModeLambda, "lambda_");
        k[kModeSigma] = dbl(m.sigma), name(kModeSigma, "sigma_");
        k[kModeKappa] = dbl(m.kappa), name(kModeKappa, "kappa_");
        switch (m.regime) {
            case Regime::undamped:
            case Regime::underdamped:
                k[kModeOmegaD] = dbl(m.omega_d), name(kModeOmegaD, "omega_d_");
                k[kModeInvOmegaD] = 1.0 / dbl(m.omega_d);
                break;
            case Regime::overdamped:
                k[kModeGamma] = dbl(m.gamma), name(kModeGamma, "gamma_");
                k[kModeR1] = dbl(m.r1), name(kModeR1, "r1_");
                k[kModeNegTwoGamma] = -2.0 * dbl(m.gamma);
                k[kModeHalfInvGamma] = 0.5 / dbl(m.gamma);
                break;
            case Regime::rigid_damped:
                k[kModeC] = dbl(m.c), name(kModeC, "c_");
                k[kModeInvC] = 1.0 / dbl(m.c);
                break;
            default:
                break;
        }
        mode_k[j] = static_cast<std::uint32_t>(p.constants.size());
        for (std::uint32_t c = 0; c < kModeConstants; ++c) constant(p, k[c], names[c]);
    }
    return mode_k;
}

/// The held force of stuck dof i on a coupled M as a combination of the
/// forces on bodies: D_i = A_i - sum_r c_r A_r over the free dofs r with
/// c_r != 0 (Derivation::held).
std::vector<std::pair<int, DD>> held_terms(const Derivation& d, int i) {
    const auto at = std::find(d.stuck_dofs.begin(), d.stuck_dofs.end(), i) - d.stuck_dofs.begin();
    const std::vector<DD>& c = d.held[static_cast<std::size_t>(at)];
    std::vector<std::pair<int, DD>> terms{{i, DD(1.0)}};
    for (std::size_t r = 0; r < c.size(); ++r)
        if (!c[r].is_zero()) terms.emplace_back(d.free_dofs[r], -c[r]);
    return terms;
}

/// The held force of stuck rider i as terms over dofs, i first: against its
/// partner p, D = (m_p A_i - m_i A_p)/(m_i + m_p), the force that holds the
/// pair together (assembly.h driving_force); where a body takes part in
/// several frictions (Model::shared_partner), D_i = sum over S_i of A_k -
/// (M_S / M_b) sum over the body b it rides of A_k (model/held_mass.h: S_i the
/// dofs i carries, assembly.h carried(); b carrier(i), none when held still).
std::vector<std::pair<int, DD>> partner_terms(const Model& model, const Derivation& d, int i) {
    const int p = model.friction_slot(static_cast<std::size_t>(i)).partner;
    const DD mi(model.masses[static_cast<std::size_t>(i)].m);
    if (!model.shared_partner()) {
        const DD mpn(model.masses[static_cast<std::size_t>(p)].m);
        return {{i, mpn / (mi + mpn)}, {p, -mi / (mi + mpn)}};
    }
    const std::vector<int> S = carried(model, d.cfg.stuck, i);
    const int b = carrier(model, d.cfg, static_cast<std::size_t>(i));
    std::vector<int> body;  // b first, then every dof riding it, in dof order
    if (b != kGround) {
        body.push_back(b);
        for (std::size_t k = 0; k < model.dof(); ++k)
            if (static_cast<int>(k) != b && d.cfg.stuck[k] && carrier(model, d.cfg, k) == b)
                body.push_back(static_cast<int>(k));
    }
    DD ms = mi, mc(0.0);  // 0 + m is m exactly: the same sums as from the first term
    for (std::size_t k = 1; k < S.size(); ++k) ms = ms + DD(model.masses[static_cast<std::size_t>(S[k])].m);
    for (int k : body) mc = mc + DD(model.masses[static_cast<std::size_t>(k)].m);
    const DD share = body.empty() ? DD(0.0) : ms / mc;
    auto in_S = [&](int k) { return std::find(S.begin(), S.end(), k) != S.end(); };
    std::vector<std::pair<int, DD>> terms{{i, DD(1.0) - share}};
    for (std::size_t k = 1; k < S.size(); ++k) terms.emplace_back(S[k], DD(1.0) - share);
    for (int k : body)
        if (!in_S(k)) terms.emplace_back(k, -share);
    return terms;
}

/// The comment of stuck friction i's release function g_F in a named program:
/// the held force as partner_terms or (on a coupled M) held_terms writes it.
std::string held_comment(const Model& model, int i, bool pos, const std::string& F, bool coupled) {
    const std::string head = "g_" + F + ": " + (pos ? "D" : "-D") + " - mu_s N of ";
    const std::string& name = model.masses[static_cast<std::size_t>(i)].name;
    if (coupled)
        return head + "stuck " + name +
               ", D = A_i - M_iF M_FF^-1 A_F (coupled M), A = -K x - C v + f + sum_h F_h sin - mu_k N sgn";
    const int p = model.friction_slot(static_cast<std::size_t>(i)).partner;
    return head + name + " stuck to " +
           (p == kGround ? std::string("the ground") : model.masses[static_cast<std::size_t>(p)].name) +
           (model.friction_chain()   ? ", D = sum over S_i of A_k - (M_S / M_b) sum over its body of A_k"
            : model.shared_partner() ? ", D = A_i - m_i a_partner"
                                     : ", D = (m_p A_i - m_i A_p)/(m_i + m_p)");
}

/// The kinetic friction a held force reads on free dof i (model/held_mass.h
/// kinetic_friction): -mu_k N sgn_i of its own and +mu_k N sgn_q of each
/// friction q against it; `magnitude` the sum of their mu_k N.
template <class Sgn>
Lin kinetic_lin(const Model& model, const std::vector<double>& mu_k_n, int i, const Sgn& sgn, double& magnitude) {
    Lin l;
    magnitude = 0.0;
    if (mu_k_n[static_cast<std::size_t>(i)] != 0.0)
        l.add(-mu_k_n[static_cast<std::size_t>(i)], sgn(i)), magnitude += mu_k_n[static_cast<std::size_t>(i)];
    for (std::size_t q = 0; q < model.dof(); ++q)
        if (model.friction_slot(q).partner == i && mu_k_n[q] != 0.0)
            l.add(mu_k_n[q], sgn(static_cast<int>(q))), magnitude += mu_k_n[q];
    return l;
}

/// out[j] = sum_k c_k of[k][j] for the combination `terms` (c_k its
/// coefficients), summed in their order.
void combine(const std::vector<std::pair<int, DD>>& terms, const std::vector<std::vector<DD>>& of, std::vector<DD>& out) {
    for (std::size_t j = 0; j < out.size(); ++j) {
        out[j] = terms[0].second * of[0][j];
        for (std::size_t k = 1; k < terms.size(); ++k) out[j] = out[j] + terms[k].second * of[k][j];
    }
}

// u = w^T x (or its rate, letter "v") as a comment: "x[a] - x[b]", or
// "+ w_1 x[b_1] + ..." along a general direction.
std::string along_text(const Model& model, const Direction& d, const char* letter = "x") {
    const std::string x = letter;
    if (!d.weighted()) return x + "[" + body_name(model, d.a) + "] - " + x + "[" + body_name(model, d.b) + "]";
    std::string s;
    for (int i = 0; i < d.count; ++i)
        s += std::string(i == 0 ? "" : " ") + "+ " + format_double(d.terms[i].w) + " " + x + "[" +
             body_name(model, d.terms[i].body) + "]";
    return s;
}

// G of a contact as the comment of its switch function: "x[a] - x[b] - gap",
// or "+ w_1 x[b_1] + ... - gap" along a general direction.
std::string gap_text(const Model& model, const Contact& ct) {
    return along_text(model, ct.direction()) + " - " + format_double(ct.gap);
}

// The modal rows of an element's u = w^T x (a contact's G = u - gap):
// alpha_j = sum_i w_i V_ij over the modes that move one of its bodies, and the
// harmonic parts sum_i w_i X_hi (lower's V, harmonic_x, each_mode_of).
template <class Vf, class Hx, class Each>
void along_rows(const Direction& d, const Vf& V, const Hx& harmonic_x, const Each& each_mode_of, std::vector<DD>& al,
                std::vector<DD>& Gs, std::vector<DD>& Gc) {
    if (!d.weighted()) {  // x[a] - x[b]
        each_mode_of({d.a, d.b}, [&](std::size_t j) { al[j] = V(d.a, j) - V(d.b, j); });
        for (std::size_t h = 0; h < Gs.size(); ++h) {
            Gs[h] = harmonic_x(h, d.a, true) - harmonic_x(h, d.b, true);
            Gc[h] = harmonic_x(h, d.a, false) - harmonic_x(h, d.b, false);
        }
        return;
    }
    std::vector<char> seen(al.size(), 0);
    for (int i = 0; i < d.count; ++i) {
        const Weight& t = d.terms[i];
        each_mode_of({t.body}, [&](std::size_t j) { seen[j] = 1; });
        for (std::size_t h = 0; h < Gs.size(); ++h) {
            Gs[h] = Gs[h] + DD(t.w) * harmonic_x(h, t.body, true);
            Gc[h] = Gc[h] + DD(t.w) * harmonic_x(h, t.body, false);
        }
    }
    for (std::size_t j = 0; j < al.size(); ++j)
        if (seen[j])
            for (int i = 0; i < d.count; ++i) al[j] = al[j] + DD(d.terms[i].w) * V(d.terms[i].body, j);
}

bool is_slip(SwitchKind k) {
    return k == SwitchKind::slip_pos || k == SwitchKind::slip_neg || k == SwitchKind::slip_velocity;
}

// What a Jenkins element's switch function is, as its comment.
std::string jenkins_comment(const Model& model, const SwitchFunction& sf) {
    const Jenkins& el = model.jenkins[static_cast<std::size_t>(sf.element)];
    if (sf.kind == SwitchKind::slip_velocity)  // u' = v[a] - v[b] (w^T v) of a slipping element
        return "relative velocity of " + el.name + " (slipping) = " + along_text(model, el.direction(), "v");
    // +-k (u - s) - F_s: the stretch force of a stuck element against F_s.
    return std::string(sf.kind == SwitchKind::slip_pos ? "" : "-") + "k e - F_s of stuck " + el.name +
           ", e = " + along_text(model, el.direction()) + " - s";
}

// The modal rows of a Jenkins element's switch function (lower's V,
// harmonic_x, each_mode_of): stuck, +-k (u - s) - F_s on q (alpha = +-k u's
// rows); slipping, u' on q' (beta = u's rows, the harmonic parts
// differentiated).
template <class Vf, class Hx, class Each>
void jenkins_rows(const Model& model, const Derivation& d, const SwitchFunction& sf, const Vf& V, const Hx& harmonic_x,
                  const Each& each_mode_of, std::vector<DD>& al, std::vector<DD>& be, std::vector<DD>& Gs,
                  std::vector<DD>& Gc) {
    const Jenkins& el = model.jenkins[static_cast<std::size_t>(sf.element)];
    const std::size_t nm = al.size(), nh = Gs.size();
    if (sf.kind != SwitchKind::slip_velocity) {
        const DD ks(sf.kind == SwitchKind::slip_pos ? el.k : -el.k);
        if (el.weights.empty()) {
            for (std::size_t jm = 0; jm < nm; ++jm) al[jm] = ks * (V(el.a, jm) - V(el.b, jm));
            for (std::size_t h = 0; h < nh; ++h) {
                Gs[h] = ks * (harmonic_x(h, el.a, true) - harmonic_x(h, el.b, true));
                Gc[h] = ks * (harmonic_x(h, el.a, false) - harmonic_x(h, el.b, false));
            }
            return;
        }
        along_rows(el.direction(), V, harmonic_x, each_mode_of, al, Gs, Gc);  // k times u's rows
        for (DD& r : al) r = ks * r;
        for (std::size_t h = 0; h < nh; ++h) Gs[h] = ks * Gs[h], Gc[h] = ks * Gc[h];
        return;
    }
    std::vector<DD> us(nh), uc(nh);
    if (el.weights.empty()) {
        for (std::size_t jm = 0; jm < nm; ++jm) be[jm] = V(el.a, jm) - V(el.b, jm);
        for (std::size_t h = 0; h < nh; ++h) {
            us[h] = harmonic_x(h, el.a, true) - harmonic_x(h, el.b, true);
            uc[h] = harmonic_x(h, el.a, false) - harmonic_x(h, el.b, false);
        }
    } else {
        along_rows(el.direction(), V, harmonic_x, each_mode_of, be, us, uc);
    }
    for (std::size_t h = 0; h < nh; ++h) {
        const DD W = d.harmonics[h].omega;
        Gs[h] = -W * uc[h];
        Gc[h] = W * us[h];
    }
}

}  // namespace

Program lower(const Derivation& d, ProgramNames names) {
    const bool named = names == ProgramNames::yes;
    const Model& model = *d.model;
    const std::size_t n = model.dof(), nf = d.n_free(), nm = d.modes.size(), nh = d.harmonics.size();
    const std::size_t nj = model.jenkins.size();
    Program p;
    p.n_dof = static_cast<int>(n);
    p.n_slider = static_cast<int>(nj);
    p.cfg = d.cfg;
    p.switches = d.switches;
    p.max_step = d.max_step;
    // V and W rounded once (each use below rounds the same double-double value), and
    // each mass's index among the free masses (-1: stuck).
    struct Matrix {  // rows of nf doubles, one allocation
        std::vector<double> a;
        std::size_t cols;
        double* operator[](std::size_t j) { return a.data() + j * cols; }
        const double* operator[](std::size_t j) const { return a.data() + j * cols; }
    };
    Matrix vd{std::vector<double>(nm * nf), nf}, wd{std::vector<double>(nm * nf), nf};
    // The sparsity of V and W: a mode lives on its block's coordinates (derivation.h),
    // exact zeros elsewhere. mode_rows[j] lists the coordinates r where V_rj or W_jr
    // is nonzero, row_modes[r] the modes j (both ascending), so that each sum below
    // visits the terms it keeps (Lin leaves out exact zeros) and no others: the same
    // terms in the same order as the dense loops, at the cost of the blocks.
    std::vector<std::vector<std::size_t>> mode_rows(nm), row_modes(nf);
    std::size_t nonzeros = 0;
    for (std::size_t j = 0; j < nm; ++j) {
        for (std::size_t r = 0; r < nf; ++r) {
            vd[j][r] = dbl(d.modes[j].v[r]);
            wd[j][r] = dbl(d.modes[j].w[r]);
            if (vd[j][r] != 0.0 || wd[j][r] != 0.0 || !d.modes[j].v[r].is_zero() || !d.modes[j].w[r].is_zero())
                mode_rows[j].push_back(r);
        }
        nonzeros += mode_rows[j].size();
    }
    for (std::size_t j = 0; j < nm; ++j)  // a block's modes share their rows: each row_modes[r] as long as them
        for (std::size_t r : mode_rows[j]) {
            if (row_modes[r].empty()) row_modes[r].reserve(mode_rows[j].size());
            row_modes[r].push_back(j);
        }
    // The exact constant forces, rounded once each by derive() (Derivation::f_const_double).
    const std::vector<double>&f_const = d.f_const_double, &mu_k_n = d.mu_k_n_double;
    std::vector<int> free_of(n, -1), coord_of(n, -1);  // coord_of: a rider moves with its carrier's coordinate
    for (std::size_t r = 0; r < nf; ++r) free_of[d.free_dofs[r]] = coord_of[d.free_dofs[r]] = static_cast<int>(r);
    auto partner_of = [&](int q) { return model.friction_slot(static_cast<std::size_t>(q)).partner; };
    // The body a rider moves with: its partner, or up a chain the first body not stuck (assembly.h carrier()).
    auto carrier_of = [&](int q) { return carrier(model, d.cfg, static_cast<std::size_t>(q)); };
    for (int q : d.riders) coord_of[q] = free_of[carrier_of(q)];

    // ---- constants: per mode (ModeConstant layout), per harmonic (Omega, phase) ----
    const std::vector<std::uint32_t> mode_k = mode_constants(p, d, named);
    std::vector<std::uint32_t> harm_k(nh);
    for (std::size_t h = 0; h < nh; ++h) {
        harm_k[h] = constant(p, dbl(d.harmonics[h].omega), named ? "Omega_" + idx(h) : std::string());
        constant(p, dbl(d.harmonics[h].phase));
    }

    // ================= setup =================
    // Room for the program up front (sizes estimated from the configuration):
    // growing these vectors instruction by instruction moved them many times.
    const std::size_t ns = d.switches.size();
    // setup: about 10 instructions per free mass, 17 per mode and 8 n^2 terms
    // (modal forces, static offset, the projection to modes, x(0) and v(0) for its
    // refinement, the refinement); eval: a mass_state of n terms per mass and, per
    // switch function, a bound over the modes.
    p.setup.code.reserve(12 * nf + 20 * nm + 8 * nh + 16);
    p.eval.code.reserve(4 * n + 2 * nm + 6 * ns + 4 * nh + 16);
    p.terms.reserve(8 * nonzeros + 6 * nf * nh + n * (6 + 6 * nh) + nonzeros + ns * (nm + 24) + 64);
    Builder s(p, p.setup, named);
    s.reg("1.0", RegisterKind::one);
    s.reg("t0", RegisterKind::input);
    s.reg("t0_lo", RegisterKind::input);
    for (std::size_t i = 0; i < n + nj; ++i) s.reg("x0[", i, RegisterKind::input, "]");
    for (std::size_t i = 0; i < n; ++i) s.reg("v0[", i, RegisterKind::input, "]");
    for (std::size_t i = 0; i < n; ++i) s.reg("sgn[", i, RegisterKind::input, "]");
    const std::uint32_t ONE = 0;
    auto x0 = [&](int i) { return Program::kSetupX0 + static_cast<std::uint32_t>(i); };
    auto v0 = [&](int i) { return p.setup_v0() + static_cast<std::uint32_t>(i); };
    auto sgn = [&](int i) { return p.setup_sgn() + static_cast<std::uint32_t>(i); };
    // A coefficient slot: coef[k] = src at the end of setup, read by eval.
    std::vector<std::uint32_t> slot_src;
    // Its name (what coef[k] holds, for the printed layout) is prefix + number.
    auto slot_name = [&](const char* prefix, std::size_t number) {
        p.coef_names.push_back(named ? prefix + std::to_string(number) : std::string());
        const auto k = static_cast<std::uint32_t>(p.coef_names.size() - 1);
        p.setup_coef.push_back(s.reg("coef[", k, RegisterKind::output, "]"));
        return k;
    };
    auto slot = [&](const char* prefix, std::size_t number, std::uint32_t src, const std::string& comment = "",
                    const std::string& note = "") {
        const std::uint32_t k = slot_name(prefix, number);
        s.annotate(s.unary(ProgramOp::copy, p.setup_coef.back(), src), comment, note);
        return k;
    };
    auto slot_lin = [&](const char* prefix, std::size_t number, const Lin& l) {
        const std::uint32_t k = slot_name(prefix, number);
        s.lin(p.setup_coef.back(), l);
        return k;
    };
    // The slots eval reads by what they hold.
    std::map<int, std::uint32_t> e_slot;                    // a rider's offset
    std::vector<std::uint32_t> theta_slot(nh), c_theta_slot(nh), x_st_slot(nf), p_slot(nm);
    std::vector<std::uint32_t> x_stuck_slot(n), s_stuck_slot(nj);

    // A rider's offset from its partner, fixed for the segment: e_q = x0_q - x0_partner.
    std::map<int, std::uint32_t> offset;
    for (int q : d.riders) {
        offset[q] = s.temp("e_" + model.masses[static_cast<std::size_t>(q)].name);
        s.annotate(s.lin(offset[q], Lin().add(1.0, x0(q)).add(-1.0, x0(carrier_of(q)))),
                   q == d.riders.front()
                       ? "Riders (stuck to their friction partner) keep their offset e = x0 - x0_partner."
                       : "");
        e_slot[q] = slot("e_", static_cast<std::size_t>(q), offset[q], "",
                         named ? model.masses[static_cast<std::size_t>(q)].name + " rides its partner" : "");
    }
    std::vector<std::uint32_t> f(nf), pj(nm);
    if (nf > 0) {
        for (std::size_t r = 0; r < nf; ++r) {
            Lin l;
            // The coordinate's force T^T (f - K e): its free mass's, then its riders'.
            std::vector<int> members{d.free_dofs[r]};
            for (int q : d.riders)
                if (coord_of[q] == static_cast<int>(r)) members.push_back(q);
            for (int i : members) {
                l.add(f_const[i], ONE);
                for (int st : d.stuck_dofs) l.add(-dbl(entry(d.k_dd, i, st)), x0(st));
                for (int q : d.riders) l.add(-dbl(entry(d.k_dd, i, q)), offset[q]);
                for_each_slider_preload(model, d.cfg, i,
                                        [&](double k, std::size_t j) { l.add(k, x0(static_cast<int>(n + j))); });
                l.add(-mu_k_n[i], sgn(i));
                for (std::size_t q = 0; q < n; ++q)  // a sliding pair: the friction's reaction on the partner
                    if (partner_of(static_cast<int>(q)) == i) l.add(mu_k_n[q], sgn(static_cast<int>(q)));
            }
            const int i = d.free_dofs[r];
            f[r] = s.temp("f_", r + 1);
            s.annotate(s.lin(f[r], l),
                 r == 0 ? "Constant force on the free masses: loads + preload - K_FS x_S - mu_k N sgn (Eq. 7-9)"
                          + std::string(nj > 0 ? ",\nwith k s of every stuck Jenkins element (slider s = x0[n + j])." : ".")
                        : "",
                 model.masses[i].name);
        }
        for (std::size_t j = 0; j < nm && !d.state_space; ++j) {
            Lin l;
            for (std::size_t r : mode_rows[j]) l.add(vd[j][r], f[r]);
            pj[j] = s.temp("p_", j + 1);
            s.annotate(s.lin(pj[j], l), j == 0 ? "Modal forces p = V^T f." : "");
        }
    }
    // Forcing phases at the segment start.
    std::vector<std::uint32_t> s_theta(nh), c_theta(nh);
    for (std::size_t h = 0; h < nh; ++h) {
        const std::uint32_t theta = s.temp("theta_", h + 1);
        ProgramInstr in{ProgramOp::phase};
        in.dst = theta;
        in.a = Program::kSetupT0;
        in.b = Program::kSetupT0Lo;
        in.first = harm_k[h];
        if (h == 0) s.annotate(in, "Forcing phases at the segment start: theta_h = Omega_h (t0 + t0_lo) + phase_h, reduced.");
        s.emit(in);
        s_theta[h] = s.temp("s_theta_", h + 1);
        s.unary(ProgramOp::sin, s_theta[h], theta);
        c_theta[h] = s.temp("c_theta_", h + 1);
        s.unary(ProgramOp::cos, c_theta[h], theta);
        theta_slot[h] = slot("theta_", h + 1, theta);
        c_theta_slot[h] = slot("c_theta_", h + 1, c_theta[h]);
    }
    std::vector<std::uint32_t> x_st(nf);
    // 1 / lambda_j once per mode (double-double: v / lambda and v (1 / lambda)
    // round to the same double but where they straddle a midpoint, about one
    // in 1e16), not a division per term.
    std::vector<DD> inv_lambda(d.state_space ? 0 : nm);
    for (std::size_t j = 0; j < inv_lambda.size(); ++j)
        if (!d.modes[j].lambda.is_zero()) inv_lambda[j] = DD(1.0) / d.modes[j].lambda;
    for (std::size_t r = 0; r < nf; ++r) {
        Lin l;
        if (d.state_space) {
            for (std::size_t c = 0; c < nf; ++c) l.add(d.state.static_inverse[r][c], f[c]);
        } else {
            for (std::size_t j : row_modes[r])
                if (!d.modes[j].lambda.is_zero()) l.add(d.modes[j].v[r] * inv_lambda[j], pj[j]);
        }
        x_st[r] = s.temp("x_st_", r + 1);
        s.annotate(s.lin(x_st[r], l),
             r != 0            ? ""
             : d.state_space ? "Static offset x_st = K_FF^-1 f (dampers: state-space pseudo-modes, derivation.h)."
                             : "Static offset x_st = V (p / lambda) over the elastic modes.",
             model.masses[d.free_dofs[r]].name);
        x_st_slot[r] = slot("x_st_", r + 1, x_st[r]);
    }
    std::vector<std::uint32_t> qh0(nm), dqh0(nm);
    if (nf > 0) {
        // The homogeneous initial state from the physical residual x0 - x_p(0), where
        // x_p(0) = x_st + sum_h (xs_h sin theta_h + xc_h cos theta_h) uses exactly the
        // constants eval adds back at tau = 0 (a modal q(0) - q_p(0) made setup subtract a
        // slightly different particular part than eval adds: a drift per restart,
        // tests/test_restart_drift.cpp).
        std::vector<std::uint32_t> xh(nf), vh(nf);
        for (std::size_t r = 0; r < nf; ++r) {
            const int i = d.free_dofs[r];
            Lin x, v;
            x.add(1.0, x0(i)).add(-1.0, x_st[r]);
            v.add(1.0, v0(i));
            for (std::size_t h = 0; h < nh; ++h) {
                const HarmonicData& hd = d.harmonics[h];
                const double W = dbl(hd.omega), xs = dbl(hd.xs[r]), xc = dbl(hd.xc[r]);
                x.add(-xs, s_theta[h]).add(-xc, c_theta[h]);
                v.add(-(W * xs), c_theta[h]).add(W * xc, s_theta[h]);
            }
            xh[r] = s.temp("xh_", r + 1);
            s.annotate(s.lin_ld(xh[r], x),
                 r == 0 ? "Homogeneous part of the initial state in x: xh = x0 - x_p(0), vh = v0 - v_p(0), with\n"
                          "x_p = x_st + sum_h (xs sin + xc cos) and the same constants as eval (long double sums)."
                        : "");
            vh[r] = s.temp("vh_", r + 1);
            s.lin_ld(vh[r], v);
        }
        // Mode j's q and q' from one pair of physical vectors: q = W x, q' = W v, or for
        // state-space pseudo-modes q = W x + W_v v, q' = dW_x x + dW_v v.
        auto project = [&](std::size_t j, const std::vector<std::uint32_t>& px, const std::vector<std::uint32_t>& pv,
                           Lin& q, Lin& dq) {
            const Mode& m = d.modes[j];
            if (d.state_space) {
                for (std::size_t r = 0; r < nf; ++r) q.add(wd[j][r], px[r]).add(m.w_v[r], pv[r]);
                for (std::size_t r = 0; r < nf; ++r) dq.add(m.dw_x[r], px[r]).add(m.dw_v[r], pv[r]);
                return;
            }
            for (std::size_t r : mode_rows[j]) {
                q.add(wd[j][r], px[r]);
                dq.add(wd[j][r], pv[r]);
            }
        };
        // The projection q = W xh, q' = W vh, refined once, against what eval returns at
        // tau = 0 (below). V and W are inverse only to rounding, so xh -> W xh -> V W xh
        // is the fixed matrix I + E (E ~ eps): applied at every segment start it is a
        // bias (a steady energy gain), not noise; the refinement leaves E^2.
        std::vector<std::uint32_t> q0(nm), dq0(nm);
        for (std::size_t j = 0; j < nm; ++j) {
            Lin q, dq;
            project(j, xh, vh, q, dq);
            q0[j] = s.temp("q0_", j + 1);
            s.annotate(s.lin(q0[j], q), j == 0 ? "Its modal coordinates q = W xh, q' = W vh." : "");
            dq0[j] = s.temp("dq0_", j + 1);
            s.lin(dq0[j], dq);
        }
        // The refinement, against what eval returns at tau = 0: x(0) and v(0) with eval's
        // constants in eval's order, the residuals x0 - x(0), v0 - v(0) (long double)
        // mapped back with W. It removes the bias of V W = I + E and the rounding of x(0),
        // a sum of terms larger than x: without it a state restarted again and again kept
        // moving the same way (tests/test_restart_drift.cpp).
        std::vector<std::uint32_t> ex(nf), ev(nf);
        for (std::size_t r = 0; r < nf; ++r) {
            const int i = d.free_dofs[r];
            Lin x, v;
            x.add(1.0, x_st[r]);
            for (std::size_t j : row_modes[r]) {
                x.add(vd[j][r], q0[j]);
                v.add(vd[j][r], dq0[j]);
            }
            for (std::size_t h = 0; h < nh; ++h) {
                const HarmonicData& hd = d.harmonics[h];
                const double W = dbl(hd.omega), xs = dbl(hd.xs[r]), xc = dbl(hd.xc[r]);
                x.add(xs, s_theta[h]).add(xc, c_theta[h]);
                v.add(W * xs, c_theta[h]).add(-W * xc, s_theta[h]);
            }
            const std::uint32_t xe = s.temp("xe_", r + 1), ve = s.temp("ve_", r + 1);
            s.annotate(s.lin(xe, x),
                 r == 0 ? "Refinement against eval at tau = 0 (same constants, same order): residuals x0 - x(0), "
                          "v0 - v(0)."
                        : "");
            s.lin(ve, v);
            ex[r] = s.temp("ex_", r + 1);
            s.lin_ld(ex[r], Lin().add(1.0, x0(i)).add(-1.0, xe));
            ev[r] = s.temp("ev_", r + 1);
            s.lin_ld(ev[r], Lin().add(1.0, v0(i)).add(-1.0, ve));
        }
        for (std::size_t j = 0; j < nm; ++j) {
            Lin q, dq;
            project(j, ex, ev, q, dq);
            qh0[j] = s.temp("qh0_", j + 1);
            s.lin(qh0[j], q, q0[j]);
            dqh0[j] = s.temp("dqh0_", j + 1);
            s.lin(dqh0[j], dq, dq0[j]);
        }
    }
    // Per mode: A = q_h(0), B = q_h'(0) + sigma A and the derivative pairs.
    std::vector<std::uint32_t> mode_coef(nm);
    for (std::size_t j = 0; j < nm; ++j) {
        const Mode& m = d.modes[j];
        const std::string J = idx(j);
        const double sigma = dbl(m.sigma), kappa = dbl(m.kappa);
        const std::string comment = !named ? std::string()
                                           : "Mode " + J + " (" + regime_name(m.regime) +
                                                 "): A = q_h(0), B = q_h'(0) + sigma A (the particular\n"
                                                 "parts start at rest or are in x_p) and the derivative pairs, consistent "
                                                 "to rounding.";
        bool commented = false;
        if (m.regime == Regime::rigid || m.regime == Regime::rigid_damped) {
            p_slot[j] = slot("p_", j + 1, pj[j], comment,
                             m.regime == Regime::rigid ? "q_p = p tau^2 / 2" : "q_p = p tau^2 phi2(-c tau)");
            commented = true;
        }
        const std::uint32_t A = s.temp("A_", j + 1), B = s.temp("B_", j + 1);
        s.annotate(s.unary(ProgramOp::copy, A, qh0[j]), commented ? "" : comment);
        s.lin(B, Lin().add(1.0, dqh0[j]).add(sigma, A));
        mode_coef[j] = slot("A_", j + 1, A);
        slot("B_", j + 1, B);
        const std::uint32_t A1 = s.temp("A1_", j + 1), B1 = s.temp("B1_", j + 1);
        s.lin(A1, Lin().add(1.0, B).add(-sigma, A));
        s.lin(B1, Lin().add(-kappa, A).add(-sigma, B));
        slot("A1_", j + 1, A1);
        slot("B1_", j + 1, B1);
        slot_lin("A2_", j + 1, Lin().add(1.0, B1).add(-sigma, A1));
        slot_lin("B2_", j + 1, Lin().add(-kappa, A1).add(-sigma, B1));
    }
    for (int st : d.stuck_dofs)
        x_stuck_slot[static_cast<std::size_t>(st)] =
            slot("x_stuck_", static_cast<std::size_t>(st), x0(st), "", named ? model.masses[st].name + " is stuck" : "");
    for (std::size_t j = 0; j < nj; ++j)
        if (d.cfg.slip[j] == 0)
            s_stuck_slot[j] = slot("s_stuck_", j, x0(static_cast<int>(n + j)), "",
                                   named ? "the slider of " + model.jenkins[j].name + " (stuck)" : "");
    // Each sliding free dof's kinetic friction that held forces read (kinetic_lin), its size in kinetic_mag.
    std::vector<std::uint32_t> kinetic_slot(n, kNoRegister);
    std::vector<double> kinetic_mag(n, 0.0);
    // In a chain of frictions a stuck dof's held force reads the reactions of the frictions sliding on it too.
    for (std::size_t ii = 0; ii < n; ++ii) {
        const int i = static_cast<int>(ii);
        if (free_of[ii] < 0 && !model.friction_chain()) continue;
        if (const Lin l = kinetic_lin(model, mu_k_n, i, sgn, kinetic_mag[ii]);
            (!d.held.empty() || model.shared_partner()) && kinetic_mag[ii] != 0.0)
            kinetic_slot[ii] = slot_lin("F_k_", ii, l);
    }
    p.n_coef = static_cast<int>(p.coef_names.size());

    // ================= eval =================
    Builder e(p, p.eval, named);
    e.reg("1.0", RegisterKind::one);
    const std::uint32_t TAU = e.reg("tau", RegisterKind::input);
    for (int k = 0; k < p.n_coef; ++k) e.reg("coef[", static_cast<std::size_t>(k), RegisterKind::input, "]");
    auto C = [&](std::uint32_t slot) { return Program::kEvalCoef + slot; };
    const char* arrays[] = {"x", "v", "a", "g", "dg", "bound", "scale"};
    std::uint32_t base[7];
    for (int k = 0; k < 7; ++k) {
        base[k] = static_cast<std::uint32_t>(p.eval.registers());
        const std::size_t len = k == 0 ? n + nj : k < 3 ? n : d.switches.size();
        const std::string prefix = std::string(arrays[k]) + "[";
        for (std::size_t i = 0; i < len; ++i) e.reg(prefix.c_str(), i, RegisterKind::output, "]");
    }
    auto X = [&](int i) { return base[0] + static_cast<std::uint32_t>(i); };
    auto Vr = [&](int i) { return base[1] + static_cast<std::uint32_t>(i); };
    auto Ar = [&](int i) { return base[2] + static_cast<std::uint32_t>(i); };
    auto G = [&](std::size_t f, int k) { return base[k] + static_cast<std::uint32_t>(f); };

    std::vector<std::uint32_t> sin_h(nh), cos_h(nh);
    for (std::size_t h = 0; h < nh; ++h) {
        const std::uint32_t r0 = e.temp("arg_", h + 1);
        e.temp("sin_", h + 1);
        e.temp("cos_", h + 1);
        sin_h[h] = r0 + 1;
        cos_h[h] = r0 + 2;
        ProgramInstr in{ProgramOp::harmonic};
        in.dst = r0;
        in.a = C(theta_slot[h]);
        in.b = TAU;
        in.first = harm_k[h];
        if (h == 0) e.annotate(in, "Forcing harmonics: sin/cos(Omega_h tau + theta_h), once each.");
        e.emit(in);
    }
    std::vector<std::uint32_t> mb(nm);  // mode blocks
    for (std::size_t j = 0; j < nm; ++j) {
        const Mode& m = d.modes[j];
        const std::string J = idx(j);
        const char* names[kModeRegisters] = {"eC_", "eS_", "q_", "dq_", "ddq_", "r_", "mq_", "mdq_", "e_", "m_"};
        if (m.regime == Regime::rigid_damped) names[kModeAux] = "m_";
        mb[j] = static_cast<std::uint32_t>(p.eval.registers());
        for (const char* nm_ : names) e.temp(nm_, j + 1);
        bool resonant = false;
        for (std::size_t h = 0; h < nh; ++h) resonant |= d.harmonics[h].modal[j].resonant;
        ProgramInstr in{ProgramOp::mode};
        in.regime = static_cast<std::uint8_t>(m.regime);
        in.accumulates = resonant || m.regime == Regime::rigid || m.regime == Regime::rigid_damped;
        in.dst = mb[j];
        in.a = Program::kEvalCoef + mode_coef[j];
        in.b = TAU;
        in.first = mode_k[j];
        if (named) e.annotate(in, "Mode " + J + " (" + regime_name(m.regime) + ").");
        e.emit(in);
        if (m.regime == Regime::rigid) {
            ProgramInstr pi{ProgramOp::rigid_particular};
            pi.a = C(p_slot[j]);
            pi.b = TAU;
            pi.c = mb[j];
            e.annotate(pi, "particular q_p = p tau^2/2");
            e.emit(pi);
        } else if (m.regime == Regime::rigid_damped) {
            // One form for every c > 0, exact as c -> 0: the split (p/c) tau + (q'(0) - p/c) eS
            // lost eps |p/c| (6e-10 at alpha = 1e-6; tests/test_sweep_kernels.cpp, floating pair).
            ProgramInstr pi{ProgramOp::rigid_damped_particular};
            pi.dst = e.temp("qp_", j + 1);
            pi.a = C(p_slot[j]);
            pi.b = TAU;
            pi.c = mb[j];
            pi.first = mode_k[j] + kModeC;
            e.annotate(pi, "particular q_p = p tau^2 phi2(-c tau) from rest: q_p' = p eS, q_p'' = p e^{-c tau}");
            e.emit(pi);
        }
        for (std::size_t h = 0; h < nh; ++h) {
            const ModalHarmonic& mh = d.harmonics[h].modal[j];
            if (!mh.resonant) continue;
            const std::string JH = J + "_" + idx(h), H = idx(h);
            const DD W = d.harmonics[h].omega;
            const double Q = dbl(mh.P / (m.omega + W)), hw = dbl((W - m.omega) / 2), wb = dbl((W + m.omega) / 2);
            ProgramInstr ri{ProgramOp::resonant};
            ri.dst = static_cast<std::uint32_t>(p.eval.registers());
            for (const char* nm_ : {"w_", "dw_", "Cb_", "Sb_", "y_", "dy_", "ddy_"}) e.temp(nm_ + JH);
            ri.a = C(theta_slot[h]);
            ri.b = TAU;
            ri.c = mb[j];
            ri.d = C(c_theta_slot[h]);
            ri.first = static_cast<std::uint32_t>(p.constants.size());
            const double k[kResConstants] = {hw, hw == 0.0 ? 0.0 : 1.0 / hw, wb, Q, hw * hw + wb * wb, 2 * wb,
                                              dbl(m.lambda)};
            for (double c : k) constant(p, c);
            if (named)
                e.annotate(ri, "Resonant response to harmonic " + H +
                                   " from rest, stable through Omega = omega:\n"
                                   "y = Q [-w cos(wbar tau + theta) + cos(theta) sin(omega tau)/omega], Q = P/(omega + Omega),\n"
                                   "w = sin(h tau)/h -> tau (h = (Omega - omega)/2, wbar = (Omega + omega)/2): the secular term.");
            e.emit(ri);
        }
    }

    // x, v, a of every mass and the magnitudes of their terms.
    std::vector<std::uint32_t> mx(n), mv(n);
    for (std::size_t i = 0; i < n; ++i) {
        const int ii = static_cast<int>(i);
        const int r = free_of[i];
        const std::string comment =
            i == 0 ? "Physical state: x = x_st + V q + sum_h (xs_h sin + xc_h cos); stuck masses rest." : "";
        if (d.rides(ii)) continue;  // after its partner, below
        if (r < 0) {
            const std::uint32_t xs = C(x_stuck_slot[i]);
            e.annotate(e.unary(ProgramOp::copy, X(ii), xs), comment, named ? model.masses[i].name + " (stuck)" : "");
            e.lin(Vr(ii), Lin());
            e.lin(Ar(ii), Lin());
            mx[i] = e.temp("mx_", i);
            e.unary(ProgramOp::abs, mx[i], xs);
            mv[i] = e.temp("mv_", i);
            e.lin(mv[i], Lin());
            continue;
        }
        const std::size_t rr = static_cast<std::size_t>(r);
        Lin modal, tx, tv, ta, tmx, tmv;
        double hx = 0.0, hv = 0.0;  // magnitudes of the harmonic terms
        for (std::size_t j : row_modes[rr]) modal.add(vd[j][rr], mb[j]);
        for (std::size_t h = 0; h < nh; ++h) {
            const HarmonicData& hd = d.harmonics[h];
            const double W = dbl(hd.omega), xs = dbl(hd.xs[rr]), xc = dbl(hd.xc[rr]);
            tx.add(xs, sin_h[h]).add(xc, cos_h[h]);
            tv.add(W * xs, cos_h[h]).add(-W * xc, sin_h[h]);
            ta.add(-W * W * xs, sin_h[h]).add(-W * W * xc, cos_h[h]);
            hx += std::fabs(xs) + std::fabs(xc);
            hv += W * (std::fabs(xs) + std::fabs(xc));
        }
        tmx.add(hx, ONE);
        tmv.add(hv, ONE);
        mx[i] = e.temp("mx_", i);
        mv[i] = e.temp("mv_", i);
        ProgramInstr in{ProgramOp::mass_state};
        in.dst = X(ii);
        in.b = Vr(ii);
        in.c = Ar(ii);
        in.d = mx[i];
        in.a = C(x_st_slot[rr]);
        in.first = static_cast<std::uint32_t>(p.terms.size());
        in.count = static_cast<std::uint32_t>(modal.size());
        p.terms.insert(p.terms.end(), modal.begin(), modal.end());
        const Lin* tails[5] = {&tx, &tv, &ta, &tmx, &tmv};
        for (int k = 0; k < 5; ++k) {
            in.tail[k] = static_cast<std::uint32_t>(tails[k]->size());
            p.terms.insert(p.terms.end(), tails[k]->begin(), tails[k]->end());
        }
        e.annotate(e.emit(in), comment, model.masses[i].name);
    }

    // Riders: their partner's motion at their offset.
    for (int q : d.riders) {
        const int p = carrier_of(q);
        const std::uint32_t eq = C(e_slot.at(q));
        e.annotate(e.lin(X(q), Lin().add(1.0, X(p)).add(1.0, eq)), q == d.riders.front() ? "Riders: x = x_partner + e." : "",
             model.masses[static_cast<std::size_t>(q)].name + " (rides " + model.masses[static_cast<std::size_t>(p)].name + ")");
        e.unary(ProgramOp::copy, Vr(q), Vr(p));
        e.unary(ProgramOp::copy, Ar(q), Ar(p));
        const std::uint32_t ae = e.temp("me_" + std::to_string(q));
        e.unary(ProgramOp::abs, ae, eq);
        mx[static_cast<std::size_t>(q)] = e.temp("mx_" + std::to_string(q));
        e.lin(mx[static_cast<std::size_t>(q)], Lin().add(1.0, mx[static_cast<std::size_t>(p)]).add(1.0, ae));
        mv[static_cast<std::size_t>(q)] = e.temp("mv_" + std::to_string(q));
        e.unary(ProgramOp::copy, mv[static_cast<std::size_t>(q)], mv[static_cast<std::size_t>(p)]);
    }

    // Jenkins sliders: fixed while stuck; while slipping the stretch is held,
    // s = x[a] - x[b] - slip F_s/k. Their magnitudes for the switch functions' scale.
    std::vector<std::uint32_t> mxs(nj);
    const LinMotion state(X, Vr, Ar, mx, mv, {});  // the element files' motion (model/elements/)
    for (std::size_t j = 0; j < nj; ++j) {
        const Jenkins& el = model.jenkins[j];
        const std::uint32_t out = X(static_cast<int>(n + j));
        mxs[j] = e.temp("ms_" + std::to_string(j));
        const std::string comment = j == 0 ? "Jenkins sliders: fixed while stuck, s = x[a] - x[b] - slip F_s/k while slipping." : "";
        if (d.cfg.slip[j] == 0) {
            const std::uint32_t sc = C(s_stuck_slot[j]);
            e.annotate(e.unary(ProgramOp::copy, out, sc), comment, el.name + " (stuck)");
            e.unary(ProgramOp::abs, mxs[j], sc);
            continue;
        }
        const LinValue held = LinValue::constant(jenkins::held_stretch(d.cfg.slip[j], el.k, el.slip_force));
        const LinValue sl = along(el.direction(), state, 0) - held;
        const LinValue ml = along_magnitude(el.direction(), state, 0) + state.abs(held);
        e.annotate(e.lin(out, sl.lin()), comment, el.name + (d.cfg.slip[j] > 0 ? " (slipping, +)" : " (slipping, -)"));
        e.lin(mxs[j], ml.lin());
    }
    std::map<std::uint32_t, std::uint32_t> slider_magnitude;  // |s_j| is the register mxs[j]
    for (std::size_t j = 0; j < nj; ++j) slider_magnitude[X(static_cast<int>(n + j))] = mxs[j];
    const LinMotion motion(X, Vr, Ar, mx, mv, slider_magnitude);
    const auto elements = model_elements<LinValue>(model, LinValue::constant,
                                                   [&](int j) { return LinValue(1.0, X(static_cast<int>(n) + j)); });

    // Switch functions.
    auto V = [&](int mass, std::size_t j) -> DD {  // V_ij, 0 for stuck masses and ground
        if (mass == kGround) return 0;
        const int r = coord_of[mass];
        return r < 0 ? DD(0) : d.modes[j].v[r];
    };
    // The nonzero entries of each row of K(cfg) and C(cfg), ascending: a force reads these alone.
    std::vector<std::vector<std::size_t>> row_nz(n);
    for (std::size_t b = 0; b < n; ++b)
        for (std::size_t k = 0; k < n; ++k)
            if (!entry(d.k_dd, static_cast<int>(b), static_cast<int>(k)).is_zero() ||
                !entry(d.c_dd, static_cast<int>(b), static_cast<int>(k)).is_zero())
                row_nz[b].push_back(k);
    // fn(j) for each mode j that moves one of `bodies` (a mode twice when it moves two):
    // the others have V = 0 on all of them.
    auto each_mode_of = [&](std::initializer_list<int> bodies, auto&& fn) {
        for (int b : bodies) {
            if (b == kGround || coord_of[b] < 0) continue;
            for (std::size_t j : row_modes[static_cast<std::size_t>(coord_of[b])]) fn(j);
        }
    };
    // The non-resonant particular part of body b's x at harmonic h: xs (sine) or xc (cosine).
    auto harmonic_x = [&](std::size_t h, int b, bool sine) -> DD {
        if (b == kGround || coord_of[b] < 0) return 0;
        return sine ? d.harmonics[h].xs[coord_of[b]] : d.harmonics[h].xc[coord_of[b]];
    };
    // A_b = -K x - C v + f + slider preload + sum_h F_h sin, the force on mass b from
    // everything but friction, as terms of A, A' and of their magnitudes (const_mag
    // gathers the constant ones), and as a combination of the state: alpha (on q) and
    // beta (on q') per mode, Gs sin + Gc cos per harmonic (the bound's inputs).
    auto force_terms = [&](int b, Lin& A, Lin& dA, Lin& mag, double& const_mag, std::vector<DD>& al,
                           std::vector<DD>& be, std::vector<DD>& Gs, std::vector<DD>& Gc) {
        A.add(f_const[b], ONE);
        for (std::size_t k : row_nz[static_cast<std::size_t>(b)]) {  // the other entries are exact zeros, left out
            const int kk = static_cast<int>(k);
            const double Kbk = dbl(entry(d.k_dd, b, kk)), Cbk = dbl(entry(d.c_dd, b, kk));
            A.add(-Kbk, X(kk));
            dA.add(-Kbk, Vr(kk));
            mag.add(std::fabs(Kbk), mx[k]);
            if (!d.cfg.stuck[k] || d.rides(kk)) {  // a rider moves with its partner
                A.add(-Cbk, Vr(kk));
                dA.add(-Cbk, Ar(kk));
                mag.add(std::fabs(Cbk), mv[k]);
            }
        }
        for_each_slider_preload(model, d.cfg, b, [&](double k, std::size_t j) {
            A.add(k, X(static_cast<int>(n + j)));
            mag.add(std::fabs(k), mxs[j]);
        });
        for (std::size_t h = 0; h < nh; ++h) {
            const double F0 = dbl(d.harmonics[h].amplitude[b]), W = dbl(d.harmonics[h].omega);
            A.add(F0, sin_h[h]);
            dA.add(F0 * W, cos_h[h]);
            const_mag += std::fabs(F0);
        }
        // Only the nonzero entries of row b of K and C: an exact-zero entry times
        // a float is the exact 0 (CLN), whose subtraction changes nothing.
        auto moving = [&](int k, std::size_t r) {
            const DD Kbk = entry(d.k_dd, b, k), Cbk = entry(d.c_dd, b, k);
            const bool kz = Kbk.is_zero(), cz = Cbk.is_zero();
            if (kz && cz) return;
            for (std::size_t j : row_modes[r]) {  // elsewhere v_r = 0: the exact 0 changes nothing
                if (!kz) al[j] -= Kbk * d.modes[j].v[r];
                if (!cz) be[j] -= Cbk * d.modes[j].v[r];
            }
        };
        for (std::size_t k : row_nz[static_cast<std::size_t>(b)])  // the free masses, in the order of their coordinates
            if (free_of[k] >= 0) moving(static_cast<int>(k), static_cast<std::size_t>(free_of[k]));
        for (int q : d.riders) moving(q, static_cast<std::size_t>(coord_of[q]));
        for (std::size_t h = 0; h < nh; ++h) {
            const HarmonicData& hd = d.harmonics[h];
            Gs[h] = hd.amplitude[b];
            auto harmonic = [&](int k, std::size_t r) {
                const DD Kbk = entry(d.k_dd, b, k), Cbk = entry(d.c_dd, b, k);
                if (Kbk.is_zero() && Cbk.is_zero()) return;  // adds the exact 0
                Gs[h] += -Kbk * hd.xs[r] + Cbk * hd.omega * hd.xc[r];
                Gc[h] += -Kbk * hd.xc[r] - Cbk * hd.omega * hd.xs[r];
            };
            for (std::size_t k : row_nz[static_cast<std::size_t>(b)])
                if (free_of[k] >= 0) harmonic(static_cast<int>(k), static_cast<std::size_t>(free_of[k]));
            for (int q : d.riders) harmonic(q, static_cast<std::size_t>(coord_of[q]));
        }
    };
    std::map<int, std::uint32_t> pair_reg;  // mass -> its A_pair register (then A', the magnitude)
    std::uint32_t s_end = kNoRegister;
    std::vector<std::uint32_t> abs_p(nm, kNoRegister);
    std::map<int, std::uint32_t> force_reg;  // mass -> its A_force register in eval
    std::vector<DD> bound_alpha(nm), bound_beta(nm);  // per mode: c + omega, c (c + omega) + lambda
    for (std::size_t j = 0; j < nm; ++j) {
        const Mode& m = d.modes[j];
        bound_alpha[j] = m.c + m.omega;
        bound_beta[j] = m.c * (m.c + m.omega) + m.lambda;
    }
    for (std::size_t f = 0; f < d.switches.size(); ++f) {
        const SwitchFunction& sf = d.switches[f];
        const std::string F = std::to_string(f);
        std::string comment = f == 0 && named ? "Switch functions (runtime/segment.h order), derivatives, bounds on |g''| and "
                                       "term magnitudes.\n"
                                       "bound = sum_j (|alpha_j| (c_j + omega_j) + |beta_j| (c_j (c_j + omega_j) + "
                                       "lambda_j)) sqrt(2 E_j)\n"
                                       "      + sum_h R_h Omega_h^2 (+ rigid-body and secular terms), for g = "
                                       "alpha.q + beta.q' + ...\n"
                                     : "";
        // g as a combination of the state: alpha (on q) and beta (on q') per mode, and the
        // harmonic sinusoid Gs sin + Gc cos of the non-resonant particular parts.
        std::vector<DD> al(nm, 0), be(nm, 0);
        std::vector<DD> Gs(nh, 0), Gc(nh, 0);
        Lin g, dg, sc;
        if (!is_release(sf.kind)) {  // the element's own file says what g is (model/elements/)
            g = switch_derivative(elements, sf, motion, 0).lin();
            dg = switch_derivative(elements, sf, motion, 1).lin();
            sc = switch_magnitude(elements, sf, motion, 0).lin();
        }
        if (sf.kind == SwitchKind::gap) {
            const Contact& ct = model.contacts[sf.element];
            if (named) comment += "g_" + F + ": gap of contact " + ct.name + " = " + gap_text(model, ct);
            along_rows(ct.direction(), V, harmonic_x, each_mode_of, al, Gs, Gc);
        } else if (sf.kind == SwitchKind::velocity && partner_of(sf.element) == kGround) {
            const int i = sf.element;
            if (named) comment += "g_" + F + ": velocity of " + model.masses[i].name + " (sliding)";
            const int r = free_of[i];
            for (std::size_t j : row_modes[static_cast<std::size_t>(r)]) be[j] = d.modes[j].v[r];
            for (std::size_t h = 0; h < nh; ++h) {
                Gs[h] = -d.harmonics[h].omega * d.harmonics[h].xc[r];
                Gc[h] = d.harmonics[h].omega * d.harmonics[h].xs[r];
            }
        } else if (sf.kind == SwitchKind::velocity) {
            // Sliding on its partner: w = v_i - v_p.
            const int i = sf.element, p = partner_of(i);
            if (named) comment += "g_" + F + ": velocity of " + model.masses[i].name + " on " + model.masses[p].name + " (sliding)";
            each_mode_of({i, p}, [&](std::size_t j) { be[j] = V(i, j) - V(p, j); });
            for (std::size_t h = 0; h < nh; ++h) {
                const DD W = d.harmonics[h].omega;
                Gs[h] = -W * (harmonic_x(h, i, false) - harmonic_x(h, p, false));
                Gc[h] = W * (harmonic_x(h, i, true) - harmonic_x(h, p, true));
            }
        } else if (is_slip(sf.kind)) {
            if (named) comment += "g_" + F + ": " + jenkins_comment(model, sf);
            jenkins_rows(model, d, sf, V, harmonic_x, each_mode_of, al, be, Gs, Gc);
        } else {
            const int i = sf.element;
            const bool pos = sf.kind == SwitchKind::release_pos;
            const Mass& ms = model.masses[i];
            const double mu_s_n = d.mu_s_n[static_cast<std::size_t>(i)];
            const int sigma = pos ? 1 : -1;
            const LinValue limit = LinValue::constant(mu_s_n);
            if (partner_of(i) == kGround && d.held.empty() && !model.friction_chain()) {  // lumped: D_i = A_i
                if (named) comment += std::string("g_") + F + ": " + (pos ? "A" : "-A") + " - mu_s N of stuck " + ms.name +
                           ", A = -K x - C v + f + sum_h F_h sin (force but friction)";
                Lin A, dA;
                double const_mag = std::fabs(f_const[i]) + mu_s_n;
                force_terms(i, A, dA, sc, const_mag, al, be, Gs, Gc);
                sc.add(const_mag, ONE);
                // release_pos comes first and computes A_i; release_neg reuses it.
                std::uint32_t af = kNoRegister, daf = kNoRegister;
                if (const auto it = force_reg.find(i); it != force_reg.end()) af = it->second, daf = af + 1;
                if (af == kNoRegister) {
                    af = e.temp("A_force_", static_cast<std::size_t>(i));
                    daf = e.temp("dA_force_", static_cast<std::size_t>(i));
                    force_reg[i] = af;
                    e.annotate(e.lin(af, A), comment);
                    comment.clear();
                    e.lin(daf, dA);
                }
                g = friction::release_value(sigma, LinValue(1.0, af), limit, 0).lin();
                dg = friction::release_value(sigma, LinValue(1.0, daf), limit, 1).lin();
            } else {
                // The force that holds i, D = sum_k c_k A_k over bodies k (partner_terms, held_terms).
                const bool pair = partner_of(i) != kGround || model.friction_chain();
                if (named) comment += held_comment(model, i, pos, F, !pair);
                const std::vector<std::pair<int, DD>> terms = pair ? partner_terms(model, d, i) : held_terms(d, i);
                const std::string prefix = pair ? "A_pair_" : "A_held_";
                const std::size_t nt = terms.size();
                std::vector<std::array<std::uint32_t, 3>> reg(nt);  // A, A', the magnitude of A's terms, per body
                std::vector<std::vector<DD>> al_b(nt), be_b(nt), Gs_b(nt), Gc_b(nt);
                for (std::size_t k = 0; k < nt; ++k) {
                    const int b = terms[k].first;
                    Lin A, dA, mag;
                    double const_mag = std::fabs(f_const[b]);
                    al_b[k].assign(nm, 0), be_b[k].assign(nm, 0);
                    Gs_b[k].assign(nh, 0), Gc_b[k].assign(nh, 0);
                    force_terms(b, A, dA, mag, const_mag, al_b[k], be_b[k], Gs_b[k], Gc_b[k]);
                    if (kinetic_slot[static_cast<std::size_t>(b)] != kNoRegister) {  // a sliding free dof's friction
                        A.add(1.0, C(kinetic_slot[static_cast<std::size_t>(b)]));
                        const_mag += kinetic_mag[static_cast<std::size_t>(b)];
                    }
                    mag.add(const_mag, ONE);
                    if (const auto it = pair_reg.find(b); it != pair_reg.end()) {
                        for (std::uint32_t q = 0; q < 3; ++q) reg[k][q] = it->second + q;
                        continue;
                    }
                    const std::string B = std::to_string(b);
                    reg[k][0] = e.temp(prefix + B);
                    reg[k][1] = e.temp("d" + prefix + B);
                    reg[k][2] = e.temp("m" + prefix + B);
                    pair_reg[b] = reg[k][0];
                    e.annotate(e.lin(reg[k][0], A), comment);
                    comment.clear();
                    e.lin(reg[k][1], dA);
                    e.lin(reg[k][2], mag);
                }
                LinValue D(dbl(terms[0].second), reg[0][0]), dD(dbl(terms[0].second), reg[0][1]);
                for (std::size_t k = 1; k < nt; ++k) {
                    D = D + LinValue(dbl(terms[k].second), reg[k][0]);
                    dD = dD + LinValue(dbl(terms[k].second), reg[k][1]);
                }
                g = friction::release_value(sigma, D, limit, 0).lin();
                dg = friction::release_value(sigma, dD, limit, 1).lin();
                for (std::size_t k = 0; k < nt; ++k) sc.add(std::fabs(dbl(terms[k].second)), reg[k][2]);
                sc.add(mu_s_n, ONE);
                combine(terms, al_b, al), combine(terms, be_b, be), combine(terms, Gs_b, Gs), combine(terms, Gc_b, Gc);
            }
        }
        e.annotate(e.lin(G(f, 3), g), comment);
        e.lin(G(f, 4), dg);
        // bound
        DD konst = 0;
        for (std::size_t h = 0; h < nh; ++h) {
            const DD W = d.harmonics[h].omega;
            konst += sqrt(Gs[h] * Gs[h] + Gc[h] * Gc[h]) * W * W;
        }
        Lin b;
        b.add(konst, ONE);
        for (std::size_t j = 0; j < nm; ++j) {
            const Mode& m = d.modes[j];
            // H = |alpha| (c + omega) + |beta| (c (c + omega) + lambda); a zero term (exact 0
            // times a factor) adds nothing, so it is left out: the same number.
            const bool za = al[j].is_zero(), zb = be[j].is_zero();
            const DD H = za && zb ? DD(0)
                              : za     ? abs(be[j]) * bound_beta[j]
                              : zb     ? abs(al[j]) * bound_alpha[j]
                                       : abs(al[j]) * bound_alpha[j] + abs(be[j]) * bound_beta[j];
            b.add(H, mb[j] + kModeR);
            if (m.regime == Regime::rigid || m.regime == Regime::rigid_damped) {  // |q_p''| <= |p|, |q_p'''| <= c |p|
                const double cp = dbl(abs(al[j]) + abs(be[j]) * m.c);
                if (cp != 0.0 && abs_p[j] == kNoRegister) {
                    abs_p[j] = e.temp("p_abs_", j + 1);
                    e.unary(ProgramOp::abs, abs_p[j], C(p_slot[j]));
                }
                b.add(cp, abs_p[j]);
            }
            for (std::size_t h = 0; h < nh; ++h) {
                const ModalHarmonic& mh = d.harmonics[h].modal[j];
                if (!mh.resonant || (al[j].is_zero() && be[j].is_zero())) continue;
                if (s_end == kNoRegister) {
                    // Secular terms are bounded at the end of the step: computed first in eval.
                    s_end = e.temp("s_end");
                    ProgramInstr se{ProgramOp::lincomb};
                    se.dst = s_end;
                    se.first = static_cast<std::uint32_t>(p.terms.size());
                    se.count = 2;
                    p.terms.push_back({1.0, TAU});
                    p.terms.push_back({d.max_step, ONE});
                    e.annotate(se, "Secular terms are bounded at the end of the step, s_end = tau + max_step.");
                    p.eval.code.insert(p.eval.code.begin(), se);
                }
                const DD W = d.harmonics[h].omega, Q = abs(mh.P / (m.omega + W));
                const DD hw = abs(W - m.omega) / 2, wb = (W + m.omega) / 2;
                // |y''| <= Q ((h^2 + wbar^2) s + 2 wbar + omega), |y'''| <= Q (wbar^3 s + 3 wbar^2 + 3 h wbar + h^2 + omega^2)
                const DD slope = abs(al[j]) * Q * (hw * hw + wb * wb) + abs(be[j]) * Q * wb * wb * wb;
                const DD off = abs(al[j]) * Q * (2 * wb + m.omega) +
                                    abs(be[j]) * Q * (3 * wb * wb + 3 * hw * wb + hw * hw + m.lambda);
                b.add(slope, s_end).add(off, ONE);
            }
        }
        e.lin(G(f, 5), b);
        e.lin(G(f, 6), sc);
    }
    p.mode_coef = std::move(mode_coef), p.x_st_coef = std::move(x_st_slot);
    p.theta_coef = std::move(theta_slot), p.c_theta_coef = std::move(c_theta_slot);
    p.restart = restart_plan(d, p);
    return p;
}

RestartPlan restart_plan(const Derivation& d, const Program& p) {
    const Model& model = *d.model;
    RestartPlan plan;
    const std::size_t nf = d.n_free(), nm = d.modes.size();
    // A coupled M's held forces read the free dofs' kinetic friction from slots
    // (F_k_) that a reversal changes and the plan does not: such a configuration sets up.
    if (d.state_space || !d.riders.empty() || !model.jenkins.empty() || !d.held.empty() || nf == 0 || nm == 0)
        return plan;
    for (const FrictionSlot& f : model.friction_slots)
        if (f.partner != kGround) return plan;
    for (const Mode& m : d.modes)
        if (m.regime == Regime::rigid || m.regime == Regime::rigid_damped) return plan;
    for (const HarmonicData& h : d.harmonics)
        for (const ModalHarmonic& mh : h.modal)
            if (mh.resonant) return plan;
    for (std::size_t j = 0; j < nm; ++j) {
        const Mode& m = d.modes[j];
        RestartPlan::Mode rm;
        rm.coef = p.mode_coef[j];
        rm.regime = static_cast<ProgramRegime>(m.regime);
        rm.sigma = dbl(m.sigma), rm.kappa = dbl(m.kappa), rm.omega_d = dbl(m.omega_d), rm.lambda = dbl(m.lambda);
        rm.r1 = dbl(m.r1), rm.gamma = dbl(m.gamma);
        plan.modes.push_back(rm);
    }
    plan.vt.resize(nf * nm);
    for (std::size_t r = 0; r < nf; ++r) {
        const int i = d.free_dofs[r];
        plan.free_mass.push_back(i);
        plan.mu_k_n.push_back(d.mu_k_n_double[static_cast<std::size_t>(i)]);
        plan.x_st.push_back(p.x_st_coef[r]);
    }
    plan.span.assign(2 * nm, 0);
    for (std::size_t j = 0; j < nm; ++j) {
        std::uint32_t lo = static_cast<std::uint32_t>(nf), hi = 0;
        for (std::size_t r = 0; r < nf; ++r) {
            const double v = dbl(d.modes[j].v[r]);
            plan.vt[j * nf + r] = v;
            if (v != 0.0) lo = std::min(lo, static_cast<std::uint32_t>(r)), hi = static_cast<std::uint32_t>(r + 1);
        }
        plan.span[2 * j] = std::min(lo, hi), plan.span[2 * j + 1] = hi;
    }
    for (std::size_t h = 0; h < d.harmonics.size(); ++h)
        plan.harmonics.push_back({p.theta_coef[h], p.c_theta_coef[h], dbl(d.harmonics[h].omega),
                                  dbl(d.harmonics[h].phase)});
    return plan;
}

std::function<Program(const Configuration&)> program_source(const Model& model) {
    // The blocks of the modal analysis recur from one configuration to the next,
    // and the friction forces are the model's: both computed once per run (the
    // cache is used under the GiNaC lock, by one thread at a time).
    auto cache = std::make_shared<DerivationCache>();
    return [&model, cache](const Configuration& cfg) {
        const auto lock = ginac_lock();  // the derivation is GiNaC (ginac_lock.h)
        return lower(derive(model, cfg, EigenMethod::refined, ExactMatrices::no, cache.get()), ProgramNames::no);
    };
}

std::function<std::shared_ptr<const RestartPlan>(const Configuration&)> restart_plan_source(const Model& model) {
    const std::function<Program(const Configuration&)> programs = program_source(model);
    return [programs](const Configuration& cfg) {
        return std::make_shared<const RestartPlan>(programs(cfg).restart);
    };
}

}  // namespace hsnc
