#include "expression_printer.h"

#include <algorithm>
#include <sstream>
#include <utility>
#include <vector>

namespace hsnc {
namespace {

using GiNaC::ex;

std::string ginac_text(const ex& e, ExpressionFormat format) {
    std::ostringstream s;
    if (format == ExpressionFormat::latex)
        s << GiNaC::latex << e;
    else
        s << e;
    return s.str();
}

/// Sort rank of a factor: numbers, symbols, powers, functions, sums, the rest.
int rank(const ex& e) {
    if (GiNaC::is_a<GiNaC::numeric>(e)) return 0;
    if (GiNaC::is_a<GiNaC::symbol>(e)) return 1;
    if (GiNaC::is_a<GiNaC::power>(e)) return 2;
    if (GiNaC::is_a<GiNaC::function>(e)) return 3;
    if (GiNaC::is_a<GiNaC::add>(e)) return 4;
    return 5;
}

bool is_negative_number(const ex& e) {
    return GiNaC::is_a<GiNaC::numeric>(e) && GiNaC::ex_to<GiNaC::numeric>(e).is_real() &&
           GiNaC::ex_to<GiNaC::numeric>(e).is_negative();
}

std::string negated(const std::string& term) { return term[0] == '-' ? term.substr(1) : "-" + term; }

class Printer {
public:
    explicit Printer(ExpressionFormat format) : latex_(format == ExpressionFormat::latex), format_(format) {}

    std::string print(const ex& e) const {
        if (GiNaC::is_a<GiNaC::numeric>(e)) return number(GiNaC::ex_to<GiNaC::numeric>(e));
        if (GiNaC::is_a<GiNaC::symbol>(e)) return ginac_text(e, format_);
        if (GiNaC::is_a<GiNaC::add>(e)) return sum(e, false, nullptr);
        if (GiNaC::is_a<GiNaC::mul>(e) || GiNaC::is_a<GiNaC::power>(e)) return product(e);  // a power may go below
        if (GiNaC::is_a<GiNaC::function>(e)) return function(e);
        return ginac_text(e, format_);
    }

private:
    std::string number(const GiNaC::numeric& n) const {
        if (latex_ && n.is_rational() && !n.is_integer()) {
            const std::string sign = n.is_negative() ? "-" : "";
            return sign + "\\frac{" + ginac_text(abs(n.numer()), format_) + "}{" + ginac_text(n.denom(), format_) + "}";
        }
        return ginac_text(n, format_);
    }

    std::string paren(const std::string& s) const { return latex_ ? "\\left(" + s + "\\right)" : "(" + s + ")"; }

    /// The terms of a sum sorted by their text without sign, constants last.
    /// With `normalize`, the first term is made positive by negating all of
    /// them (*flipped says so): GiNaC keeps a sign inside or outside a sum
    /// factor depending on its hash order, which varies from run to run.
    std::string sum(const ex& e, bool normalize, bool* flipped) const {
        std::vector<std::pair<std::string, std::string>> terms;  // (key, text)
        std::vector<std::string> constants;
        for (std::size_t i = 0; i < e.nops(); ++i) {
            const std::string t = print(e.op(i));
            if (GiNaC::is_a<GiNaC::numeric>(e.op(i)))
                constants.push_back(t);
            else
                terms.emplace_back(t[0] == '-' ? t.substr(1) : t, t);
        }
        std::sort(terms.begin(), terms.end());
        for (const std::string& c : constants) terms.emplace_back("", c);
        const bool flip = normalize && !terms.empty() && terms.front().second[0] == '-';
        if (flipped) *flipped = flip;
        std::string out;
        for (const auto& kt : terms) {
            const std::string t = flip ? negated(kt.second) : kt.second;
            if (out.empty())
                out = t;
            else
                out += t[0] == '-' ? (latex_ ? " - " : "-") + t.substr(1) : (latex_ ? " + " : "+") + t;
        }
        return out;
    }

    /// Factors (numbers, symbols, functions, sums, powers) sorted by kind and
    /// text; sums normalised (see sum()), toggling *negate when that pulls out
    /// an odd number of signs. `bare_sum`: a lone sum without parentheses.
    std::string join(const std::vector<ex>& fs, bool* negate, bool bare_sum) const {
        std::vector<std::pair<std::pair<int, std::string>, std::string>> keyed;
        for (const ex& f : fs) {
            std::string t;
            if (GiNaC::is_a<GiNaC::add>(f)) {
                bool fl = false;
                t = sum(f, true, &fl);
                if (fl) *negate = !*negate;
                if (!(bare_sum && fs.size() == 1)) t = paren(t);
            } else if (GiNaC::is_a<GiNaC::power>(f)) {
                t = power(f, negate);
            } else {
                t = print(f);
                if (is_negative_number(f)) t = paren(t);
            }
            keyed.push_back({{rank(f), t}, t});
        }
        std::sort(keyed.begin(), keyed.end());
        std::string out;
        for (const auto& k : keyed) out += (out.empty() ? "" : (latex_ ? " " : "*")) + k.second;
        return out;
    }

