// hsnc -- evaluating one model expression with its cost bounded (see the header).
//
// The pre-scan is a recursive-descent parser of GiNaC's expression grammar
// (GiNaC 1.8, ginac/parser/parser.cpp and parse_binop_rhs.cpp): binary
// operators by precedence (+ - 20, * / 40, ^ 60, each level left to right),
// and a unary sign at the start of an operand that, as in GiNaC, reads the
// rest of the operand list at the lowest precedence ("2*-3+1" is 2*(-3+1)).
// Parsing the same way gives the same tree, so the estimate of each
// intermediate value is the value GiNaC will compute, to long double accuracy.
#include "expression_evaluator.h"

#include <cerrno>
#include <cfloat>
#include <cmath>
#include <cstdlib>
#include <set>
#include <sstream>
#include <utility>
#include <vector>

#include <ginac/ginac.h>

namespace hsnc {

std::string excerpt(const std::string& text, std::size_t max_chars) {
    std::string out;
    std::size_t chars = 0;
    for (std::size_t i = 0; i < text.size(); ++i) {
        const auto byte = static_cast<unsigned char>(text[i]);
        const bool continuation = (byte & 0xC0) == 0x80;
        if (!continuation && chars++ == max_chars) return out + "...";
        out += byte < 0x20 || byte == 0x7F ? ' ' : text[i];
    }
    return out;
}

namespace {

// The functions a model expression may call, with their argument counts:
// elementary functions only, whose cost does not grow with their argument
// (factorial's is bounded by the magnitude check), and which a kernel can
// call (generator/param_emitter.cpp prints them as C).
const std::vector<std::pair<const char*, std::size_t>> kFunctions = {
    {"sin", 1},   {"cos", 1},   {"tan", 1},   {"asin", 1},  {"acos", 1}, {"atan", 1},
    {"atan2", 2}, {"sinh", 1},  {"cosh", 1},  {"tanh", 1},  {"asinh", 1}, {"acosh", 1},
    {"atanh", 1}, {"exp", 1},   {"log", 1},   {"sqrt", 1},  {"abs", 1},  {"pow", 2},
    {"factorial", 1}};

bool function_allowed(const std::string& name, std::size_t arity) {
    for (const auto& [n, a] : kFunctions)
        if (name == n && arity == a) return true;
    return false;
}

/// GiNaC's default function table restricted to kFunctions.
const GiNaC::prototype_table& allowed_reader() {
    static const GiNaC::prototype_table table = [] {
        GiNaC::prototype_table t;
        for (const auto& [proto, fn] : GiNaC::get_default_reader())
            if (function_allowed(proto.first, proto.second)) t.emplace(proto, fn);
        return t;
    }();
    return table;
}

/// Sets GiNaC's working precision for a scope and restores it after.
class DigitsGuard {
public:
    explicit DigitsGuard(long digits) : saved_(GiNaC::Digits) { GiNaC::Digits = digits; }
    ~DigitsGuard() { GiNaC::Digits = saved_; }
    DigitsGuard(const DigitsGuard&) = delete;
    DigitsGuard& operator=(const DigitsGuard&) = delete;

private:
    long saved_;
};

std::string first_line(const std::string& text) { return text.substr(0, text.find('\n')); }

constexpr long double kLog10E = 0.434294481903251827651128918916605082L;
constexpr long double kLog2Of10 = 3.32192809488736234787031942948939018L;

/// What the pre-scan knows of a subexpression: its value (a magnitude for a
/// complex one; NaN only after a division by 0, which GiNaC refuses itself)
/// and, for a number GiNaC keeps exact, a bound on its size in bits.
struct Estimate {
    long double v = 0;
    bool exact = false;    ///< an integer, a fraction or an exact root: GiNaC computes it exactly
    bool integer = false;  ///< an exact integer
    double bits = 0;       ///< size bound (numerator plus denominator) when exact
};

struct Token {
    enum class Kind { end, number, identifier, literal, symbol } kind = Kind::end;
    std::string text;  ///< number or name
    char ch = 0;       ///< Kind::symbol: the character
    std::size_t pos = 0;
};

class PreScan {
public:
    PreScan(const std::string& text, const ExpressionScope& scope) : text_(text), scope_(scope) { advance(); }

    /// Parse the whole text; returns the estimate of its value.
    Estimate run() {
        const Estimate e = expression();
        if (token_.kind != Token::Kind::end) syntax("unexpected " + describe(token_) + " after the expression");
        return e;
    }

    long double largest_trig_argument() const { return trig_; }
    const std::set<std::string>& parameters_used() const { return used_; }

