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
// and the static offset x_st moved by V (Delta p / lambda), one n x n sum
// (setup has four). The state at the event is the same (to rounding), x = x_st + V q_h + the forcing's particular part,
// which depends on the absolute time alone. Any other event that keeps the
// configuration (a stop that slides on, a touch) changes no force and
// carries the state as it is.
//
// It reads and writes only the coefficient block, whose layout every kind of
// solver shares bit for bit (kernels/program.h), and takes each mode's e^x,
// sin and cos from kernel_abi.h's four-lane helpers, whose bits do not
// depend on the grouping: every kind restarted this way gives the same bits.
// The engine restarts a segment so when the event kept the configuration,
// the configuration has at least kRestartFrom modes and a plan is known
// (the interpreter's program carries one; for compiled kernels the engine
// asks EngineOptions::restart_plans); otherwise it sets up.
#pragma once

#include "program.h"

namespace hsnc {

/// Configurations with at least this many modes are restarted at events that
/// keep them (engine.cpp); smaller ones are set up from the state. A setup
/// costs about four n x n sums, a restart one, O(n) per changed friction
/// force and each mode's factors: in the all-open configuration of the
/// chains of bench_common.h 0.24 against 0.46 us at 16 masses, 0.52 against
/// 1.42 us at 32, 3.6 against 16.3 us at 128 (bench/program_bench.cpp,
/// section 5). Below
/// this the saving is small, and a compiled setup (the bundled models'
/// ahead-of-time kernels, 8 masses at most) would pay for a derivation to
/// learn the plan: seed scenario 2 ran 1.06x when every size restarted.
inline constexpr std::size_t kRestartFrom = 16;

/// Rewrites `coef` (a segment's block, whose segment reached the event at
/// tau) for the segment that starts at the event, t0 + t0_lo, with the
/// friction directions sgn_new instead of sgn_old. `plan` must not be empty.
void restart_coefficients(const RestartPlan& plan, double* coef, double tau, double t0, double t0_lo,
                          const signed char* sgn_old, const signed char* sgn_new);

}  // namespace hsnc
