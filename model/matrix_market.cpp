#include "matrix_market.h"

#include <algorithm>
#include <cerrno>
#include <cfloat>
#include <cmath>
#include <cstdint>
#include <cstdlib>
#include <sstream>

#include "error.h"
#include "file_read.h"

namespace hsnc {
namespace {

std::string lower(std::string s) {
    for (char& c : s)
        if (c >= 'A' && c <= 'Z') c = static_cast<char>(c - 'A' + 'a');
    return s;
}

/// The whitespace-separated words of one line.
std::vector<std::string> words(const std::string& line) {
    std::vector<std::string> out;
    std::istringstream in(line);
    std::string w;
    while (in >> w) out.push_back(w);
    return out;
}

/// [+-]?[0-9]+
bool is_integer_literal(const std::string& w) {
    const std::size_t digits = !w.empty() && (w[0] == '+' || w[0] == '-') ? 1 : 0;
    return w.size() > digits && w.find_first_not_of("0123456789", digits) == std::string::npos;
}

class Parser {
public:
    Parser(const std::string& text, std::string source, std::size_t max_dimension)
        : text_(text), source_(std::move(source)), max_dimension_(max_dimension) {}

    /// Every entry the file gives, both triangles of a symmetric one, in file order.
    SparseMarket parse() {
        std::string line;
        if (!next_raw(line)) fail(0, "empty file (expected a '%%MatrixMarket matrix ...' header)");
        const std::vector<std::string> h = words(line);
        if (h.empty() || h[0] != "%%MatrixMarket")
            fail(line_, "expected the header '%%MatrixMarket matrix coordinate|array real general|symmetric'");
        if (h.size() != 5) fail(line_, "header needs 4 words after %%MatrixMarket (object format field symmetry)");
        if (lower(h[1]) != "matrix") fail(line_, "object '" + h[1] + "' is not supported (expected matrix)");
        const std::string format = lower(h[2]), field = lower(h[3]), symmetry = lower(h[4]);
        if (format != "coordinate" && format != "array")
            fail(line_, "format '" + h[2] + "' is not supported (expected coordinate or array)");
        if (field != "real" && field != "integer" && field != "double")
            fail(line_, "field '" + h[3] + "' is not supported (expected real or integer)");
        if (symmetry != "general" && symmetry != "symmetric")
            fail(line_, "symmetry '" + h[4] + "' is not supported (expected general or symmetric)");
        const bool symmetric = symmetry == "symmetric";
        integer_ = field == "integer";

        if (!next_data(line)) fail(0, "missing the size line");
        const std::vector<std::string> size = words(line);
        SparseMarket m;
        std::size_t nnz = 0;
        if (size.size() != (format == "coordinate" ? 3u : 2u))
            fail(line_, format == "coordinate" ? "size line must be 'ROWS COLS ENTRIES'" : "size line must be 'ROWS COLS'");
        m.rows = count(size[0], "rows");
        m.cols = count(size[1], "columns");
        if (m.rows == 0 || m.cols == 0) fail(line_, "the matrix is empty (0 rows or columns)");
        if (m.rows > max_dimension_ || m.cols > max_dimension_)
            fail(line_, "larger than " + std::to_string(max_dimension_) + " rows or columns");
        if (symmetric && m.rows != m.cols) fail(line_, "a symmetric matrix must be square");
        if (format == "array" && m.rows > kMaxMatrixDimension)  // every value listed: a dense file
            fail(line_, "an array (dense) file of more than " + std::to_string(kMaxMatrixDimension) +
                            " rows; give a coordinate file");

        if (format == "coordinate") {
            nnz = count(size[2], "entries");
            // Each entry at most once: a bitmap while the matrix is small, else
            // the sorted positions once the whole file is read.
            const bool small = m.rows * m.cols <= kMaxMatrixDimension * kMaxMatrixDimension;
            std::vector<char> seen(small ? m.rows * m.cols : 0, 0);
            std::vector<std::size_t> lines;
            std::vector<std::uint64_t> positions;  // (i - 1) << 32 | (j - 1)
            m.entries.reserve(std::min<std::size_t>(nnz, std::size_t{1} << 24) * (symmetric ? 2 : 1));
            for (std::size_t e = 0; e < nnz; ++e) {
                if (!next_data(line))
                    fail(0, "the size line announces " + std::to_string(nnz) + " entries, the file ends after " +
                                std::to_string(e));
                const std::vector<std::string> w = words(line);
                if (w.size() != 3) fail(line_, "expected an entry 'ROW COLUMN VALUE'");
                const std::size_t i = count(w[0], "row"), j = count(w[1], "column");
                if (i < 1 || i > m.rows || j < 1 || j > m.cols)
                    fail(line_, "entry (" + w[0] + ", " + w[1] + ") is outside the " + std::to_string(m.rows) + " x " +
                                    std::to_string(m.cols) + " matrix");
                if (symmetric && i < j)
                    fail(line_, "entry (" + w[0] + ", " + w[1] +
                                    ") is above the diagonal; a symmetric file holds the lower triangle only");
                if (small) {
                    if (seen[(i - 1) * m.cols + (j - 1)])
                        fail(line_, "entry (" + w[0] + ", " + w[1] + ") is given twice");
                    seen[(i - 1) * m.cols + (j - 1)] = 1;
                } else {
                    lines.push_back(line_);
                    positions.push_back(static_cast<std::uint64_t>(i - 1) << 32 | (j - 1));
                }
                put(m, i - 1, j - 1, value(w[2]), symmetric);
            }
            if (!small) no_duplicates(positions, lines);
        } else {
            for (std::size_t j = 0; j < m.cols; ++j)
                for (std::size_t i = symmetric ? j : 0; i < m.rows; ++i) {
                    if (!next_data(line))
                        fail(0, "the file ends before entry (" + std::to_string(i + 1) + ", " + std::to_string(j + 1) +
                                    ") of the array");
                    const std::vector<std::string> w = words(line);
                    if (w.size() != 1) fail(line_, "expected one value per line in array format");
                    put(m, i, j, value(w[0]), symmetric);
                }
        }
        if (next_data(line)) fail(line_, "more entries than the size line announces");
        return m;
    }

private:
    [[noreturn]] void fail(std::size_t line, const std::string& reason) const {
        throw InputError(source_ + (line ? ":" + std::to_string(line) : std::string()) + ": " + reason);
    }