    /// The text with `pi` (the constant) written `Pi`, for GiNaC's own parser.
    std::string canonical_text() const {
        std::string out;
        std::size_t from = 0;
        for (std::size_t at : pi_at_) {
            out += text_.substr(from, at - from) + "Pi";
            from = at + 2;
        }
        return out + text_.substr(from);
    }

private:
    // ---- lexer: GiNaC's (ginac/parser/lexer.cpp) ----

    static bool alpha(char c) { return (c >= 'A' && c <= 'Z') || (c >= 'a' && c <= 'z'); }
    static bool digit(char c) { return c >= '0' && c <= '9'; }
    static bool space(char c) { return c == ' ' || c == '\t' || c == '\n' || c == '\r' || c == '\v' || c == '\f'; }

    void advance() {
        std::size_t& i = pos_;
        while (true) {
            while (i < text_.size() && space(text_[i])) ++i;
            if (i < text_.size() && text_[i] == '#') {  // a comment to the end of the line
                while (i < text_.size() && text_[i] != '\n' && text_[i] != '\r') ++i;
                continue;
            }
            break;
        }
        token_ = Token{};
        token_.pos = i;
        if (i >= text_.size()) return;
        const char c = text_[i];
        if (alpha(c)) {
            const std::size_t start = i;
            while (i < text_.size() && (alpha(text_[i]) || digit(text_[i]) || text_[i] == '_')) ++i;
            token_.text = text_.substr(start, i - start);
            const bool literal = token_.text == "I" || token_.text == "Pi" || token_.text == "Euler" ||
                                 token_.text == "Catalan";
            token_.kind = literal ? Token::Kind::literal : Token::Kind::identifier;
            return;
        }
        if (digit(c) || c == '.') {
            const std::size_t start = i;
            while (i < text_.size() && (digit(text_[i]) || text_[i] == '.')) ++i;
            if (i < text_.size() && (text_[i] == 'e' || text_[i] == 'E')) {
                ++i;
                if (i < text_.size()) ++i;  // the exponent's sign or first digit, as GiNaC takes it
                while (i < text_.size() && digit(text_[i])) ++i;
            }
            token_.kind = Token::Kind::number;
            token_.text = text_.substr(start, i - start);
            return;
        }
        token_.kind = Token::Kind::symbol;
        token_.ch = c;
        ++i;
    }

    static std::string describe(const Token& t) {
        switch (t.kind) {
            case Token::Kind::end: return "end of expression";
            case Token::Kind::symbol: return "'" + excerpt(std::string(1, t.ch)) + "'";
            default: return "'" + excerpt(t.text, 40) + "'";
        }
    }

    // ---- errors ----

    [[noreturn]] void syntax(const std::string& reason) const {
        throw ExpressionError{"expression '" + excerpt(text_) + "' does not parse: " + reason, ""};
    }
    [[noreturn]] void refuse(const std::string& reason) const {
        throw ExpressionError{"expression '" + excerpt(text_) + "' " + reason, ""};
    }
    [[noreturn]] void out_of_range(long double log10_magnitude) const {
        std::ostringstream s;
        s << "is refused before evaluating it: a value in it is about 10^"
          << static_cast<long long>(std::floor(std::max(-1e18L, std::min(1e18L, log10_magnitude))))
          << ", outside the magnitudes 10^-" << kMaxDecimalExponent << " to 10^" << kMaxDecimalExponent
          << " a model expression may pass through (a double holds 4.9e-324 to 1.8e308)";
        refuse(s.str());
    }

    /// Refuse a value far outside the range of a double.
    Estimate checked(Estimate e) const {
        if (std::isinf(e.v)) out_of_range(e.v > 0 ? 1e18L : -1e18L);
        if (!std::isnan(e.v) && e.v != 0) {
            const long double l = std::log10(std::fabs(e.v));
            if (std::fabs(l) > kMaxDecimalExponent) out_of_range(l);
        }
        if (e.exact && e.bits > kMaxExactBits) {
            std::ostringstream s;
            s << "is refused before evaluating it: an exact number in it would have about "
              << static_cast<long long>(std::min<long double>(e.bits, 1e18L) / kLog2Of10)
              << " digits (at most " << static_cast<long long>(kMaxExactBits / kLog2Of10)
              << "); write a base with a decimal point (e.g. 1.5) to compute in floating point";
            refuse(s.str());
        }
        return e;
    }
    /// Refuse before computing a value whose log10 magnitude is `l`.
    void check_log10(long double l) const {
        if (std::isnan(l)) return;
        if (std::fabs(l) > kMaxDecimalExponent) out_of_range(l);
    }

