// hsnc -- lowering: a configuration's Derivation (double-double) to the Program
// (kernels/program.h) that both the emitter prints and the interpreter runs.
//
// Every constant is rounded once from the derivation's double-double value; every
// sum is written in the order in which it is computed. The maths of each
// block is in the comments of lowering.cpp and, printed, in each kernel.
#pragma once

#include <functional>
#include <memory>

#include "derivation.h"
#include "program.h"

namespace hsnc {

/// Whether a program carries what only its printer reads: the names of its
/// registers and coefficient slots, and the comments and notes of its
/// instructions. The interpreter reads none of them; building them was about
/// half of lowering a configuration of a 32-mass chain.
enum class ProgramNames { yes, no };

/// The setup and eval programs of `d`; the same numbers and the same
/// instructions with or without names.
Program lower(const Derivation& d, ProgramNames names = ProgramNames::yes);

/// What restarting one of `d`'s segments at a reversal needs (kernels/program.h
/// RestartPlan), with the coefficient indices of `p` = lower(d); empty when
/// `d` has dampers' pseudo-modes, riders, Jenkins elements, friction pairs,
/// rigid modes or a resonant harmonic.
RestartPlan restart_plan(const Derivation& d, const Program& p);

/// The program of each configuration of `model`, lower(derive(model, cfg)):
/// the source of the generic path (InterpretedSolverProvider). `model` must
/// outlive the function.
std::function<Program(const Configuration&)> program_source(const Model& model);
std::function<Program(const Configuration&)> program_source(const Model&& model) = delete;  ///< would dangle

/// The restart plan of each configuration of `model`, as program_source's
/// programs carry it (Program::restart): EngineOptions::restart_plans for
/// solvers that keep none (compiled kernels). `model` must outlive the function.
std::function<std::shared_ptr<const RestartPlan>(const Configuration&)> restart_plan_source(const Model& model);
std::function<std::shared_ptr<const RestartPlan>(const Configuration&)> restart_plan_source(const Model&& model) = delete;

}  // namespace hsnc
