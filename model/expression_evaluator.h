// hsnc -- evaluating one model expression ("2*k1", "sqrt(k/m)") to a double,
// with its cost bounded before GiNaC computes anything.
//
// GiNaC's parser is recursive, and it evaluates numbers exactly while it
// builds the expression: "10^(10^10)" or "factorial(10^7)" would be computed
// as exact integers of billions of digits, and 7000 nested parentheses
// overflow the stack. So every expression is first read by a small parser of
// the same grammar (GiNaC's: + - * / ^, unary signs that take the rest of the
// operand list, calls, numbers [0-9.]+ with an optional exponent, '#'
// comments) that estimates every intermediate value in long double and
// refuses, naming the reason:
//  - nesting deeper than kMaxExpressionDepth levels (parentheses, calls,
//    unary signs);
//  - a value whose magnitude is beyond 10^kMaxDecimalExponent or below
//    10^-kMaxDecimalExponent (other than 0): far outside a double, and
//    costly to compute exactly;
//  - an exact number (GiNaC keeps integers and fractions exact) of more than
//    kMaxExactBits bits, e.g. "(1000001/1000000)^(10^9)";
//  - a number literal longer than kMaxLiteralLength characters;
//  - a function outside the list allowed_functions() names.
// Only then does GiNaC parse and evaluate it, at kEvaluationDigits decimal
// digits, or more when sin/cos/tan have a large argument (the argument is then
// known to 10^-40 absolutely, so sin(1e80) is the sine of 10^80, not 0).
// Subnormal results are returned as subnormal doubles; a non-zero result
// below the smallest subnormal is refused rather than rounded to 0.
#pragma once

#include <string>
#include <unordered_map>

namespace hsnc {

/// Limits of a model expression (documented in docs/guide/models.md, "Model expressions").
inline constexpr int kMaxExpressionDepth = 200;
inline constexpr int kMaxDecimalExponent = 1000;
inline constexpr double kMaxExactBits = 100000;
inline constexpr std::size_t kMaxLiteralLength = 1000;

/// Decimal digits of the evaluation (see model_reader.cpp: at 40 digits the
/// string "0.1" gives the same double as the TOML literal 0.1).
inline constexpr long kEvaluationDigits = 40;

/// Why an expression could not be turned into a real, finite double.
struct ExpressionError {
    std::string reason;          ///< "expression '...' does not parse: ...", one line
    std::string unknown_symbol;  ///< set when the cause is a name not in scope
};

/// The names an expression may use beyond the parameters in scope.
struct ExpressionScope {
    const std::unordered_map<std::string, double>* parameters = nullptr;  ///< name -> value
    bool pi_is_constant = true;  ///< `pi` means Pi (false when a parameter is named pi)
};

/// The evaluated value and the text the other readers of the model may parse
/// with GiNaC's own parser (`pi` written as `Pi`).
struct EvaluatedExpression {
    double value = 0;
    std::string canonical_text;
};

/// Evaluate `text` (see the file comment). Throws ExpressionError.
EvaluatedExpression evaluate_expression(const std::string& text, const ExpressionScope& scope);

/// "sin, cos, ..." -- the functions a model expression may call.
std::string allowed_functions();

/// `text` shortened for a message: at most `max_chars` UTF-8 characters, cut
/// at a character boundary and ended with "...", control characters shown as
/// spaces so that the message stays on one line.
std::string excerpt(const std::string& text, std::size_t max_chars = 80);

}  // namespace hsnc
