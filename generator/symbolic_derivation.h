// hsnc -- SymbolicDerivation: the segment formulas of one configuration with
// the model's parameters kept as symbols (`hsnc inspect --symbolic`).
//
// The model's source texts (Model::parameter_expressions, field_expressions)
// are parsed back with GiNaC, every parameter a symbol. For free masses F and
// stuck masses S (paper Eq. 7-9):
//     M_FF x'' + C_FF x' + K_FF x = f + sum_h F_h sin(Omega_h t + phi_h),
//     f = loads + preload - K_FS x0_S - mu_k m g sgn,   C = alpha M + beta K(cfg).
// The eigenvalues of det(K - lambda M) = 0 are closed-form for at most
// kMaxSymbolicDof free masses (M is diagonal):
//     1 DOF:  lambda = k/m;
//     2 DOF:  lambda_{1,2} = (k11 m2 + k22 m1 -+ sqrt((k11 m2 - k22 m1)^2 + 4 m1 m2 k12^2)) / (2 m1 m2),
//             mode shapes V_j = (-k12, k11 - lambda_j m1) (the unit vectors when k12 = 0).
// With x = x_st + V q (x_st = K^-1 f) the modes decouple (V^T M V = diag(mu_j)):
//     q_j'' + c_j q_j' + lambda_j q_j = sum_h P_jh sin(Omega_h t + phi_h),  c_j = alpha + beta lambda_j,
//     P_jh = V_j^T F_h / mu_j,
// solved in the underdamped/undamped form (0 <= c_j < 2 omega_j, no resonance):
//     q_j = e^{-c_j (t-t0)/2} (A_j cos(omega_d_j (t-t0)) + B_j sin(omega_d_j (t-t0))) + q_p_j(t),
//     q_p_j = sum_h P_jh ((lambda_j - Omega_h^2) sin th_h - c_j Omega_h cos th_h) / ((lambda_j - Omega_h^2)^2 + c_j^2 Omega_h^2),
//     A_j = q_j(t0) - q_p_j(t0),  B_j = (q_j'(t0) - q_p_j'(t0) + c_j A_j / 2) / omega_d_j.
// Which regime holds depends on the parameter values: the printout says so.
#pragma once

#include <ginac/ginac.h>

#include <string>
#include <utility>
#include <vector>

#include "configuration.h"
#include "model.h"

namespace hsnc {

/// Most free masses for which the derivation is symbolic (closed-form eigenvalues).
inline constexpr std::size_t kMaxSymbolicDof = 2;

/// A named quantity and its definition (over parameters, initial state, t and
/// earlier quantities).
struct Definition {
    GiNaC::symbol name;
    GiNaC::ex value;
};

struct SymbolicDerivation {
    std::vector<int> free_dofs, stuck_dofs;
    GiNaC::symbol t, t0;
    std::vector<GiNaC::symbol> x0, v0, sgn;  ///< all masses (sgn used by sliding friction masses)
    GiNaC::matrix M, K, C;                   ///< reduced to the free masses
    std::vector<GiNaC::ex> f;                ///< constant force on the free masses
    struct Harmonic {
        GiNaC::ex omega, phase;
        std::vector<GiNaC::ex> amplitude;  ///< free masses
    };
    std::vector<Harmonic> harmonics;
    std::vector<GiNaC::ex> lambda, omega, c, xi;  ///< per mode, ascending lambda when coupled
    std::vector<std::vector<GiNaC::ex>> shapes;   ///< V_j over the free masses
    std::vector<GiNaC::ex> x_static;              ///< K^-1 f over the free masses
    /// x_st, modal mass, initial modal state, A_j, B_j, ... in the order to print.
    std::vector<Definition> definitions;
    std::vector<GiNaC::ex> q;     ///< q_j(t) over the definitions' names
    std::vector<GiNaC::ex> x;     ///< x_i(t), all masses, over the definitions' names
    /// Switch functions in model/switch_function.h order: (description, g) with
    /// x_<mass>, v_<mass> standing for x_i(t), v_i(t).
    std::vector<std::pair<std::string, GiNaC::ex>> switches;
};

/// Derive configuration `cfg` of `model` symbolically. Returns false and says
/// why in `why` when it cannot: more than kMaxSymbolicDof free masses, no
/// source expressions (a model built in code), no free mass, or a singular
/// K of the free masses (a rigid-body mode: no static offset).
bool derive_symbolic(const Model& model, const Configuration& cfg, SymbolicDerivation& out, std::string& why);

}  // namespace hsnc
