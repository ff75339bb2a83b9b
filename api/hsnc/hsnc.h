// hsnc -- everything a program needs to read a model and simulate it:
// hsnc::read_model (model_reader.h), hsnc::simulate (simulate.h), the
// Observer that receives samples and switch events and the RunSummary of a
// run (engine.h), the errors (error.h), periodic orbits (periodic.h) and
// Lyapunov exponents (lyapunov.h).
#pragma once

#include "engine.h"
#include "error.h"
#include "integrators.h"
#include "lyapunov.h"
#include "model.h"
#include "model_reader.h"
#include "modes.h"
#include "periodic.h"
#include "simulate.h"
