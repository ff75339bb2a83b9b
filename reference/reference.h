// hsnc -- the high-precision reference engine (CLN): the HSNC method with every
// quantity at N decimal digits, independent of the double engine's arithmetic.
//
// It solves exactly the problem the double engine sees: the Model's double
// values (parameters, initial state, t0, t_end, sample times) are converted
// EXACTLY to CLN floats, and from there on everything -- the modal
// decomposition (cyclic Jacobi; with dampers the matrix exponential of the
// state matrix), the closed forms of every regime, the forcing
// particular solutions, the switch search and the transitions -- is evaluated
// at N digits (reference/mp_segment.h, reference/reference.cpp). Its own
// accuracy is checked by agreement between N and 2N digits
// (tests/test_reference.cpp, bench/reference_check.sh).
//
// This header is CLN-free; reference/reference_engine.h gives the results at
// full precision.
#pragma once

#include "engine_options.h"
#include "model.h"
#include "observer.h"
#include "run_summary.h"

namespace hsnc::reference {

/// Smallest and largest `digits` accepted by simulate().
inline constexpr int kMinDigits = 20;
inline constexpr int kMaxDigits = 100;

/// Bits of mantissa the reference carries for `digits` (CLN rounds up to whole 64-bit words: 50 -> 192).
int carried_bits(int digits);

/// Runs `model` from its initial state with every quantity at `digits` decimal digits (CLN), reporting samples and
/// events to `observer` rounded to double; returns the summary (x, v rounded to double).
/// Throws InputError when digits is outside [kMinDigits, kMaxDigits] (the CLI's range), RunError when the modal
/// analysis fails. RunStatus as for Engine::run.
RunSummary simulate(const Model& model, int digits, const EngineOptions& options, Observer& observer);

}  // namespace hsnc::reference
