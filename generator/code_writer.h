// hsnc -- the one way the emitters build C++ text (generator/emitter.cpp,
// the folded kernels; generator/param_emitter.cpp, the sweep kernels).
//
// A CodeWriter appends lines at a fixed layout (4 spaces per indent level,
// one statement per line, "\n" line ends), comments, verbatim text and
// blocks; numbers are written with format_double (double_literal.h), so every
// constant of every kernel reads back to the same double.
#pragma once

#include <string>
#include <vector>

#include "double_literal.h"

namespace hsnc {

class CodeWriter {
public:
    /// `text` on a line of its own at `indent` levels.
    CodeWriter& line(int indent, const std::string& text);
    /// An empty line.
    CodeWriter& blank();
    /// `text` as it is (it brings its own line ends).
    CodeWriter& raw(const std::string& text);
    /// "// <line>" at `indent` for every non-empty line of `text` ('\n' separated).
    CodeWriter& comment(int indent, const std::string& text);
    /// `open` at `indent`, what `body` writes (at indent + 1 by its own calls), `close` at `indent`.
    template <class Body>
    CodeWriter& block(int indent, const std::string& open, const std::string& close, Body body) {
        line(indent, open);
        body();
        return line(indent, close);
    }
    /// Everything written so far.
    const std::string& str() const { return out_; }

    /// A double as a literal that reads back to it (format_double).
    static std::string literal(double v) { return format_double(v); }
    /// The same as an operand: a negative one in parentheses ("(-2.5)").
    static std::string operand(double v);
    /// "a, b, c" of integers; `empty` when there are none.
    static std::string list(const std::vector<int>& v, const std::string& empty = "0");
    /// "a, b, c" of texts (no brackets); "" when there are none.
    static std::string join(const std::vector<std::string>& v, const std::string& separator = ", ");

private:
    std::string out_;
};

}  // namespace hsnc
