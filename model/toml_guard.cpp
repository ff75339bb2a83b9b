// hsnc -- the guard in front of toml++ 3.3 (toml_guard.h): a scan that
// follows toml++'s own tokenisation (toml++/impl/parser.inl: consume_comment,
// parse_string, parse_basic_string, parse_literal_string).
#include "toml_guard.h"

#include <cstdio>
#include <utility>

namespace hsnc {

bool toml_whitespace_lookup_undefined(char32_t c) {
    // is_non_ascii_horizontal_whitespace splits U+00A0..U+FEFF into 64 blocks
    // of 0x3FA code points; blocks 0, 11 and 63 hold only U+00A0, U+3000 and
    // U+FEFF as whitespace, and every other code point of theirs falls through
    // to TOML_UNREACHABLE.
    return (c >= 0xA1 && c <= 0x499) || (c >= 0x2C5E && c <= 0x3057 && c != 0x3000) || (c >= 0xFB26 && c <= 0xFEFE);
}

namespace {

/// What toml++ 3.3 calls horizontal whitespace (is_horizontal_whitespace),
/// for a code point it is defined on.
bool toml_horizontal_whitespace(char32_t c) {
    return c == '\t' || c == ' ' || c == 0xA0 || c == 0x1680 || c == 0x180E || (c >= 0x2000 && c <= 0x200B) ||
           c == 0x202F || c == 0x205F || c == 0x2060 || c == 0x3000 || c == 0xFEFF;
}

/// toml++'s is_whitespace: horizontal or vertical (\n..\r, U+0085, U+2028, U+2029).
bool toml_whitespace(char32_t c) {
    return toml_horizontal_whitespace(c) || (c >= '\n' && c <= '\r') || c == 0x85 || c == 0x2028 || c == 0x2029;
}

std::string code_point_name(char32_t c) {
    char name[16];
    std::snprintf(name, sizeof name, "U+%04X", static_cast<unsigned>(c));
    return name;
}

class Scanner {
public:
    explicit Scanner(std::string_view in) : in_(in) {
        // toml++ skips a leading byte-order mark before it counts positions.
        if (in_.substr(0, 3) == "\xEF\xBB\xBF") i_ = 3;
    }