    // ---- grammar ----

    Estimate expression() { return rhs(0, primary()); }

    static int precedence(const Token& t) {
        if (t.kind != Token::Kind::symbol) return -1;
        switch (t.ch) {
            case '+': case '-': return 20;
            case '*': case '/': return 40;
            case '^': return 60;
            default: return -1;
        }
    }

    /// Binary operators of precedence >= `min` after `lhs`, left to right.
    Estimate rhs(int min, Estimate lhs) {
        while (precedence(token_) >= min && precedence(token_) >= 0) {
            const char op = token_.ch;
            const int p = precedence(token_);
            advance();
            Estimate right = primary();
            if (precedence(token_) > p) right = rhs(p + 1, right);
            lhs = apply(op, lhs, right);
        }
        return lhs;
    }

    Estimate primary() {
        struct Depth {
            int& d;
            explicit Depth(int& depth) : d(depth) { ++d; }
            ~Depth() { --d; }
        } depth(depth_);
        if (depth_ > kMaxExpressionDepth)
            refuse("nests parentheses, function calls and signs more than " + std::to_string(kMaxExpressionDepth) +
                   " levels deep (the most a model expression may)");
        switch (token_.kind) {
            case Token::Kind::number: {
                const Estimate e = number(token_.text);
                advance();
                return e;
            }
            case Token::Kind::literal: {
                const std::string name = token_.text;
                advance();
                return constant(name);
            }
            case Token::Kind::identifier: return identifier();
            case Token::Kind::symbol:
                if (token_.ch == '(') {
                    advance();
                    const Estimate e = expression();
                    if (!(token_.kind == Token::Kind::symbol && token_.ch == ')'))
                        syntax("expected ')', got " + describe(token_));
                    advance();
                    return e;
                }
                if (token_.ch == '+' || token_.ch == '-') {
                    // GiNaC reads a sign as 0 +- (the rest of the operand list).
                    Estimate zero;
                    zero.exact = zero.integer = true;
                    zero.bits = 1;
                    return rhs(0, zero);
                }
                syntax("unexpected " + describe(token_));
            case Token::Kind::end: syntax("unexpected end of expression");
        }
        syntax("unexpected " + describe(token_));
    }

    Estimate number(const std::string& t) const {
        if (t.size() > kMaxLiteralLength)
            refuse("has a number of more than " + std::to_string(kMaxLiteralLength) + " characters");
        const bool is_float = t.find_first_of(".eE") != std::string::npos;
        errno = 0;
        char* end = nullptr;
        Estimate e;
        e.v = std::strtold(t.c_str(), &end);
        if (end != t.c_str() + t.size()) syntax("malformed number '" + excerpt(t, 40) + "'");
        if (errno == ERANGE) out_of_range(e.v == 0 ? -1e18L : 1e18L);
        if (!is_float) {
            e.exact = e.integer = true;
            e.bits = static_cast<double>(t.size()) * kLog2Of10 + 1;
        }
        return checked(e);
    }

    Estimate constant(const std::string& name) const {
        Estimate e;
        if (name == "I") {  // magnitude 1; exact, as GiNaC keeps I
            e.v = 1;
            e.exact = true;
            e.bits = 2;
        } else if (name == "Pi") {
            e.v = 3.14159265358979323846264338327950288L;
        } else if (name == "Euler") {
            e.v = 0.577215664901532860606512090082402431L;
        } else {  // Catalan
            e.v = 0.915965594177219015054603514932384110L;
        }
        return e;
    }

    Estimate identifier() {
        const Token name = token_;
        advance();
        if (token_.kind == Token::Kind::symbol && token_.ch == '(') {
            advance();
            std::vector<Estimate> args;
            if (!(token_.kind == Token::Kind::symbol && token_.ch == ')')) {
                while (true) {
                    args.push_back(expression());
                    if (token_.kind == Token::Kind::symbol && token_.ch == ')') break;
                    if (!(token_.kind == Token::Kind::symbol && token_.ch == ','))
                        syntax("expected ')' or ',' in the arguments of " + excerpt(name.text, 40) + ", got " +
                               describe(token_));
                    advance();
                }
            }
            advance();
            if (!function_allowed(name.text, args.size()))
                syntax("no function '" + excerpt(name.text, 40) + "' of " + std::to_string(args.size()) +
                       " argument" + (args.size() == 1 ? "" : "s") + " (a model expression may use " +
                       allowed_functions() + ")");
            return call(name.text, args);
        }
        const auto& params = *scope_.parameters;
        if (const auto it = params.find(name.text); it != params.end()) {
            used_.insert(name.text);
            Estimate e;
            e.v = it->second;
            return e;
        }
        if (name.text == "pi" && scope_.pi_is_constant) {
            pi_at_.push_back(name.pos);
            return constant("Pi");
        }
        throw ExpressionError{
            "expression '" + excerpt(text_) + "': unknown parameter '" + excerpt(name.text, 40) + "'", name.text};
    }

