// hsnc -- a strict reader of Matrix Market files (the NIST exchange format) for
// the matrices of a [structure] (interface.md section 5).
//
// Accepted: "%%MatrixMarket matrix coordinate|array real|integer general|symmetric".
// Coordinate files give "i j value" lines (1-based, each entry at most once;
// a symmetric file holds the lower triangle i >= j only); array files give
// every value column by column (a symmetric one the lower triangle, column by
// column). Comment lines start with '%'; blank lines are skipped. Anything
// else (complex or pattern fields, skew-symmetric or Hermitian storage, a
// missing or extra entry, a number that is not finite or not a normal double,
// a value of an integer file that is not an integer literal, trailing text on
// a line, a NUL byte) is an error "FILE:LINE: reason" (LINE when the
// error belongs to one line). The whole file is read before anything is used.
#pragma once

#include <cstddef>
#include <string>
#include <vector>

#include <Eigen/SparseCore>

namespace hsnc {

/// A dense matrix read from a Matrix Market file, row-major.
struct MarketMatrix {
    std::size_t rows = 0;
    std::size_t cols = 0;
    std::vector<double> values;  ///< rows*cols entries, row-major; symmetric files filled in both triangles
    double operator()(std::size_t i, std::size_t j) const { return values[i * cols + j]; }
};

/// A matrix read entry by entry, for the structures a [reduction] reduces
/// (reduction.h): its nonzero entries (a symmetric file's mirrored), in file order.
struct SparseMarket {
    using Entry = Eigen::Triplet<double, int>;
    std::size_t rows = 0;
    std::size_t cols = 0;
    std::vector<Entry> entries;
};

/// Largest file read (a dense 2000 x 2000 matrix written with 17 digits fits).
inline constexpr std::size_t kMaxMatrixFileBytes = std::size_t{128} << 20;
/// Largest dimension accepted, and the most dofs a model may have (the
/// reader refuses more, model_reader.h): hsnc's matrices are dense and its
/// modal analysis is cubic in the dofs. Measured on a 2-core machine under
/// load, a chain structure with one contact: `check` 0.24 s / 18 MB at 500
/// dofs, 1.8 s / 47 MB at 1000, 21 s / 166 MB at 2000, 156 s / 369 MB at 3000;
/// `simulate` (generic kernels, 2 configurations) 6 s / 148 MB at 500, 18 s /
/// 305 MB at 750. 500 keeps both within seconds and a few hundred MB.
inline constexpr std::size_t kMaxMatrixDimension = 500;

/// Largest dimension of a matrix read sparse (a structure that [reduction]
/// reduces), and the largest such file: 2 GiB of text holds about 5e7 entries.
inline constexpr std::size_t kMaxSparseDimension = 10'000'000;
inline constexpr std::size_t kMaxSparseFileBytes = std::size_t{2} << 30;

/// Parse Matrix Market text; `source` names it in messages. Throws InputError.
MarketMatrix parse_matrix_market(const std::string& text, const std::string& source);

/// Read the Matrix Market file at `path` (a regular file of at most
/// kMaxMatrixFileBytes). Throws InputError "cannot read matrix file 'PATH': REASON"
/// or a parse error.
MarketMatrix read_matrix_market(const std::string& path);

/// The same reader for a structure of up to kMaxSparseDimension dofs, its
/// entries kept sparse (array files only up to kMaxMatrixDimension rows).
SparseMarket parse_sparse_matrix_market(const std::string& text, const std::string& source);
SparseMarket read_sparse_matrix_market(const std::string& path);

/// A symmetric n x n matrix (row-major, n*n doubles) as the text of a
/// Matrix Market coordinate file: its nonzero lower triangle, each value in
/// 17 significant digits (reads back as the same double), `comment` as a
/// `%` line after the banner.
std::string symmetric_market_text(const std::vector<double>& row_major, std::size_t n, const std::string& comment);

}  // namespace hsnc