    TomlGuard run() {
        TomlGuard guard;
        while (i_ < in_.size() && !guard.problem) {
            Char c;
            if (!decode(c)) break;  // invalid UTF-8: toml++ stops there with its own message
            if (c.value >= 0x80) {
                if (toml_whitespace_lookup_undefined(c.value)) {
                    if (state_ == State::bare) {
                        guard.problem = problem(
                            "character " + code_point_name(c.value) + " is not allowed outside strings and comments");
                        break;
                    }
                    if (state_ == State::ml_basic && skipping_) {
                        // The first character after the indentation a line-ending
                        // backslash skips: written as an escape of the same code point.
                        guard.rewrites.push_back({line_, column_});
                        rewrite_at_.push_back({i_, c});
                        skipping_ = false;
                    }
                } else if (state_ == State::ml_basic && skipping_ && !toml_horizontal_whitespace(c.value)) {
                    skipping_ = false;
                } else if (state_ == State::bare) {
                    if (toml_whitespace(c.value)) {
                        numeric_run_ = false;
                    } else {
                        last_significant_ = 'x';  // not one that starts a value
                    }
                }
                step(c);
                continue;
            }
            const char ch = static_cast<char>(c.value);
            switch (state_) {
                case State::bare:
                    if (numeric_run_) {
                        if (!value_terminator(ch)) {
                            last_significant_ = ch;
                            step(c);  // a quote here starts no string
                            break;
                        }
                        if (ch == ' ' && !run_extended_) {
                            // toml++ reads on after one space (a date's time may follow)
                            run_extended_ = true;
                            step(c);
                            break;
                        }
                        numeric_run_ = false;
                    }
                    if (ch != ' ' && ch != '\t' && ch != '\n' && ch != '\r' && ch != '#') {
                        const bool value_start = last_significant_ == '=' || last_significant_ == '[' || last_significant_ == ',';
                        if (value_start && ((ch >= '0' && ch <= '9') || ch == '+' || ch == '-' || ch == '.')) {
                            numeric_run_ = true;
                            run_extended_ = false;
                        }
                        last_significant_ = ch;
                    }
                    if (ch == '#') {
                        state_ = State::comment;
                    } else if (ch == '"' || ch == '\'') {
                        const bool multi_line = at(i_ + 1) == ch && at(i_ + 2) == ch;
                        if (multi_line) {
                            state_ = ch == '"' ? State::ml_basic : State::ml_literal;
                            skipping_ = false;
                            skip_ascii(3);
                            continue;
                        }
                        state_ = ch == '"' ? State::basic : State::literal;
                    }
                    step(c);
                    break;
                case State::comment:
                    if (ch == '\n') state_ = State::bare;
                    step(c);
                    break;
                case State::basic:  // toml++ refuses an unknown escape here without asking about whitespace
                    if (ch == '"' || ch == '\n') state_ = State::bare;
                    step(c);
                    if (ch == '\\' && i_ < in_.size()) {
                        Char escaped;
                        if (!decode(escaped)) break;
                        step(escaped);
                    }
                    break;
                case State::literal:
                    if (ch == '\'' || ch == '\n') state_ = State::bare;
                    step(c);
                    break;
                case State::ml_literal:
                    if (ch == '\'') {
                        close_or_keep_quotes('\'');
                    } else {
                        step(c);
                    }
                    break;
                case State::ml_basic:
                    if (ch == '"') {
                        close_or_keep_quotes('"');
                    } else if (ch == '\\') {
                        step(c);
                        skipping_ = false;
                        escape(guard);
                    } else {
                        // A line break keeps skipping; any other character but a
                        // space or tab ends it (control characters: toml++ refuses).
                        if (skipping_ && !(ch >= '\n' && ch <= '\r') && !toml_horizontal_whitespace(c.value))
                            skipping_ = false;
                        step(c);
                    }
                    break;
            }
        }
        return finish(std::move(guard));
    }

private:
    enum class State { bare, comment, basic, literal, ml_basic, ml_literal };
    struct Char {
        char32_t value = 0;
        std::size_t bytes = 0;
    };

    /// toml++'s is_value_terminator, for an ASCII character.
    static bool value_terminator(char ch) {
        return ch == ' ' || ch == '\t' || (ch >= '\n' && ch <= '\r') || ch == ']' || ch == '}' || ch == ',' || ch == '#';
    }

    char at(std::size_t i) const { return i < in_.size() ? in_[i] : '\0'; }

    /// The code point at i_ (strict UTF-8, as toml++'s decoder: no overlong
    /// forms, no surrogates, nothing above U+10FFFF). False when invalid or cut off.
    bool decode(Char& c) const {
        const auto byte = [&](std::size_t k) { return static_cast<unsigned char>(at(i_ + k)); };
        const unsigned b0 = byte(0);
        std::size_t n;
        unsigned lo = 0x80, hi = 0xBF;  // range of the second byte
        if (b0 < 0x80) {
            c = {b0, 1};
            return true;
        } else if (b0 >= 0xC2 && b0 <= 0xDF) {
            n = 2;
        } else if (b0 >= 0xE0 && b0 <= 0xEF) {
            n = 3;
            if (b0 == 0xE0) lo = 0xA0;
            if (b0 == 0xED) hi = 0x9F;
        } else if (b0 >= 0xF0 && b0 <= 0xF4) {
            n = 4;
            if (b0 == 0xF0) lo = 0x90;
            if (b0 == 0xF4) hi = 0x8F;
        } else {
            return false;
        }
        if (i_ + n > in_.size()) return false;
        char32_t value = b0 & (0xFFu >> (n + 1));
        for (std::size_t k = 1; k < n; ++k) {
            const unsigned b = byte(k);
            if (k == 1 ? (b < lo || b > hi) : (b < 0x80 || b > 0xBF)) return false;
            value = (value << 6) | (b & 0x3Fu);
        }
        c = {value, n};
        return true;
    }