    // ---- the estimates ----

    Estimate apply(char op, const Estimate& a, const Estimate& b) const {
        Estimate r;
        r.exact = a.exact && b.exact;
        switch (op) {
            case '+':
            case '-':
                r.v = op == '+' ? a.v + b.v : a.v - b.v;
                r.integer = a.integer && b.integer;
                r.bits = r.integer ? std::max(a.bits, b.bits) + 1 : a.bits + b.bits + 1;
                break;
            case '*':
                r.v = a.v * b.v;
                r.integer = a.integer && b.integer;
                r.bits = a.bits + b.bits;
                break;
            case '/':
                r.v = b.v == 0 ? NAN : a.v / b.v;
                r.bits = a.bits + b.bits;
                break;
            default:  // '^'
                return power(a, b);
        }
        return checked(r);
    }

    Estimate power(const Estimate& a, const Estimate& b) const {
        Estimate r;
        r.exact = a.exact && b.exact;
        r.integer = a.integer && b.integer && b.v >= 0;
        if (std::isnan(a.v) || std::isnan(b.v)) {
            r.v = NAN;
            return r;
        }
        const long double base = std::fabs(a.v);
        if (base == 0 || base == 1) {
            r.v = base == 0 ? (b.v > 0 ? 0.0L : NAN) : 1.0L;
            r.bits = std::max(a.bits, 1.0);
            return r;
        }
        check_log10(b.v * std::log10(base));  // before computing it, exactly or not
        if (r.exact) r.bits = static_cast<double>(std::fabs(b.v)) * std::max(a.bits, 1.0);
        r.v = std::pow(base, b.v);
        if (a.v < 0 && std::fmod(b.v, 2.0L) != 0 && std::floor(b.v) == b.v) r.v = -r.v;
        return checked(r);
    }

    Estimate call(const std::string& f, const std::vector<Estimate>& args) {
        const Estimate& x = args[0];
        Estimate r;
        if (f == "pow") return power(args[0], args[1]);
        if (f == "abs" || f == "sqrt") {
            r = x;
            r.v = f == "abs" ? std::fabs(x.v) : std::sqrt(std::fabs(x.v));
            r.integer = f == "abs" && x.integer;
            return checked(r);
        }
        if (f == "factorial") {
            if (!std::isnan(x.v) && x.v > 0) check_log10(std::lgamma(x.v + 1) * kLog10E);
            r.exact = r.integer = x.exact;
            if (!std::isnan(x.v) && x.v > 0) r.bits = static_cast<double>(std::lgamma(x.v + 1) * kLog10E * kLog2Of10) + 1;
            r.v = std::isnan(x.v) || x.v < 0 ? NAN : std::tgamma(x.v + 1);
            return checked(r);
        }
        if (f == "exp" || f == "sinh" || f == "cosh") {
            check_log10(std::fabs(x.v) * kLog10E);
            r.v = f == "exp" ? std::exp(x.v) : f == "sinh" ? std::sinh(x.v) : std::cosh(x.v);
            return checked(r);
        }
        if (f == "sin" || f == "cos" || f == "tan") {
            if (!std::isnan(x.v)) trig_ = std::max(trig_, std::fabs(x.v));
            r.v = f == "sin" ? std::sin(x.v) : f == "cos" ? std::cos(x.v) : std::tan(x.v);
            return checked(r);
        }
        if (f == "log") {
            r.v = x.v == 0 ? NAN : std::log(std::fabs(x.v));
            return checked(r);
        }
        if (f == "atan2") {
            r.v = std::atan2(args[0].v, args[1].v);
            return checked(r);
        }
        // asin acos atan tanh asinh acosh atanh: bounded, or complex of a
        // magnitude below log(2|x|) + 2 outside their real domain.
        const long double m = std::fabs(x.v);
        r.v = m <= 1 ? 1.0L : std::log(2 * m) + 2;
        return checked(r);
    }

