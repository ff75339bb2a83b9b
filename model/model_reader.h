// hsnc -- reading a model file (interface.md section 1) into a Model.
//
// Numbers may be given as TOML numbers or as strings holding an expression
// over earlier [parameters], parsed by GiNaC ("2*k1", "sqrt(k/m)"). Every
// check that makes a model physically meaningful happens here; a Model that
// leaves this reader is valid. Every failure throws InputError with a message
// "FILE:LINE: key 'KEY': reason" (LINE where toml++ gives one).
//
// Decisions where interface.md is silent (each one is tested in
// tests/test_model_reader.cpp):
//  - KEY is the TOML path; tables of an array are numbered from 1 as they
//    appear in the file: "mass[2].m", "forcing[1].amplitude.m1".
//  - Masses and contacts share one name space (a contact may not be named like
//    a mass), so the `element` column of the events CSV is never ambiguous.
//    Parameters have their own name space: a mass "m1" whose value is the
//    parameter "m1" is the paper's Table 1 notation and is allowed.
//  - `ground` is reserved for masses, contacts and parameters; so are the
//    constants GiNaC's parser knows by name (Pi, Euler, Catalan, I), which a
//    parameter could not shadow.
//  - `pi` is the constant Pi as well (GiNaC's parser knows only `Pi`), unless
//    the file names a parameter pi, which then keeps that name; expressions
//    are recorded with Pi. What an expression may contain and cost is in
//    expression_evaluator.h (and docs/guide/models.md, "Model expressions").
//  - A subnormal value (0 < |v| < 2.2e-308) is refused: the derivation's
//    numbers (CLN) have none.
//  - `g` is a parameter. When [parameters] does not define it, it is an
//    implicit first parameter g = 9.81 that every expression may use (and
//    --set g=... may override); it then comes first in Model::parameters.
//    When the file defines g it is an ordinary parameter in file order.
//  - Forcing omega must be > 0: omega < 0 is meaningless, and omega = 0 is a
//    constant force, which [load] states directly.
//  - [simulate].t_end must be > t0, unless the caller replaces it
//    (ModelOverrides::t_end, the --t-end flag): a default nobody uses is not
//    an error. Model::t_end is then the override.
//  - A flag naming the same parameter or mass twice is an error, not
//    "last one wins": a repeated override is most likely a slip.
//  - [structure] (interface.md section 5; the checks on its matrices are in
//    structure.h): its dofs become the masses (m = M_ii) and share the name
//    space of masses and contacts; its files are read relative to the model
//    file's folder; messages say "dof" where they say "mass" for [[mass]].
//  - [[friction]] between a body and the ground is that body's friction with
//    N = normal (elements/friction.h, FrictionSlot); its names share the same name
//    space (default "friction<N>"). Friction between two bodies and
//    [[jenkins]] are refused as not yet supported.
//  - [[damper]] c = 0 adds no damper (the model stays proportional: every
//    kernel kind runs it); c < 0 is refused.
#pragma once

#include <optional>
#include <string>
#include <utility>
#include <vector>

#include "model.h"

namespace hsnc {

/// Command-line overrides, applied while reading (flags --set, --x0, --v0).
/// Each entry is the raw flag value "NAME=VALUE"; VALUE may be an expression
/// over the parameters.
struct ModelOverrides {
    std::vector<std::string> set;  ///< parameter overrides; later parameters see the new value
    std::vector<std::string> x0;   ///< initial position overrides
    std::vector<std::string> v0;   ///< initial velocity overrides
    std::optional<double> t_end;   ///< --t-end: replaces [simulate].t_end, which is then not checked against t0
    /// With [reduction]: also solve the full structure's lowest frequencies
    /// (ReductionSource::open and closed, for `check` and `reduce`; sparse eigensolves).
    bool full_frequencies = false;
};

/// `overrides` with `t_end` from a --t-end flag (NaN: the flag was not given).
ModelOverrides with_t_end(ModelOverrides overrides, double t_end);

/// Read and validate the model file at `path`; Model::source is `path`.
/// A missing or unreadable file is an InputError
/// "cannot read model file 'PATH': REASON".
Model read_model(const std::string& path, const ModelOverrides& overrides = {});

/// Same, from TOML text; `source` names it in messages and is Model::source.
Model parse_model(const std::string& toml_text, const std::string& source,
                  const ModelOverrides& overrides = {});

/// True when `name` matches [A-Za-z_][A-Za-z0-9_]* (interface.md section 1).
bool is_valid_name(const std::string& name);

}  // namespace hsnc
