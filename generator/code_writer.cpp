#include "code_writer.h"

namespace hsnc {

CodeWriter& CodeWriter::line(int indent, const std::string& text) {
    out_.append(static_cast<std::size_t>(4 * indent), ' ');
    out_ += text;
    out_ += '\n';
    return *this;
}

CodeWriter& CodeWriter::blank() {
    out_ += '\n';
    return *this;
}

CodeWriter& CodeWriter::raw(const std::string& text) {
    out_ += text;
    return *this;
}

CodeWriter& CodeWriter::comment(int indent, const std::string& text) {
    std::size_t start = 0;
    while (start < text.size()) {
        std::size_t end = text.find('\n', start);
        if (end == std::string::npos) end = text.size();
        if (end > start) line(indent, "// " + text.substr(start, end - start));
        start = end + 1;
    }
    return *this;
}

std::string CodeWriter::operand(double v) { return v < 0 ? "(" + format_double(v) + ")" : format_double(v); }

std::string CodeWriter::list(const std::vector<int>& v, const std::string& empty) {
    std::string s;
    for (int x : v) s += (s.empty() ? "" : ", ") + std::to_string(x);
    return s.empty() ? empty : s;
}

std::string CodeWriter::join(const std::vector<std::string>& v, const std::string& separator) {
    std::string s;
    for (std::size_t k = 0; k < v.size(); ++k) s += (k ? separator : "") + v[k];
    return s;
}

}  // namespace hsnc