    void step(const Char& c) {
        i_ += c.bytes;
        if (c.value == '\n') {
            ++line_;
            column_ = 1;
        } else {
            ++column_;
        }
    }

    void skip_ascii(std::size_t count) {
        for (std::size_t k = 0; k < count; ++k) step(Char{static_cast<unsigned char>(at(i_)), 1});
    }

    /// A run of `quote` in a multi-line string: three or more close it (toml++
    /// takes up to five: one or two of them belong to the string), fewer are text.
    void close_or_keep_quotes(char quote) {
        std::size_t run = 0;
        while (run < 5 && at(i_ + run) == quote) ++run;
        skip_ascii(run);
        if (run >= 3) state_ = State::bare;
        if (quote == '"') skipping_ = false;
    }

    /// After a backslash in a multi-line basic string (toml++ asks is_whitespace
    /// about the next code point, and after whitespace about each one up to the
    /// line break).
    void escape(TomlGuard& guard) {
        Char c;
        if (i_ >= in_.size() || !decode(c)) return;
        if (toml_whitespace_lookup_undefined(c.value)) {
            guard.problem = problem("a backslash followed by " + code_point_name(c.value) +
                                    " is not an escape sequence");
            return;
        }
        if (!toml_whitespace(c.value)) {  // an escape sequence: its first character
            step(c);
            return;
        }
        // A line-ending backslash: spaces and tabs, then the line break.
        while (i_ < in_.size()) {
            if (!decode(c)) return;
            if (toml_whitespace_lookup_undefined(c.value)) {
                guard.problem = problem("after a line-ending backslash only spaces and tabs may follow on its line, not " +
                                        code_point_name(c.value));
                return;
            }
            if (!toml_horizontal_whitespace(c.value)) break;
            step(c);
        }
        if (at(i_) == '\n') {
            skip_ascii(1);
            skipping_ = true;
        } else if (at(i_) == '\r' && at(i_ + 1) == '\n') {
            skip_ascii(2);
            skipping_ = true;
        }
        // otherwise toml++ refuses the backslash; the scan goes on as text
    }

    TomlGuard::Problem problem(std::string description) const { return {line_, column_, std::move(description)}; }

    /// The text toml++ may parse: the input with the rewrites.
    TomlGuard finish(TomlGuard guard) const {
        if (guard.problem) {
            guard.rewrites.clear();
            return guard;
        }
        std::size_t from = 0;
        guard.text.reserve(in_.size() + 5 * rewrite_at_.size());
        for (const auto& [offset, c] : rewrite_at_) {
            guard.text.append(in_.data() + from, offset - from);
            char escape[8];
            std::snprintf(escape, sizeof escape, "\\u%04X", static_cast<unsigned>(c.value));
            guard.text += escape;
            from = offset + c.bytes;
        }
        guard.text.append(in_.data() + from, in_.size() - from);
        return guard;
    }

    std::string_view in_;
    std::size_t i_ = 0;
    std::size_t line_ = 1, column_ = 1;
    State state_ = State::bare;
    bool skipping_ = false;  ///< in the indentation a line-ending backslash skips
    // Outside strings and comments: the last character that was not whitespace
    // (comments skipped), and whether the current token is a value toml++ scans
    // ahead in before it parses it.
    char last_significant_ = '\0';
    bool numeric_run_ = false, run_extended_ = false;
    std::vector<std::pair<std::size_t, Char>> rewrite_at_;  ///< byte offset and code point of each rewrite
};

}  // namespace

std::size_t TomlGuard::original_column(std::size_t line, std::size_t column) const {
    // Each rewrite puts six code points (\uXXXX) where the input had one.
    std::size_t shift = 0;
    for (const Rewrite& r : rewrites) {
        if (r.line != line) continue;
        const std::size_t start = r.column + shift;  // of the backslash, in the text
        if (column < start) break;
        if (column <= start + 5) return r.column;
        shift += 5;
    }
    return column - shift;
}

TomlGuard guard_toml_text(std::string_view text) { return Scanner(text).run(); }

}  // namespace hsnc