    /// The next line, whatever it holds; false at the end.
    bool next_raw(std::string& line) {
        if (pos_ >= text_.size()) return false;
        const std::size_t end = text_.find('\n', pos_);
        line = text_.substr(pos_, end == std::string::npos ? std::string::npos : end - pos_);
        if (!line.empty() && line.back() == '\r') line.pop_back();
        pos_ = end == std::string::npos ? text_.size() : end + 1;
        ++line_;
        // A NUL would end the C string strtod reads: "1\0garbage" would read as 1.
        if (line.find('\0') != std::string::npos) fail(line_, "contains a NUL byte (not a text file?)");
        return true;
    }
    /// The next line that is neither blank nor a comment.
    bool next_data(std::string& line) {
        while (next_raw(line)) {
            const std::size_t first = line.find_first_not_of(" \t");
            if (first == std::string::npos || line[first] == '%') continue;
            return true;
        }
        return false;
    }

    std::size_t count(const std::string& word, const char* what) const {
        if (word.empty() || word.find_first_not_of("0123456789") != std::string::npos || word.size() > 9)
            fail(line_, std::string("'") + word + "' is not a valid number of " + what);
        return static_cast<std::size_t>(std::stoul(word));
    }

    double value(const std::string& word) const {
        // An integer field holds integers: "1.5" or "1e3" there is a damaged or mislabelled file.
        if (integer_ && !is_integer_literal(word))
            fail(line_, "'" + word + "' is not an integer (the header says the field is integer)");
        errno = 0;
        char* end = nullptr;
        const double v = std::strtod(word.c_str(), &end);
        if (end == word.c_str() || end != word.c_str() + word.size()) fail(line_, "'" + word + "' is not a number");
        if (!std::isfinite(v)) fail(line_, "'" + word + "' is not a finite double");
        if ((v != 0.0 && std::fabs(v) < DBL_MIN) || (v == 0.0 && errno == ERANGE))
            fail(line_, "'" + word + "' is below the smallest normal double (subnormal values are refused)");
        if (errno == ERANGE) fail(line_, "'" + word + "' is beyond the double range");
        return v;
    }