    std::string product(const ex& e) const {
        GiNaC::numeric coeff(1);
        std::vector<ex> num, den;
        auto take = [&](const ex& f) {
            if (GiNaC::is_a<GiNaC::numeric>(f))
                coeff *= GiNaC::ex_to<GiNaC::numeric>(f);
            else if (GiNaC::is_a<GiNaC::power>(f) && is_negative_number(f.op(1)))
                den.push_back(GiNaC::pow(f.op(0), -f.op(1)));
            else
                num.push_back(f);
        };
        if (GiNaC::is_a<GiNaC::mul>(e))
            for (std::size_t i = 0; i < e.nops(); ++i) take(e.op(i));
        else
            take(e);
        bool negate = false;
        if (coeff.is_real() && coeff.is_negative()) {
            negate = true;
            coeff = -coeff;
        }
        if (coeff.is_rational() && !coeff.is_integer()) {  // p/q: p joins the numerator, q the denominator
            if (coeff.numer() != 1) num.push_back(coeff.numer());
            den.push_back(coeff.denom());
        } else if (coeff != 1) {
            num.push_back(coeff);
        }
        const std::string top = num.empty() ? "1" : join(num, &negate, latex_ && !den.empty());
        if (den.empty()) return (negate ? "-" : "") + top;
        const std::string bottom = join(den, &negate, latex_);
        const std::string sign = negate ? "-" : "";
        if (latex_) return sign + "\\frac{" + top + "}{" + bottom + "}";
        return sign + top + "/" + (den.size() == 1 ? bottom : paren(bottom));  // a lone sum is in parentheses
    }

    std::string power(const ex& e, bool* negate) const {
        const ex base = e.op(0), expo = e.op(1);
        if (expo == GiNaC::numeric(1, 2)) return latex_ ? "\\sqrt{" + print(base) + "}" : "sqrt(" + print(base) + ")";
        const bool integer_power = GiNaC::is_a<GiNaC::numeric>(expo) && GiNaC::ex_to<GiNaC::numeric>(expo).is_integer();
        std::string b;
        if (GiNaC::is_a<GiNaC::add>(base) && integer_power) {  // (-s)^n = (-1)^n s^n
            bool fl = false;
            b = paren(sum(base, true, &fl));
            if (fl && GiNaC::ex_to<GiNaC::numeric>(expo).is_odd()) *negate = !*negate;
        } else {
            const bool simple = GiNaC::is_a<GiNaC::symbol>(base) || GiNaC::is_a<GiNaC::function>(base) ||
                                (GiNaC::is_a<GiNaC::numeric>(base) && !is_negative_number(base));
            b = simple ? print(base) : paren(print(base));
        }
        if (latex_) return "{" + b + "}^{" + print(expo) + "}";
        const bool simple_expo = GiNaC::is_a<GiNaC::symbol>(expo) ||
                                 (GiNaC::is_a<GiNaC::numeric>(expo) && GiNaC::ex_to<GiNaC::numeric>(expo).is_pos_integer());
        return b + "^" + (simple_expo ? print(expo) : paren(print(expo)));
    }

    std::string function(const ex& e) const {
        const std::string name = GiNaC::ex_to<GiNaC::function>(e).get_name();
        std::string args;
        for (std::size_t i = 0; i < e.nops(); ++i) args += (i ? (latex_ ? ", " : ",") : "") + print(e.op(i));
        if (!latex_) return name + "(" + args + ")";
        if (name == "exp") return "e^{" + args + "}";
        if (name == "abs") return "\\left|" + args + "\\right|";
        if (name == "sin" || name == "cos" || name == "tan" || name == "sinh" || name == "cosh" || name == "log")
            return "\\" + name + paren(args);
        return "\\operatorname{" + name + "}" + paren(args);
    }

    bool latex_;
    ExpressionFormat format_;
};

}  // namespace

std::string print_sorted(const ex& e, ExpressionFormat format) { return Printer(format).print(e); }

}  // namespace hsnc
