// hsnc -- the tangent dynamics of a model with stick elements (Jenkins
// elements, friction between two bodies; assembly.h stick_elements), on the
// full state z = (x, v, s): the masses' positions and velocities, then every
// Jenkins slider (2n + nj numbers).
//
// Between two switches dz/dt = A(cfg) z + (constants), so a perturbation
// moves by exp(A tau) (Eigen's scaling and squaring: to rounding, no
// integration) after the projection P(cfg) onto the states the configuration
// allows:
//   a mass stuck against the ground   dv = 0 (it stops again at once; tangent.h)
//   a body and what rides on it (its  dv of each = their momentum-weighted mean
//     stuck riders, up every chain)     (friction is internal: the body's momentum stays)
//   a slipping Jenkins element        ds = dx_a - dx_b (its stretch is held)
// A: x' = v; v' = M^-1 (-K x - C v + k s on a stuck element's ends) per body,
// a body's rows its members' (summed forces over summed mass); s' = 0 while
// stuck, v_a - v_b while slipping. A release function's gradient is that of
// D_i: the pair's closed form, or P_i . f (model/held_mass.h) where several
// frictions meet on a body (Model::coupled_friction()).
// At a switch the saltation matrix S = I + (f+ - f-) h_z^T / (h_z f- + h_t)
// uses the full vector fields f-+ before and after (field()) and the switch
// function's gradient (gradient()).
#pragma once

#include <Eigen/Core>

#include "configuration.h"
#include "model.h"
#include "switch_function.h"

namespace hsnc::analysis {

/// A(cfg) and P(cfg) of the full state.
Eigen::MatrixXd stick_generator(const Model& model, const Configuration& cfg);
Eigen::MatrixXd stick_projection(const Model& model, const Configuration& cfg);

/// dz/dt at (t, x, v) in cfg with the sliding directions sgn; x holds the
/// sliders after the masses.
Eigen::VectorXd stick_field(const Model& model, const Configuration& cfg, const signed char* sgn, double t,
                            const double* x, const double* v);

/// The gradient h_z of switch function f of cfg and its explicit time
/// derivative h_t (the forcing in a release function) at time t.
void stick_gradient(const Model& model, const Configuration& cfg, const SwitchFunction& f, double t,
                    Eigen::RowVectorXd& hz, double& ht);

}  // namespace hsnc::analysis