    const std::string& text_;
    const ExpressionScope& scope_;
    std::size_t pos_ = 0;
    Token token_;
    int depth_ = 0;
    long double trig_ = 0;
    std::set<std::string> used_;
    std::vector<std::size_t> pi_at_;
};

/// The double `d` as the exact GiNaC number it is (no float conversion, so a
/// subnormal never reaches CLN's double-float type, which has none).
GiNaC::numeric exact_number(double d) {
    if (d == 0) return 0;
    int exponent = 0;
    const double mantissa = std::frexp(d, &exponent);  // d = mantissa 2^exponent, 0.5 <= |mantissa| < 1
    const auto integer = static_cast<long>(std::ldexp(mantissa, 53));
    return GiNaC::numeric(integer) * GiNaC::numeric(2).power(exponent - 53);
}

/// The real number `n` rounded to a double; a subnormal result is rounded on
/// the subnormal grid (CLN's own conversion gives 0 there).
double to_double(const GiNaC::numeric& n, const std::string& text) {
    static const GiNaC::numeric smallest_normal = GiNaC::numeric(2).power(-1022);
    if (n.is_zero()) return 0.0;
    const ExpressionError not_finite{"expression '" + excerpt(text) + "' is not a finite double", ""};
    if (GiNaC::abs(n) >= smallest_normal) {
        double d = 0;
        try {
            d = n.to_double();
        } catch (const std::exception&) {  // CLN's floating_point_overflow
            throw not_finite;
        }
        if (!std::isfinite(d)) throw not_finite;
        return d;
    }
    // |n| < 2^-1022: a multiple of 2^-1074 after rounding.
    const double units = std::nearbyint((n * GiNaC::numeric(2).power(1074)).to_double());
    if (units == 0) {
        std::ostringstream value;
        value << GiNaC::ex(n);
        throw ExpressionError{"expression '" + excerpt(text) + "' is " + excerpt(value.str(), 30) +
                                  ", not 0 but below the smallest positive double (4.9e-324)",
                              ""};
    }
    return std::ldexp(units, -1074);
}

}  // namespace

std::string allowed_functions() {
    std::string out;
    for (const auto& [name, arity] : kFunctions) out += (out.empty() ? "" : ", ") + std::string(name);
    return out;
}

EvaluatedExpression evaluate_expression(const std::string& text, const ExpressionScope& scope) {
    PreScan scan(text, scope);
    scan.run();
    EvaluatedExpression result;
    result.canonical_text = scan.canonical_text();

    // sin, cos and tan of x need x to 10^-40 absolutely: 40 digits plus those
    // of the integer part of the largest argument.
    long digits = kEvaluationDigits;
    if (scan.largest_trig_argument() > 1)
        digits += static_cast<long>(std::ceil(std::log10(scan.largest_trig_argument())));
    const DigitsGuard precision(digits);

    GiNaC::ex value;
    try {
        GiNaC::symtab symbols;
        for (const std::string& name : scan.parameters_used())
            symbols[name] = GiNaC::ex(exact_number(scope.parameters->at(name))).evalf();
        GiNaC::parser reader(symbols, /*strict=*/true, allowed_reader());
        value = reader(result.canonical_text).evalf();
    } catch (const GiNaC::parse_error& e) {
        // GiNaC: "GiNaC: parse error at line 0, column 0: REASON\n[where]";
        // the position is always 0 for a one-line string, so keep REASON.
        std::string reason = first_line(e.what());
        const std::string marker = "column 0: ";
        if (const auto at = reason.find(marker); at != std::string::npos) reason = reason.substr(at + marker.size());
        throw ExpressionError{"expression '" + excerpt(text) + "' does not parse: " + excerpt(reason), ""};
    } catch (const std::exception& e) {
        // pole_error ("power::eval(): division by zero"), domain_error, CLN's
        // floating-point exceptions, ...
        throw ExpressionError{"expression '" + excerpt(text) + "' cannot be evaluated: " + excerpt(first_line(e.what())), ""};
    }
    if (!GiNaC::is_a<GiNaC::numeric>(value)) {
        std::ostringstream shown;
        shown << value;
        throw ExpressionError{
            "expression '" + excerpt(text) + "' does not evaluate to a number (got " + excerpt(shown.str()) + ")", ""};
    }
    const GiNaC::numeric& number = GiNaC::ex_to<GiNaC::numeric>(value);
    if (!number.is_real()) {
        std::ostringstream shown;
        shown << number;
        throw ExpressionError{
            "expression '" + excerpt(text) + "' is not a real number (it is " + excerpt(shown.str()) + ")", ""};
    }
    result.value = to_double(number, text);
    return result;
}

}  // namespace hsnc