    static void put(SparseMarket& m, std::size_t i, std::size_t j, double v, bool symmetric) {
        if (v == 0.0) return;
        m.entries.emplace_back(static_cast<int>(i), static_cast<int>(j), v);
        if (symmetric && i != j) m.entries.emplace_back(static_cast<int>(j), static_cast<int>(i), v);
    }

    /// A large coordinate file: no position twice (positions[k] and lines[k]
    /// of the k-th entry given, zero or not; the later line of a pair is named).
    void no_duplicates(const std::vector<std::uint64_t>& positions, const std::vector<std::size_t>& lines) const {
        std::vector<std::size_t> order(lines.size());
        for (std::size_t k = 0; k < order.size(); ++k) order[k] = k;
        std::sort(order.begin(), order.end(), [&](std::size_t a, std::size_t b) {
            return positions[a] != positions[b] ? positions[a] < positions[b] : a < b;
        });
        for (std::size_t k = 1; k < order.size(); ++k)
            if (positions[order[k]] == positions[order[k - 1]]) {
                const std::uint64_t p = positions[order[k]];
                fail(lines[order[k]], "entry (" + std::to_string((p >> 32) + 1) + ", " +
                                          std::to_string((p & 0xffffffffu) + 1) + ") is given twice");
            }
    }

    const std::string& text_;
    std::string source_;
    std::size_t pos_ = 0;
    std::size_t max_dimension_;
    std::size_t line_ = 0;
    bool integer_ = false;  ///< the header's field is integer
};

}  // namespace

MarketMatrix parse_matrix_market(const std::string& text, const std::string& source) {
    const SparseMarket s = Parser(text, source, kMaxMatrixDimension).parse();
    MarketMatrix m;
    m.rows = s.rows;
    m.cols = s.cols;
    m.values.assign(m.rows * m.cols, 0.0);
    for (const auto& e : s.entries)
        m.values[static_cast<std::size_t>(e.row()) * m.cols + static_cast<std::size_t>(e.col())] = e.value();
    return m;
}

SparseMarket parse_sparse_matrix_market(const std::string& text, const std::string& source) {
    return Parser(text, source, kMaxSparseDimension).parse();
}

SparseMarket read_sparse_matrix_market(const std::string& path) {
    const FileRead file = read_regular_file(path, kMaxSparseFileBytes);
    if (file.status != FileRead::Status::ok) throw InputError("cannot read matrix file '" + path + "': " + file.problem);
    return parse_sparse_matrix_market(file.bytes, path);
}

MarketMatrix read_matrix_market(const std::string& path) {
    const FileRead file = read_regular_file(path, kMaxMatrixFileBytes);
    if (file.status != FileRead::Status::ok) throw InputError("cannot read matrix file '" + path + "': " + file.problem);
    return parse_matrix_market(file.bytes, path);
}

std::string symmetric_market_text(const std::vector<double>& row_major, std::size_t n, const std::string& comment) {
    std::ostringstream body;
    body.precision(17);
    std::size_t nnz = 0;
    for (std::size_t j = 0; j < n; ++j)
        for (std::size_t i = j; i < n; ++i)
            if (const double v = row_major[i * n + j]; v != 0.0) body << i + 1 << " " << j + 1 << " " << v << "\n", ++nnz;
    return "%%MatrixMarket matrix coordinate real symmetric\n% " + comment + "\n" + std::to_string(n) + " " +
           std::to_string(n) + " " + std::to_string(nnz) + "\n" + body.str();
}

}  // namespace hsnc
