// hsnc -- matrices of a [structure] from MATLAB .mat files (libmatio).
//
// A structure key may name a variable of a .mat file (version 5, 7.3):
// "beam.mat:K" is variable K of beam.mat; "beam.mat" alone takes the key's
// own letter (M for mass, K for stiffness, C for damping). The variable must
// be a real, two-dimensional double matrix, dense or sparse; every value a
// finite normal double (or zero), as the Matrix Market reader demands.
//
// Before libmatio reads a variable, hsnc checks what libmatio does not: a
// version 5 file's variables must lie whole inside the file (libmatio reads
// the part cut off a truncated file as zeros), a version 7.3 file must be an
// HDF5 file that HDF5 opens, and the variable's header (class, rank,
// dimensions) must be within kMaxMatrixDimension and within what the file's
// size can hold, so no data is allocated or read for a variable that would be
// refused. Version 4 files are refused.
//
// libmatio (Debian's libmatio11) is loaded with dlopen when the first .mat
// file is read: linked in, it and HDF5 would load a dozen shared libraries
// into every hsnc process. HDF5's error stack and libmatio's log stay off
// stderr. Errors are InputError "FILE:VARIABLE: reason" (or "cannot read
// matrix file 'FILE': reason").
#pragma once

#include <string>

#include "matrix_market.h"

namespace hsnc {

/// True when `spec` names a .mat file ("x.mat" or "x.mat:VAR").
bool is_mat_spec(const std::string& spec);

/// Splits "x.mat:VAR" into ("x.mat", "VAR"); "x.mat" gives ("x.mat", default_variable).
std::pair<std::string, std::string> split_mat_spec(const std::string& spec, const std::string& default_variable);

/// Variable `variable` of the .mat file at `path`. Throws InputError.
MarketMatrix read_mat_variable(const std::string& path, const std::string& variable);

}  // namespace hsnc
