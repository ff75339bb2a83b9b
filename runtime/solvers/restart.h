// hsnc -- restarting a segment at a reversal from its coefficient block.
//
// A reversal (a sliding mass's velocity changes sign) keeps the configuration:
// the modes are the same and only the kinetic friction force of the reversing
// masses changes, so only the modal forces do. Instead of projecting the state
// at the event back onto the modes (setup: eight sums over the modes per
// mode, a refinement included), the coefficient block setup wrote can be
// carried over: each mode's homogeneous state at the event, q_h(tau) and
// q_h'(tau), less the change of its static deflection, Delta p_j / lambda_j
// with Delta p = V^T Delta f (Delta f nonzero only at the reversing masses),
// and the static offset x_st moved by V (Delta p / lambda). The state at the
// event is the same (to rounding), x = x_st + V q_h + the forcing's particular
// part, which depends on the absolute time alone.
//
// It reads and writes only the coefficient block, whose layout every kind of
// solver shares bit for bit (kernels/program.h), so every kind restarted this
// way would keep giving the same bits. Not wired into the engine yet: the
// engine calls setup at every segment (issue 13's note says what remains).
#pragma once

#include "program.h"

namespace hsnc {

/// Rewrites `coef` (a segment started at absolute time t_start, evaluated up
/// to the reversal at tau) for the segment that starts at t0 + t0_lo = the
/// reversal, with the friction directions sgn_new instead of sgn_old. `plan`
/// must not be empty.
void restart_coefficients(const RestartPlan& plan, double* coef, double tau, double t0, double t0_lo,
                          const signed char* sgn_old, const signed char* sgn_new);

}  // namespace hsnc
