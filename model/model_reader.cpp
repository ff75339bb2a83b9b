// hsnc -- reading a model file: TOML (toml++) in, a validated Model out.
//
// The reader walks the document once, in a fixed order: parameters first
// (each one evaluated with only the earlier ones in scope), then masses,
// because every later table refers to them by name, then the rest. Every
// table is checked against the keys it may hold, so a typo is an error and
// never a silently ignored key (interface.md section 1).
#include "model_reader.h"

#include <algorithm>
#include <cerrno>
#include <cfloat>
#include <cmath>
#include <complex>
#include <cstdio>
#include <cstring>
#include <functional>
#include <map>
#include <optional>
#include <sstream>
#include <unordered_map>

#include <Eigen/Eigenvalues>
#include <toml++/toml.h>

#include "error.h"
#include "expression_evaluator.h"
#include "file_read.h"
#include "input_files.h"
#include "ginac_lock.h"
#include "mat_file.h"
#include "matrix_market.h"
#include "reduction.h"
#include "structure.h"
#include "toml_guard.h"

namespace hsnc {

bool is_valid_name(const std::string& name) {
    auto alpha = [](char c) { return (c >= 'A' && c <= 'Z') || (c >= 'a' && c <= 'z') || c == '_'; };
    auto digit = [](char c) { return c >= '0' && c <= '9'; };
    if (name.empty() || !alpha(name[0])) return false;
    return std::all_of(name.begin() + 1, name.end(), [&](char c) { return alpha(c) || digit(c); });
}

namespace {

constexpr double kDefaultGravity = 9.81;

// Names the GiNaC parser resolves itself before looking at the symbol table;
// a parameter of that name could never be referred to.
const char* const kParserConstants[] = {"Pi", "Euler", "Catalan", "I"};

std::string type_name(const toml::node& node) {
    std::ostringstream out;
    out << node.type();
    return out.str();
}

/// Split a flag value "NAME=VALUE" (at the first '='). Throws InputError.
std::pair<std::string, std::string> split_assignment(const std::string& flag, const std::string& raw) {
    const auto eq = raw.find('=');
    if (eq == std::string::npos) throw InputError(flag + " '" + excerpt(raw) + "': expected NAME=VALUE");
    std::string name = raw.substr(0, eq), value = raw.substr(eq + 1);
    if (!is_valid_name(name))
        throw InputError(flag + " '" + excerpt(raw) + "': '" + excerpt(name) + "' is not a valid name ([A-Za-z_][A-Za-z0-9_]*)");
    if (value.find_first_not_of(" \t") == std::string::npos)
        throw InputError(flag + " '" + excerpt(raw) + "': expected NAME=VALUE, VALUE is empty");
    return {name, value};
}

/// One override flag, split, and the raw text for messages.
struct Override {
    std::string flag;   ///< "--set", "--x0", "--v0"
    std::string raw;    ///< "NAME=VALUE" as given
    std::string value;  ///< VALUE
};

/// Split a list of override flags into NAME -> Override; a name given twice is an error.
std::map<std::string, Override> collect_overrides(const std::string& flag, const std::vector<std::string>& raws) {
    std::map<std::string, Override> out;
    for (const std::string& raw : raws) {
        auto [name, value] = split_assignment(flag, raw);
        if (out.count(name))
            throw InputError(flag + " '" + excerpt(raw) + "': '" + excerpt(name) + "' is already set by " + flag +
                             " '" + excerpt(out.at(name).raw) + "'");
        out.emplace(name, Override{flag, raw, value});
    }
    return out;
}

/// Reads one parsed TOML document into a Model. One instance per document.
class Reader {
public:
    Reader(std::string source, const ModelOverrides& overrides)
        : source_(std::move(source)), t_end_override_(overrides.t_end), full_frequencies_(overrides.full_frequencies) {
        set_ = collect_overrides("--set", overrides.set);
        x0_ = collect_overrides("--x0", overrides.x0);
        v0_ = collect_overrides("--v0", overrides.v0);
    }

    Model read(const toml::table& root) {
        model_.source = source_;
        check_keys(root, "",
                   {"name", "description", "parameters", "mass", "structure", "spring", "damping", "damper", "contact",
                    "friction", "jenkins", "forcing", "base", "load", "load_step", "initial", "simulate", "reduction"});
        model_.name = required_string(root, "", "name");
        if (model_.name.empty()) fail(root.get("name"), "name", "must not be empty");
        if (const toml::node* d = root.get("description")) model_.description = string_value(*d, "description");

        read_parameters(root);
        if (root.get("structure"))
            read_structure(root);
        else
            read_masses(root);
        if (root.get("reduction") && !root.get("structure"))
            fail(root.get("reduction"), "reduction", "reduces a [structure]; this model has none");
        read_springs(root);
        add_structure_springs();
        read_damping(root);
        read_dampers(root);
        read_contacts(root);
        read_frictions(root);
        read_jenkins(root);
        read_forcing(root);
        read_base(root);
        read_load(root);
        read_initial(root);
        check_rigid_stops(root);
        read_load_steps(root);
        check_finite_rates(root);
        if (full_M_) compare_reduction(), compare_responses();
        read_simulate(root);
        if (t_end_override_) {
            const double t_end = *t_end_override_;
            if (!std::isfinite(t_end) || !(t_end > model_.t0))
                throw InputError("--t-end " + show(t_end, 17) + ": must be finite and after t0 = " + show(model_.t0, 17));
            model_.t_end = t_end;
        }
        return std::move(model_);
    }

private:
    // ---- messages: "FILE:LINE: key 'KEY': reason" ----

    [[noreturn]] void fail(const toml::node* where, const std::string& key, const std::string& reason) const {
        fail_at(where ? where->source().begin.line : 0, key, reason);
    }
    [[noreturn]] void fail_at(std::size_t line, const std::string& key, const std::string& reason) const {
        std::string message = source_;
        if (line > 0) message += ":" + std::to_string(line);
        message += ": key '" + excerpt(key, 120) + "': " + reason;
        throw InputError(message);
    }
    /// The line of a table's own header, or 0 for the document root (line 1
    /// there would point at whatever happens to be first in the file).
    std::size_t table_line(const toml::table& table, const std::string& path) const {
        return path.empty() ? 0 : table.source().begin.line;
    }
    static std::string join(const std::string& path, const std::string& key) {
        return path.empty() ? key : path + "." + key;
    }

    // ---- structure ----

    /// Every key of `table` must be one of `allowed`.
    void check_keys(const toml::table& table, const std::string& path, std::initializer_list<const char*> allowed) const {
        for (auto&& [key, node] : table) {
            const std::string name(key.str());
            if (std::find(allowed.begin(), allowed.end(), name) != allowed.end()) continue;
            std::string expected;
            for (const char* a : allowed) expected += (expected.empty() ? "" : ", ") + std::string(a);
            fail_at(key.source().begin.line ? key.source().begin.line : node.source().begin.line, join(path, name),
                    "unknown key (expected one of: " + expected + ")");
        }
    }

    const toml::table* optional_table(const toml::table& parent, const std::string& path, const char* key) const {
        const toml::node* node = parent.get(key);
        if (!node) return nullptr;
        if (!node->is_table()) fail(node, join(path, key), "expected a table, got " + type_name(*node));
        return node->as_table();
    }

    /// The tables of an array of tables ([[key]]); empty when absent.
    std::vector<const toml::table*> table_array(const toml::table& root, const char* key) const {
        std::vector<const toml::table*> out;
        const toml::node* node = root.get(key);
        if (!node) return out;
        const toml::array* array = node->as_array();
        if (!array)
            fail(node, key, std::string("expected an array of tables [[") + key + "]], got " + type_name(*node));
        for (const toml::node& item : *array) {
            if (!item.is_table())
                fail(&item, key, std::string("expected an array of tables [[") + key + "]], got an element of type " +
                                     type_name(item));
            out.push_back(item.as_table());
        }
        return out;
    }

    std::string string_value(const toml::node& node, const std::string& key) const {
        if (!node.is_string()) fail(&node, key, "expected a string, got " + type_name(node));
        return node.as_string()->get();
    }

    std::string required_string(const toml::table& table, const std::string& path, const char* key) const {
        const toml::node* node = table.get(key);
        if (!node) fail_at(table_line(table, path), join(path, key), "required key is missing");
        return string_value(*node, join(path, key));
    }

    // ---- numbers and expressions ----

    /// A TOML integer, a finite float, or an expression string over the parameters.
    /// The source text is recorded in Model::field_expressions (parameters in
    /// Model::parameter_expressions) under `key`.
    double number(const toml::node& node, const std::string& key) {
        const bool is_parameter = key.rfind("parameters.", 0) == 0;
        if (const auto* i = node.as_integer()) {
            if (!is_parameter) model_.field_expressions[key] = std::to_string(i->get());
            return static_cast<double>(i->get());
        }
        if (const auto* f = node.as_floating_point()) {
            if (!std::isfinite(f->get())) fail(&node, key, "must be finite, got " + std::string(std::isnan(f->get()) ? "nan" : "inf"));
            if (is_subnormal(f->get())) fail(&node, key, subnormal_reason(f->get()));
            if (!is_parameter) model_.field_expressions[key] = literal_text(f->get());
            return f->get();
        }
        if (const auto* s = node.as_string()) {
            EvaluatedExpression e;
            try {
                e = evaluate_expression(s->get(), scope());
            } catch (const ExpressionError& error) {
                fail(&node, key, explain(error));
            }
            if (is_subnormal(e.value)) fail(&node, key, subnormal_reason(e.value));
            (is_parameter ? parameter_text_ : model_.field_expressions[key]) = e.canonical_text;
            return e.value;
        }
        fail(&node, key, "expected a number or an expression string, got " + type_name(node));
    }

    /// A float literal as the shortest text that reads back to the same double.
    static std::string literal_text(double v) {
        char buf[40];
        for (int digits = 1; digits <= 17; ++digits) {
            std::snprintf(buf, sizeof buf, "%.*g", digits, v);
            if (std::strtod(buf, nullptr) == v) break;
        }
        return buf;
    }

    /// The source text of parameter node (for Model::parameter_expressions),
    /// once number() has read it: an expression as evaluate_expression() wrote it.
    std::string source_text(const toml::node& node) const {
        if (const auto* i = node.as_integer()) return std::to_string(i->get());
        if (const auto* f = node.as_floating_point()) return literal_text(f->get());
        return parameter_text_;
    }

    /// The names an expression may use now: the parameters so far, and pi
    /// unless the file names a parameter so.
    ExpressionScope scope() const {
        ExpressionScope s;
        s.parameters = &values_;
        s.pi_is_constant = pi_is_constant_;
        return s;
    }

    /// An expression error, with a hint when the unknown name is a later parameter.
    std::string explain(const ExpressionError& e) const {
        if (!e.unknown_symbol.empty() &&
            std::find(parameter_names_.begin(), parameter_names_.end(), e.unknown_symbol) != parameter_names_.end())
            return e.reason + " (it is defined later; a parameter may use only earlier parameters)";
        return e.reason;
    }

    EvaluatedExpression override_value(const Override& o) const {
        EvaluatedExpression e;
        try {
            e = evaluate_expression(o.value, scope());
        } catch (const ExpressionError& error) {
            throw InputError(o.flag + " '" + excerpt(o.raw) + "': " + explain(error));
        }
        if (is_subnormal(e.value)) throw InputError(o.flag + " '" + excerpt(o.raw) + "': " + subnormal_reason(e.value));
        return e;
    }

    // Subnormal doubles (0 < |v| < 2^-1022) are refused: the symbolic
    // derivation's numbers (CLN's double-float) have none, and a value that
    // small is no physical model's. The message says so instead of CLN's
    // "floating point underflow".
    static bool is_subnormal(double v) { return v != 0.0 && std::fabs(v) < DBL_MIN; }
    static std::string subnormal_reason(double v) {
        return "value " + show(v, 17) + " is a subnormal double (magnitude below 2.2250738585072014e-308), too " +
               "small to compute with; write 0 or a magnitude of at least 2.2250738585072014e-308";
    }

    std::optional<double> optional_number(const toml::table& table, const std::string& path, const char* key) {
        const toml::node* node = table.get(key);
        if (!node) return std::nullopt;
        return number(*node, join(path, key));
    }

    double required_number(const toml::table& table, const std::string& path, const char* key) {
        const toml::node* node = table.get(key);
        if (!node) fail_at(table_line(table, path), join(path, key), "required key is missing");
        return number(*node, join(path, key));
    }

    // ---- names and bodies ----

    /// A name for a mass or contact: valid syntax, not reserved, not taken.
    /// `prefix` starts each message (a dof file's "FILE:LINE: ").
    void check_new_name(const toml::node* where, const std::string& key, const std::string& name,
                        const std::string& prefix = "") const {
        if (!is_valid_name(name))
            fail(where, key, prefix + "'" + excerpt(name) + "' is not a valid name ([A-Za-z_][A-Za-z0-9_]*)");
        if (name == "ground") fail(where, key, prefix + "'ground' is reserved for the fixed ground");
        if (const auto taken = element_names_.find(name); taken != element_names_.end())
            fail(where, key, prefix + "name '" + excerpt(name) + "' is already used by " + taken->second);
    }

    /// A massless dof of [structure], condensed statically.
    bool condensed(const std::string& name) const {
        const Condensation& c = model_.condensation;
        for (std::size_t d = 0; d < c.dofs.size(); ++d)
            if (c.dofs[d] == name && c.mass[d] < 0) return true;
        return false;
    }
    static std::string condensed_message(const std::string& name) {
        return "'" + name + "' is a massless dof (a zero row of M), condensed statically: an element or an "
               "initial value cannot name it (give it a mass, or act on a dof with mass; a load or forcing may)";
    }
    /// The row of condensed dof `name` in Condensation::recovery, or -1.
    int condensed_row(const std::string& name) const {
        const Condensation& c = model_.condensation;
        int row = 0;
        for (std::size_t d = 0; d < c.dofs.size(); ++d) {
            if (c.mass[d] >= 0) continue;
            if (c.dofs[d] == name) return row;
            ++row;
        }
        return -1;
    }
    /// Forces f_c given on condensed dofs, carried by the dofs with mass as
    /// R^T f_c (static condensation: K_cc x_c + K_cm x_m = f_c).
    void fold_condensed(const std::vector<double>& fc, std::vector<double>& f) const {
        const Condensation& c = model_.condensation;
        const std::size_t n = model_.dof();
        for (std::size_t r = 0; r < fc.size(); ++r)
            if (fc[r] != 0.0)
                for (std::size_t j = 0; j < n; ++j) f[j] += c.recovery[r * n + j] * fc[r];
    }

    /// Mass name -> index; `kGround` for "ground".
    int body(const toml::node& node, const std::string& key) const {
        const std::string name = string_value(node, key);
        if (name == "ground") return kGround;
        const int i = model_.mass_index(name);
        if (i < 0 && condensed(name)) fail(&node, key, condensed_message(name));
        if (i < 0)
            fail(&node, key, "unknown body '" + excerpt(name) + "' (expected 'ground' or a " + body_word() + " name)");
        return i;
    }

    /// `between = [a, b]`: two distinct bodies.
    std::pair<int, int> between(const toml::table& table, const std::string& path) const {
        const std::string key = join(path, "between");
        const toml::node* node = table.get("between");
        if (!node) fail_at(table_line(table, path), key, "required key is missing");
        const toml::array* pair = node->as_array();
        if (!pair || pair->size() != 2)
            fail(node, key, "expected a list of two body names, e.g. [\"ground\", \"m1\"]");
        const int a = body(*pair->get(0), key), b = body(*pair->get(1), key);
        if (a == b)
            fail(node, key, "connects '" + (a == kGround ? std::string("ground") : model_.masses[a].name) +
                                "' to itself");
        return {a, b};
    }

    /// `direction = { dof = w, ... }`: u = sum w_i x_i over dofs with mass,
    /// each weight finite and non-zero (toml++ keeps the keys sorted by name:
    /// the terms come in that order).
    std::vector<Weight> direction(const toml::node& node, const std::string& key) {
        const toml::table* table = node.as_table();
        if (!table || table->empty())
            fail(&node, key, "expected a table of " + body_word() + " names and weights, e.g. { th3 = -0.05, th4 = 0.05 }");
        std::vector<Weight> terms;
        for (auto&& [k, v] : *table) {
            const std::string name(k.str());
            const std::string at = join(key, name);
            if (name == "ground") fail_at(k.source().begin.line, at, "the ground does not move: leave it out of a direction");
            const int i = model_.mass_index(name);
            if (i < 0 && condensed(name)) fail_at(k.source().begin.line, at, condensed_message(name));
            if (i < 0) fail_at(k.source().begin.line, at, "unknown " + body_word() + " '" + excerpt(name) + "'");
            const double w = number(v, at);
            if (w == 0.0) fail(&v, at, "a weight of 0 (leave the " + body_word() + " out)");
            terms.push_back({i, w});
        }
        return terms;
    }

    /// A table mass-name -> number (load, amplitude, initial x and v): one entry per mass, 0 when absent.
    /// With `on_condensed` (a force), a condensed dof's value goes there, by its row.
    std::vector<double> per_mass(const toml::node& node, const std::string& key,
                                 std::vector<double>* on_condensed = nullptr) {
        if (!node.is_table())
            fail(&node, key, "expected a table of " + body_word() + " names, e.g. { m1 = 1.0 }, got " + type_name(node));
        std::vector<double> values(model_.dof(), 0.0);
        if (on_condensed) on_condensed->assign(model_.condensation.condensed(), 0.0);
        for (auto&& [k, v] : *node.as_table()) {
            const std::string name(k.str());
            const int i = model_.mass_index(name);
            if (i < 0 && on_condensed && condensed(name)) {
                (*on_condensed)[static_cast<std::size_t>(condensed_row(name))] = number(v, join(key, name));
                continue;
            }
            if (i < 0 && condensed(name)) fail_at(k.source().begin.line, join(key, name), condensed_message(name));
            if (i < 0) fail_at(k.source().begin.line, join(key, name), "unknown " + body_word() + " '" + excerpt(name) + "'");
            values[i] = number(v, join(key, name));
        }
        return values;
    }

    // ---- sections, in the order they are read ----

    void read_parameters(const toml::table& root) {
        // toml++ keeps a table's keys sorted by name; file order is source order.
        std::vector<std::pair<std::string, const toml::node*>> entries;
        if (const toml::table* params = optional_table(root, "", "parameters")) {
            for (auto&& [k, v] : *params) entries.emplace_back(std::string(k.str()), &v);
            std::sort(entries.begin(), entries.end(), [](const auto& a, const auto& b) {
                const auto pa = a.second->source().begin, pb = b.second->source().begin;
                return pa.line != pb.line ? pa.line < pb.line : pa.column < pb.column;
            });
        }
        for (const auto& [name, node] : entries) parameter_names_.push_back(name);
        const bool implicit_g = std::find(parameter_names_.begin(), parameter_names_.end(), "g") == parameter_names_.end();
        if (implicit_g) parameter_names_.insert(parameter_names_.begin(), "g");
        pi_is_constant_ = std::find(parameter_names_.begin(), parameter_names_.end(), "pi") == parameter_names_.end();

        for (const auto& [name, o] : set_)
            if (std::find(parameter_names_.begin(), parameter_names_.end(), name) == parameter_names_.end())
                throw InputError("--set '" + excerpt(o.raw) + "': no parameter named '" + excerpt(name) + "'");

        if (implicit_g) define_parameter("g", nullptr);
        for (const auto& [name, node] : entries) define_parameter(name, node);

        for (const auto& [name, value] : model_.parameters)
            if (name == "g") model_.g = value;
    }

    /// Evaluate parameter `name` (from the file, or from --set) with the
    /// parameters before it in scope, then bring it into scope.
    void define_parameter(const std::string& name, const toml::node* node) {
        const std::string key = "parameters." + name;
        if (!is_valid_name(name)) fail(node, key, "'" + excerpt(name) + "' is not a valid name ([A-Za-z_][A-Za-z0-9_]*)");
        if (name == "ground") fail(node, key, "'ground' is reserved for the fixed ground");
        for (const char* reserved : kParserConstants)
            if (name == reserved) fail(node, key, "'" + name + "' is a constant of the expression parser and cannot be a parameter");
        double value = kDefaultGravity;
        std::string text = "9.81";
        const auto o = set_.find(name);
        if (o != set_.end()) {
            const EvaluatedExpression e = override_value(o->second);
            value = e.value;
            text = e.canonical_text;
        } else if (node) {
            value = number(*node, key);
            text = source_text(*node);
        }
        // The normal force of friction is m*g (interface.md section 2).
        if (name == "g" && !(value > 0.0)) {
            const std::string reason = "gravity g must be > 0 (friction's normal force is m*g), got " + show(value);
            if (o != set_.end()) throw InputError(o->second.flag + " '" + excerpt(o->second.raw) + "': " + reason);
            fail(node, key, reason);
        }
        model_.parameters.emplace_back(name, value);
        model_.parameter_expressions.emplace_back(name, text);
        values_[name] = value;
    }

    /// The model size limit (matrix_market.h kMaxMatrixDimension), said once for masses and dofs.
    static std::string too_many_dofs(std::size_t n) {
        return std::to_string(n) + " degrees of freedom, more than the " + std::to_string(kMaxMatrixDimension) +
               " hsnc takes for now: its matrices are dense and its modal analysis is cubic in the dofs (at " +
               std::to_string(kMaxMatrixDimension) + " dofs, check takes under a second and simulate seconds per "
               "configuration; at 10000 check would take hours and gigabytes)";
    }

    /// What a body other than ground is called in messages.
    std::string body_word() const { return model_.structure.present ? "dof" : "mass"; }

    /// A path of the model file, relative to the model file's folder (or as given when absolute).
    std::string beside_model(const std::string& path) const {
        if (!path.empty() && path[0] == '/') return path;
        const auto slash = source_.rfind('/');
        return slash == std::string::npos ? path : source_.substr(0, slash + 1) + path;
    }

    /// A matrix file named by key `key` of [structure]; its errors name the key and the file.
    /// structure.KEY's file, its name checked and noted as an input of the
    /// run: read_mat(FILE, VARIABLE) reads a .mat variable, read_market(PATH)
    /// a Matrix Market file; their errors are named by the key.
    template <class ReadMat, class ReadMarket>
    auto structure_matrix(const toml::table& t, const char* key, std::string& written, ReadMat read_mat,
                          ReadMarket read_market) {
        const std::string path = "structure." + std::string(key);
        written = required_string(t, "structure", key);
        if (written.empty()) fail(t.get(key), path, "must name a Matrix Market or .mat file");
        if (written.find('\0') != std::string::npos)  // the file system would read the path up to the NUL only
            fail(t.get(key), path, "'" + excerpt(written) + "': a path cannot hold a NUL character");
        try {
            if (is_mat_spec(written)) {  // "x.mat:VAR", or "x.mat" with variable M, K or C
                const char* letter = std::string(key) == "mass" ? "M" : std::string(key) == "stiffness" ? "K" : "C";
                const auto [file, variable] = split_mat_spec(written, letter);
                note_input_file(beside_model(file));  // no output of the run may replace it
                return read_mat(beside_model(file), variable);
            }
            note_input_file(beside_model(written));
            return read_market(beside_model(written));
        } catch (const InputError& e) {
            fail(t.get(key), path, e.what());
        }
    }

    MarketMatrix matrix_file(const toml::table& t, const char* key, std::string& written) {
        return structure_matrix(t, key, written, read_mat_variable, read_matrix_market);
    }

    /// A [structure] matrix that [reduction] reduces: read sparse, n x n for
    /// the n dofs, symmetric to 1e-12 of its largest entry (used as (A + A^T)/2).
    SparseMatrixD sparse_matrix_file(const toml::table& t, const char* key, std::string& written, std::size_t n) {
        const std::string path = "structure." + std::string(key);
        const SparseMarket m = structure_matrix(
            t, key, written,
            [](const std::string& file, const std::string& variable) {  // .mat files are read dense (up to 500 rows)
                const MarketMatrix d = read_mat_variable(file, variable);
                SparseMarket s;
                s.rows = d.rows, s.cols = d.cols;
                for (std::size_t i = 0; i < d.rows; ++i)
                    for (std::size_t j = 0; j < d.cols; ++j)
                        if (d(i, j) != 0.0) s.entries.emplace_back(static_cast<int>(i), static_cast<int>(j), d(i, j));
                return s;
            },
            read_sparse_matrix_market);
        if (m.rows != n || m.cols != n)
            fail(t.get(key), path, written + ": is " + std::to_string(m.rows) + " x " + std::to_string(m.cols) +
                                       ", the structure has " + std::to_string(n) + " dofs");
        SparseMatrixD A(static_cast<int>(n), static_cast<int>(n));
        A.setFromTriplets(m.entries.begin(), m.entries.end());
        const SparseMatrixD At = A.transpose();
        const SparseMatrixD asym = A - At;
        double largest = 0.0, off = 0.0;
        for (const auto& e : m.entries) largest = std::max(largest, std::fabs(e.value()));
        for (int c = 0; c < asym.outerSize(); ++c)
            for (SparseMatrixD::InnerIterator it(asym, c); it; ++it) off = std::max(off, std::fabs(it.value()));
        if (off > 1e-12 * largest)
            fail(t.get(key), path, written + ": is not symmetric (|A - A^T| up to " + show(off) + ", largest |entry| " +
                                       show(largest) + ")");
        return (A + At) / 2.0;
    }

    /// The dofs a [reduction] keeps physical: every dof name the model's
    /// tables use (as a value or as a key: elements, loads, forcing, initial
    /// values, directions) and those of reduction.boundary, in dof order.
    std::vector<std::size_t> boundary_dofs(const toml::table& root, const std::vector<std::string>& names) {
        std::unordered_map<std::string, std::size_t> index;
        for (std::size_t i = 0; i < names.size(); ++i) index.emplace(names[i], i);
        std::vector<char> named(names.size(), 0);
        auto mark = [&](const std::string& s) {
            if (const auto it = index.find(s); it != index.end()) named[it->second] = 1;
        };
        std::function<void(const toml::node&)> walk = [&](const toml::node& node) {
            if (const auto* str = node.as_string()) mark(str->get());
            if (const auto* tab = node.as_table())
                for (auto&& [k, v] : *tab) mark(std::string(k.str())), walk(v);
            if (const auto* arr = node.as_array())
                for (const toml::node& v : *arr) walk(v);
        };
        for (auto&& [k, v] : root) {
            if (k.str() == "base" && v.is_array()) {  // a base motion's direction acts through M on every dof
                for (const toml::node& b : *v.as_array())
                    if (const auto* tab = b.as_table())
                        for (auto&& [bk, bv] : *tab)
                            if (bk.str() != "direction") walk(bv);
                continue;
            }
            if (k.str() != "structure" && k.str() != "parameters" && k.str() != "name" && k.str() != "description")
                walk(v);
        }
        std::vector<std::size_t> out;
        for (std::size_t i = 0; i < names.size(); ++i)
            if (named[i]) out.push_back(i);
        return out;
    }

    /// M r of each [[base]] over the full structure (a column each; r, kept
    /// in base_r_, from its `direction`, which may name any dof of the
    /// structure, the interior included: a rigid translation moves every
    /// dof). Read before the
    /// reduction removes the interior; a missing `direction` is left for
    /// read_base to refuse.
    Eigen::MatrixXd base_influence(const toml::table& root, const std::vector<std::string>& names,
                                   const SparseMatrixD& M) {
        const auto tables = table_array(root, "base");
        std::unordered_map<std::string, std::size_t> index;
        for (std::size_t i = 0; i < names.size(); ++i) index.emplace(names[i], i);
        Eigen::MatrixXd R =
            Eigen::MatrixXd::Zero(static_cast<Eigen::Index>(names.size()), static_cast<Eigen::Index>(tables.size()));
        for (std::size_t j = 0; j < tables.size(); ++j) {
            const std::string key = "base[" + std::to_string(j + 1) + "].direction";
            const toml::node* d = tables[j]->get("direction");
            if (!d) continue;
            const toml::table* table = d->as_table();
            if (!table || table->empty())
                fail(d, key, "expected a table of dof names and weights, e.g. { u1 = 1.0, u2 = 1.0 }");
            for (auto&& [k, v] : *table) {
                const std::string name(k.str()), at = join(key, name);
                const auto it = index.find(name);
                if (it == index.end())
                    fail_at(k.source().begin.line, at, "'" + excerpt(name) + "' is not a dof of the structure");
                const double w = number(v, at);
                if (w == 0.0) fail(&v, at, "a weight of 0 (leave the dof out)");
                R(static_cast<Eigen::Index>(it->second), static_cast<Eigen::Index>(j)) = w;
            }
        }
        base_r_ = R;
        return M * R;
    }

    /// [reduction]: the structure's matrices read sparse and reduced
    /// (reduction.h); M, K, C and `names` become the reduced model's.
    void reduce_structure(const toml::table& root, const toml::table& t, std::vector<std::string>& names,
                          MarketMatrix& M, MarketMatrix& K, std::optional<MarketMatrix>& C) {
        const toml::table* r = optional_table(root, "", "reduction");
        check_keys(*r, "reduction", {"method", "modes", "cutoff", "boundary", "prefix"});
        ReductionSource& red = model_.reduction;
        red.present = true;
        red.method = "craig-bampton";
        if (const toml::node* m = r->get("method")) {
            red.method = string_value(*m, "reduction.method");
            if (red.method != "craig-bampton" && red.method != "rubin")
                fail(m, "reduction.method",
                     "'" + excerpt(red.method) + "' is not a method (expected \"craig-bampton\" or \"rubin\")");
        }
        ReductionSettings settings;
        if (red.method == "rubin") settings.method = ReductionMethod::rubin;
        const toml::node* modes = r->get("modes");
        const toml::node* cutoff = r->get("cutoff");
        if ((modes != nullptr) == (cutoff != nullptr))
            fail_at(table_line(*r, "reduction"), "reduction",
                    "give exactly one of 'modes' (how many modes to keep) and 'cutoff' (rad/s)");
        if (modes) {
            const auto* i = modes->as_integer();
            if (!i || i->get() < 0) fail(modes, "reduction.modes", "expected an integer >= 0");
            settings.modes = static_cast<std::size_t>(i->get());
        } else {
            settings.cutoff = number(*cutoff, "reduction.cutoff");
            if (!std::isfinite(settings.cutoff) || !(settings.cutoff > 0.0))
                fail(cutoff, "reduction.cutoff", "must be a finite circular frequency > 0 (rad/s), got " + show(settings.cutoff));
        }
        std::string prefix = "q";
        if (const toml::node* p = r->get("prefix")) prefix = string_value(*p, "reduction.prefix");
        if (const toml::node* b = r->get("boundary")) {
            const toml::array* list = b->as_array();
            if (!list) fail(b, "reduction.boundary", "expected a list of dof names");
            for (std::size_t i = 0; i < list->size(); ++i) {
                const std::string key = "reduction.boundary[" + std::to_string(i + 1) + "]";
                const std::string name = string_value(*list->get(i), key);
                if (std::find(names.begin(), names.end(), name) == names.end())
                    fail(list->get(i), key, "'" + excerpt(name) + "' is not a dof of the structure");
            }
        }
        const std::size_t n = names.size();
        const SparseMatrixD Ms = sparse_matrix_file(t, "mass", model_.structure.mass_file, n);
        const SparseMatrixD Ks = sparse_matrix_file(t, "stiffness", model_.structure.stiffness_file, n);
        std::optional<SparseMatrixD> Cs;
        if (t.get("damping")) Cs = sparse_matrix_file(t, "damping", model_.structure.damping_file, n);
        const std::vector<std::size_t> boundary = boundary_dofs(root, names);
        if (boundary.empty())
            fail_at(table_line(*r, "reduction"), "reduction",
                    "no dof of the structure is named by an element, load, forcing or initial value, nor in "
                    "reduction.boundary: nothing would stay physical");
        const Eigen::MatrixXd base_forces = base_influence(root, names, Ms);
        ReducedStructure out;
        if (const std::string why = reduce_memo(Ms, Ks, Cs ? &*Cs : nullptr, boundary, settings, out, &base_forces);
            !why.empty())
            fail_at(table_line(*r, "reduction"), "reduction", why);
        reduced_base_forces_ = out.forces;
        const auto nr = static_cast<std::size_t>(out.M.rows());
        if (nr > kMaxMatrixDimension)
            fail(modes ? modes : cutoff, modes ? "reduction.modes" : "reduction.cutoff",
                 "the reduced model has " + std::to_string(nr) + " dofs (" + std::to_string(boundary.size()) +
                     " boundary, " + std::to_string(nr - boundary.size()) + " modes), more than the " +
                     std::to_string(kMaxMatrixDimension) + " hsnc solves");
        std::vector<std::string> kept;
        for (const std::size_t i : boundary) kept.push_back(names[i]);
        // The interior dofs are gone: their names no longer name anything.
        for (std::size_t i = 0, b = 0; i < n; ++i)
            if (b < boundary.size() && boundary[b] == i) ++b;
            else element_names_.erase(names[i]);
        red.modal_names.clear();
        for (std::size_t k = 1; k + boundary.size() <= nr; ++k) {
            const std::string q = prefix + std::to_string(k);
            if (element_names_.count(q))
                fail(r->get("prefix") ? r->get("prefix") : r, "reduction.prefix",
                     "the modal coordinate '" + excerpt(q) + "' is already the name of " + element_names_.at(q) +
                         "; choose another prefix");
            red.modal_names.push_back(q);
            kept.push_back(q);
        }
        for (const std::string& q : red.modal_names) element_names_.emplace(q, "reduction (a modal coordinate)");
        names = kept;
        red.full_dofs = n;
        red.boundary = boundary.size();
        red.boundary_index = boundary;
        red.interface_omega.assign(out.interface_omega.begin(), out.interface_omega.end());
        auto dense = [nr](const Eigen::MatrixXd& A, std::vector<double>& flat) {
            MarketMatrix m;
            m.rows = m.cols = nr;
            m.values.resize(nr * nr);
            for (std::size_t i = 0; i < nr; ++i)
                for (std::size_t j = 0; j < nr; ++j)
                    m.values[i * nr + j] = A(static_cast<Eigen::Index>(i), static_cast<Eigen::Index>(j));
            flat = m.values;
            return m;
        };
        M = dense(out.M, red.M);
        K = dense(out.K, red.K);
        if (Cs) C = dense(out.C, red.C);
        if (full_frequencies_) {  // kept for the report once the contacts are read (compare_reduction)
            full_M_ = Ms;
            full_K_ = Ks;
            reduced_M_ = out.M;
            reduced_K_ = out.K;
            if (Cs) full_C_ = *Cs, reduced_C_ = out.C;
            full_base_forces_ = base_forces;
        }
    }

    /// The reduction's accuracy (ModelOverrides::full_frequencies): the lowest
    /// frequencies of the full and the reduced structure with every contact
    /// open, and with every contact closed (k w w^T added on the boundary dofs
    /// of both; left out when a contact acts on a modal coordinate).
    void compare_reduction() {
        ReductionSource& red = model_.reduction;
        const std::size_t nr = model_.dof(), count = std::min<std::size_t>(nr, kReportedFrequencies);
        auto compare = [&](const SparseMatrixD& K, const Eigen::MatrixXd& Kr, ReductionSource::Frequencies& f) {
            Eigen::VectorXd full;
            f.problem = lowest_frequencies(*full_M_, K, count, full);
            f.full.assign(full.begin(), full.end());
            const Eigen::GeneralizedSelfAdjointEigenSolver<Eigen::MatrixXd> es(Kr, *reduced_M_, Eigen::EigenvaluesOnly);
            for (Eigen::Index k = 0; k < static_cast<Eigen::Index>(count); ++k)
                f.reduced.push_back(std::sqrt(std::max(0.0, es.eigenvalues()(k))));
        };
        compare(*full_K_, *reduced_K_, red.open);
        if (model_.contacts.empty()) return;
        std::vector<Eigen::Triplet<double, int>> add;
        Eigen::MatrixXd Kr = *reduced_K_;
        for (const Contact& c : model_.contacts) {
            std::vector<std::pair<int, double>> w;  // (reduced dof, weight)
            for_each_term(c.direction(), [&](int body, double weight) { w.emplace_back(body, weight); });
            for (const auto& [i, wi] : w) {
                if (static_cast<std::size_t>(i) >= red.boundary) return;  // on a modal coordinate
                for (const auto& [j, wj] : w) {
                    Kr(i, j) += c.k * wi * wj;
                    add.emplace_back(static_cast<int>(red.boundary_index[static_cast<std::size_t>(i)]),
                                     static_cast<int>(red.boundary_index[static_cast<std::size_t>(j)]), c.k * wi * wj);
                }
            }
        }
        SparseMatrixD extra(full_K_->rows(), full_K_->cols());
        extra.setFromTriplets(add.begin(), add.end());
        compare(*full_K_ + extra, Kr, red.closed);
    }

    /// The reduction's response error (ReductionSource::response): the
    /// structure's steady response to the load (static) and to each forcing
    /// harmonic, (K - w^2 M + i w C) X = F, full (sparse LU) against reduced
    /// (dense LU), at the boundary dofs. C: the structure's own, else
    /// Rayleigh's alpha M + beta K. The full F: the load and harmonics on
    /// the boundary dofs where they act, a base motion's -M r s.
    void compare_responses() {
        using Complex = std::complex<double>;
        ReductionSource& red = model_.reduction;
        const auto n = static_cast<Eigen::Index>(red.full_dofs), nr = static_cast<Eigen::Index>(model_.dof());
        const auto nb = static_cast<Eigen::Index>(red.boundary);
        if (nr != reduced_M_->rows()) {  // massless dofs condensed after the reduction: the dofs differ
            red.response.push_back({"every load", NAN, "massless dofs are condensed"});
            return;
        }
        const SparseMatrixD C = full_C_ ? *full_C_ : SparseMatrixD(model_.alpha * *full_M_ + model_.beta * *full_K_);
        const Eigen::MatrixXd Cr =
            reduced_C_ ? *reduced_C_ : Eigen::MatrixXd(model_.alpha * *reduced_M_ + model_.beta * *reduced_K_);
        // One load: the reduced F on the reduced dofs, the full one (null: it acts on a modal coordinate).
        auto compare = [&](const std::string& what, double w, const Eigen::VectorXd& Fr, const Eigen::VectorXd* F) {
            ReductionSource::Response r{what, NAN, ""};
            if (!F) {
                r.problem = "it acts on a modal coordinate";
                red.response.push_back(r);
                return;
            }
            Eigen::VectorXcd X;
            r.problem = harmonic_response(*full_M_, *full_K_, C, w, *F, X);
            const Eigen::MatrixXcd Ar =
                (*reduced_K_ - w * w * *reduced_M_).cast<Complex>() + Complex(0, w) * Cr.cast<Complex>();
            const Eigen::FullPivLU<Eigen::MatrixXcd> lur(Ar);
            if (r.problem.empty() && !lur.isInvertible())
                r.problem = w == 0.0 ? "K is singular (a rigid-body motion)" : "the structure resonates there";
            if (!r.problem.empty()) {
                red.response.push_back(r);
                return;
            }
            const Eigen::VectorXcd Xr = lur.solve(Fr.cast<Complex>());
            double diff = 0.0, size = 0.0;
            for (Eigen::Index i = 0; i < nb; ++i) {
                const Complex full = X(static_cast<Eigen::Index>(red.boundary_index[static_cast<std::size_t>(i)]));
                diff = std::max(diff, std::abs(Xr(i) - full));
                size = std::max(size, std::abs(full));
            }
            r.error = size > 0.0 ? diff / size : diff;
            red.response.push_back(r);
        };
        // A load on the reduced dofs as the full structure feels it (null when it names a modal coordinate).
        auto full_force = [&](const std::vector<double>& f, Eigen::VectorXd& F) {
            F = Eigen::VectorXd::Zero(n);
            for (Eigen::Index i = 0; i < nr; ++i)
                if (f[static_cast<std::size_t>(i)] != 0.0) {
                    if (i >= nb) return false;
                    F(static_cast<Eigen::Index>(red.boundary_index[static_cast<std::size_t>(i)])) =
                        f[static_cast<std::size_t>(i)];
                }
            return true;
        };
        Eigen::VectorXd F;
        if (std::any_of(model_.load.begin(), model_.load.end(), [](double v) { return v != 0.0; })) {
            const bool on_boundary = full_force(model_.load, F);
            compare("load (static)", 0.0, Eigen::Map<const Eigen::VectorXd>(model_.load.data(), nr),
                    on_boundary ? &F : nullptr);
        }
        for (std::size_t h = 0; h < model_.forcing.size(); ++h) {
            const Harmonic& hm = model_.forcing[h];
            bool on_boundary = false;
            const auto base = std::find_if(model_.base.begin(), model_.base.end(),
                                           [&](const BaseMotion& b) { return b.harmonic == h; });
            if (base != model_.base.end()) {
                const auto j = static_cast<std::size_t>(base - model_.base.begin());
                F = -base_scale_[j] * full_base_forces_.col(static_cast<Eigen::Index>(j));
                on_boundary = true;
            } else {
                on_boundary = full_force(hm.amplitude, F);
            }
            compare("forcing " + std::to_string(h + 1) + " at " + show(hm.omega) + " rad/s", hm.omega,
                    Eigen::Map<const Eigen::VectorXd>(hm.amplitude.data(), nr), on_boundary ? &F : nullptr);
        }
    }

    /// structure.dofs = "FILE": the dof names one per line, in matrix order
    /// (blank lines and lines starting with '#' skipped; spaces around a name
    /// ignored). Each name is checked as a list's would be, named "FILE:LINE".
    std::vector<std::string> dof_name_file(const toml::node& node, std::size_t limit) {
        const std::string written = string_value(node, "structure.dofs");
        if (written.empty() || written.find('\0') != std::string::npos)
            fail(&node, "structure.dofs", "must name a file of dof names (one per line)");
        const std::string path = beside_model(written);
        note_input_file(path);
        const FileRead file = read_regular_file(path, kMaxSparseFileBytes);
        if (file.status != FileRead::Status::ok)
            fail(&node, "structure.dofs", "cannot read dof file '" + written + "': " + file.problem);
        std::vector<std::string> names;
        std::size_t line = 0, pos = 0;
        while (pos < file.bytes.size()) {
            const std::size_t end = std::min(file.bytes.find('\n', pos), file.bytes.size());
            std::string name = file.bytes.substr(pos, end - pos);
            pos = end + 1;
            ++line;
            const std::size_t first = name.find_first_not_of(" \t\r"), last = name.find_last_not_of(" \t\r");
            if (first == std::string::npos || name[first] == '#') continue;
            name = name.substr(first, last - first + 1);
            const std::string where = written + ":" + std::to_string(line);
            check_new_name(&node, "structure.dofs", name, where + ": ");
            if (names.size() == limit) fail(&node, "structure.dofs", where + ": " + too_many_dofs(limit + 1));
            element_names_.emplace(name, "structure.dofs (" + where + ")");
            names.push_back(name);
        }
        if (names.empty()) fail(&node, "structure.dofs", "'" + written + "' holds no dof name");
        return names;
    }

    void read_structure(const toml::table& root) {
        if (const toml::node* m = root.get("mass"))
            fail(m, "mass", "[[mass]] and [structure] exclude each other (a structure's bodies are its dofs)");
        const toml::table* t = optional_table(root, "", "structure");
        check_keys(*t, "structure", {"dofs", "mass", "stiffness", "damping"});
        model_.structure.present = true;
        const toml::node* dofs = t->get("dofs");
        if (!dofs) fail_at(table_line(*t, "structure"), "structure.dofs", "required key is missing");
        const bool reduced = root.get("reduction") != nullptr;
        const std::size_t limit = reduced ? kMaxSparseDimension : kMaxMatrixDimension;
        std::vector<std::string> names;
        if (dofs->as_string()) {
            names = dof_name_file(*dofs, limit);
        } else {
            const toml::array* list = dofs->as_array();
            if (!list || list->empty())
                fail(dofs, "structure.dofs",
                     "expected a non-empty list of dof names, e.g. [\"u1\", \"u2\"], or the name of a file of them");
            if (list->size() > limit) fail(dofs, "structure.dofs", too_many_dofs(list->size()));
            for (std::size_t i = 0; i < list->size(); ++i) {
                const std::string key = "structure.dofs[" + std::to_string(i + 1) + "]";
                const std::string name = string_value(*list->get(i), key);
                check_new_name(list->get(i), key, name);
                element_names_.emplace(name, key);
                names.push_back(name);
            }
        }
        MarketMatrix M, K;
        std::optional<MarketMatrix> damping;
        if (reduced) {
            reduce_structure(root, *t, names, M, K, damping);
        } else {
            M = matrix_file(*t, "mass", model_.structure.mass_file);
            K = matrix_file(*t, "stiffness", model_.structure.stiffness_file);
            if (t->get("damping")) damping = matrix_file(*t, "damping", model_.structure.damping_file);
        }
        // Massless dofs (zero rows of M) condensed statically before the checks (structure.h).
        if (const std::string why =
                condense_massless(M, K, damping ? &*damping : nullptr, names, model_.condensation);
            !why.empty()) {
            const bool of_c = why.rfind("C ", 0) == 0, of_k = why.rfind("K ", 0) == 0;
            const char* key = of_c ? "damping" : of_k ? "stiffness" : "mass";
            const std::string& file = of_c ? model_.structure.damping_file
                                      : of_k ? model_.structure.stiffness_file : model_.structure.mass_file;
            fail(t->get(key), std::string("structure.") + key, file + ": " + why);
        }
        std::vector<double> mass;
        if (const std::string why = check_mass_matrix(M, names, mass, model_.mass_matrix, model_.mass_floor);
            !why.empty())
            fail(t->get("mass"), "structure.mass", model_.structure.mass_file + ": " + why);
        if (const std::string why = check_stiffness_matrix(K, names, structure_springs_); !why.empty())
            fail(t->get("stiffness"), "structure.stiffness", model_.structure.stiffness_file + ": " + why);
        if (damping) {
            const MarketMatrix& C = *damping;
            double a = 0.0, b = 0.0;
            bool proportional = false;
            if (const std::string why = fit_rayleigh_damping(C, M, K, names, a, b, proportional); !why.empty())
                fail(t->get("damping"), "structure.damping", model_.structure.damping_file + ": " + why);
            if (proportional) {
                structure_damping_ = std::make_pair(a, b);
            } else {
                if (const std::string why = check_damping_matrix(C, names, structure_dampers_); !why.empty())
                    fail(t->get("damping"), "structure.damping", model_.structure.damping_file + ": " + why);
                structure_damping_ = std::make_pair(0.0, 0.0);  // C is all dampers
            }
        }
        for (std::size_t i = 0; i < names.size(); ++i) {
            Mass m;
            m.name = names[i];
            m.m = mass[i];
            // The matrices are numbers: their text is the literal (inspect --symbolic, sweep kernels).
            model_.field_expressions["mass[" + std::to_string(i + 1) + "].m"] = literal_text(m.m);
            model_.masses.push_back(m);
        }
    }

    /// The springs of a [structure]'s K, after the file's own [[spring]]s (whose
    /// keys "spring[N].k" keep their numbers).
    void add_structure_springs() {
        for (const Spring& s : structure_springs_) {
            model_.springs.push_back(s);
            model_.field_expressions["spring[" + std::to_string(model_.springs.size()) + "].k"] = literal_text(s.k);
        }
    }

    /// [[damper]] tables, then the dampers of a non-proportional structure.damping.
    void read_dampers(const toml::table& root) {
        const auto tables = table_array(root, "damper");
        for (std::size_t i = 0; i < tables.size(); ++i) {
            const toml::table& t = *tables[i];
            const std::string path = "damper[" + std::to_string(i + 1) + "]";
            check_keys(t, path, {"between", "c"});
            Damper d;
            std::tie(d.a, d.b) = between(t, path);
            d.c = required_number(t, path, "c");
            if (d.c < 0.0) fail(t.get("c"), path + ".c", "damping coefficient must be >= 0, got " + show(d.c));
            if (d.c > 0.0) {  // c = 0 (a sweep's end point) is no damper at all
                model_.dampers.push_back(d);
                damper_keys_.emplace_back(path + ".c", t.get("c")->source().begin.line);
            }
        }
        model_.dampers.insert(model_.dampers.end(), structure_dampers_.begin(), structure_dampers_.end());
    }

    /// An element's `name` (checked as a new name), or KIND<i+1> when it has none.
    std::string element_name(const toml::table& t, const std::string& path, const std::string& kind, std::size_t i) {
        if (t.get("name")) {
            std::string name = required_string(t, path, "name");
            check_new_name(t.get("name"), path + ".name", name);
            return name;
        }
        std::string name = kind + std::to_string(i + 1);
        check_new_name(&t, path + ".name", name);  // the default may clash with a mass
        return name;
    }

    void read_jenkins(const toml::table& root) {
        const auto tables = table_array(root, "jenkins");
        for (std::size_t i = 0; i < tables.size(); ++i) {
            const toml::table& t = *tables[i];
            const std::string path = "jenkins[" + std::to_string(i + 1) + "]";
            check_keys(t, path, {"name", "between", "direction", "k", "slip_force"});
            Jenkins j;
            j.name = element_name(t, path, "jenkins", i);
            if (const toml::node* dir = t.get("direction")) {
                if (t.get("between")) fail(dir, path + ".direction", "give either 'between' or 'direction', not both");
                j.weights = direction(*dir, path + ".direction");
            } else {
                std::tie(j.a, j.b) = between(t, path);
            }
            j.k = required_number(t, path, "k");
            if (!(j.k > 0.0)) fail(t.get("k"), path + ".k", "stiffness must be > 0, got " + show(j.k));
            j.slip_force = required_number(t, path, "slip_force");
            if (!(j.slip_force > 0.0))
                fail(t.get("slip_force"), path + ".slip_force", "must be > 0, got " + show(j.slip_force));
            model_.jenkins.push_back(j);
            element_names_.emplace(j.name, path);
        }
    }

    /// Each [[friction]]'s (carrier, partner): the frictions between two bodies
    /// form a forest over the bodies, each body carrying at most one (its
    /// friction toward the root of its tree: the ground when a body of the
    /// tree has a friction against it, else the body in the most frictions,
    /// most often written second, first in model order). So a lone friction
    /// [a, b] is a's against b (as written), a damper between two blades is
    /// the partner of both, and a block on a block on the ground rides the
    /// lower one. A friction closing a loop (two roots, or a cycle) is refused
    /// by key; one against the ground is (body, kGround).
    std::vector<std::pair<int, int>> orient_frictions(const std::vector<const toml::table*>& tables) const {
        const std::size_t n = model_.masses.size();
        std::vector<std::pair<int, int>> out(tables.size());
        std::vector<std::vector<std::pair<int, std::size_t>>> edges(n);  // per body: (other body, friction)
        std::vector<char> grounded(n, 0);
        for (std::size_t i = 0; i < n; ++i) grounded[i] = model_.has_friction(i) ? 1 : 0;  // a mass's own mu_k
        for (std::size_t i = 0; i < tables.size(); ++i) {
            const std::string path = "friction[" + std::to_string(i + 1) + "]";
            check_keys(*tables[i], path, {"name", "between", "mu_k", "mu_s", "normal"});
            out[i] = between(*tables[i], path);
            const auto [a, b] = out[i];
            if (a == kGround || b == kGround) {
                const int body = a == kGround ? b : a;
                out[i] = {body, kGround};
                grounded[static_cast<std::size_t>(body)] = 1;
                continue;
            }
            edges[static_cast<std::size_t>(a)].push_back({b, i});
            edges[static_cast<std::size_t>(b)].push_back({a, i});
        }
        std::vector<int> tree(n, -1);  // the tree each body is in, by its first body
        std::vector<char> oriented(tables.size(), 0);
        for (std::size_t start = 0; start < n; ++start) {
            if (tree[start] >= 0 || edges[start].empty()) continue;
            std::vector<int> members{static_cast<int>(start)};
            tree[start] = static_cast<int>(start);
            for (std::size_t k = 0; k < members.size(); ++k)
                for (const auto& [o, e] : edges[static_cast<std::size_t>(members[k])])
                    if (tree[static_cast<std::size_t>(o)] < 0)
                        tree[static_cast<std::size_t>(o)] = static_cast<int>(start), members.push_back(o);
            int root = -1;
            for (int m : members)
                if (grounded[static_cast<std::size_t>(m)]) root = m;
            // Else the body in the most frictions; of several, the one most often written second
            // (between = [rider, partner]: a lone friction keeps a as its carrier); then model order.
            auto rank = [&](int m) {
                int second = 0;
                for (const auto& [o, e] : edges[static_cast<std::size_t>(m)]) second += out[e].second == m ? 1 : -1;
                return std::make_pair(edges[static_cast<std::size_t>(m)].size(), second);
            };
            if (root < 0)
                for (int m : members)
                    if (root < 0 || rank(m) > rank(root)) root = m;
            // From the root outwards: each body carries the friction it was reached by.
            std::vector<char> seen(n, 0);
            std::vector<int> queue{root};
            seen[static_cast<std::size_t>(root)] = 1;
            for (std::size_t k = 0; k < queue.size(); ++k) {
                const int p = queue[k];
                for (const auto& [o, e] : edges[static_cast<std::size_t>(p)]) {
                    if (oriented[e]) continue;
                    oriented[e] = 1;
                    const std::string path = "friction[" + std::to_string(e + 1) + "]";
                    const toml::node* where = tables[e]->get("between");
                    if (seen[static_cast<std::size_t>(o)])
                        fail(where, path + ".between",
                             "closes a loop of frictions between bodies (through '" +
                                 model_.masses[static_cast<std::size_t>(o)].name +
                                 "'): the forces a loop of stuck frictions holds are not determined; not supported");
                    if (grounded[static_cast<std::size_t>(o)])
                        fail(
                            where, path + ".between",
                            "'" + model_.masses[static_cast<std::size_t>(o)].name + "' and '" +
                                model_.masses[static_cast<std::size_t>(root)].name +
                                "' both have friction against the ground and are joined by frictions between bodies: a "
                                "loop through the ground, whose stuck forces are not determined; not supported");
                    seen[static_cast<std::size_t>(o)] = 1;
                    out[e] = {o, p};  // o rides p
                    queue.push_back(o);
                }
            }
        }
        return out;
    }

    void read_frictions(const toml::table& root) {
        const auto tables = table_array(root, "friction");
        const std::vector<std::pair<int, int>> carried = orient_frictions(tables);
        for (std::size_t i = 0; i < tables.size(); ++i) {
            const toml::table& t = *tables[i];
            const std::string path = "friction[" + std::to_string(i + 1) + "]";
            FrictionElement f;
            f.name = element_name(t, path, "friction", i);
            std::tie(f.a, f.b) = carried[i];
            const bool two_bodies = f.a != kGround && f.b != kGround;
            const int body = f.a == kGround ? f.b : f.a;
            Mass& mass = model_.masses[static_cast<std::size_t>(body)];
            // Between two bodies a and b: a carries the friction, on w = v[a] - v[b],
            // with b as its partner (elements/friction.h FrictionSlot::partner; orient_frictions).
            if (two_bodies) {
                if (!model_.proportional_damping())
                    fail(t.get("between"), path + ".between",
                         "friction between two bodies with non-proportional damping ([[damper]] or a contact's c) is "
                         "not yet supported");
            }
            if (model_.coupled_mass() && two_bodies)  // a stuck pair on a coupled M: stage c of issue 36
                fail(t.get("between"), path + ".between",
                     "friction between two dofs of a structure with a coupled (non-diagonal) mass matrix is not yet "
                     "supported: give friction against the ground, or model the joint with a [[jenkins]] element");
            f.mu_k = required_number(t, path, "mu_k");
            if (f.mu_k < 0.0) fail(t.get("mu_k"), path + ".mu_k", "must be >= 0, got " + show(f.mu_k));
            f.mu_s = optional_number(t, path, "mu_s").value_or(f.mu_k);
            if (f.mu_s < f.mu_k)
                fail(t.get("mu_s"), path + ".mu_s",
                     "static coefficient must be >= mu_k = " + show(f.mu_k) + ", got " + show(f.mu_s));
            const std::string mass_key = "mass[" + std::to_string(body + 1) + "]";
            const auto normal = optional_number(t, path, "normal");
            if (!normal && model_.structure.present)
                fail_at(table_line(t, path), path + ".normal",
                        "required key is missing (a dof has no weight m*g: give the normal force)");
            if (!normal && two_bodies)
                fail_at(table_line(t, path), path + ".normal",
                        "required key is missing (between two bodies the normal force is not a weight m*g: give it)");
            f.normal = normal.value_or(mass.m * model_.g);
            if (!(f.normal > 0.0)) fail(t.get("normal"), path + ".normal", "normal force must be > 0, got " + show(f.normal));
            FrictionSlot& slot = model_.set_friction(static_cast<std::size_t>(body));
            if (slot.active)
                fail(t.get("between"), path + ".between",
                     "'" + mass.name + "' already has friction (" +
                         (slot.element >= 0
                              ? "element '" + model_.frictions[static_cast<std::size_t>(slot.element)].name + "'"
                              : std::string("its own mu_k")) +
                         "); one friction to ground per " + body_word() + " is supported");
            // The element acts as the mass's friction, with its own coefficients and normal force (model.h).
            slot.active = true;
            slot.mu_k = f.mu_k;
            slot.mu_s = f.mu_s;
            slot.normal = normal ? f.normal : 0.0;
            slot.element = static_cast<int>(model_.frictions.size());
            slot.partner = two_bodies ? f.b : kGround;
            auto text = [&](const std::string& key) {
                const auto it = model_.field_expressions.find(key);
                return it == model_.field_expressions.end() ? std::string() : it->second;
            };
            const std::string mu_k_text = text(path + ".mu_k"), mu_s_text = t.get("mu_s") ? text(path + ".mu_s") : mu_k_text;
            model_.field_expressions[mass_key + ".mu_k"] = mu_k_text;
            model_.field_expressions[mass_key + ".mu_s"] = mu_s_text;
            if (normal) model_.field_expressions[mass_key + ".normal"] = text(path + ".normal");
            element_names_.emplace(f.name, path);
            model_.frictions.push_back(f);
        }
    }

    void read_masses(const toml::table& root) {
        const auto tables = table_array(root, "mass");
        if (tables.empty()) fail(root.get("mass"), "mass", "no masses: give at least one [[mass]] table");
        if (tables.size() > kMaxMatrixDimension) fail(root.get("mass"), "mass", too_many_dofs(tables.size()));
        for (std::size_t i = 0; i < tables.size(); ++i) {
            const toml::table& t = *tables[i];
            const std::string path = "mass[" + std::to_string(i + 1) + "]";
            check_keys(t, path, {"name", "m", "mu_k", "mu_s"});
            Mass mass;
            mass.name = required_string(t, path, "name");
            check_new_name(t.get("name"), path + ".name", mass.name);
            mass.m = required_number(t, path, "m");
            if (!(mass.m > 0.0)) fail(t.get("m"), path + ".m", "mass must be > 0, got " + show(mass.m));
            const auto mu_k = optional_number(t, path, "mu_k");
            const auto mu_s = optional_number(t, path, "mu_s");
            if (mu_s && !mu_k)
                fail(t.get("mu_s"), path + ".mu_s", "mu_s given without mu_k (a mass has friction exactly when it has mu_k)");
            if (mu_k) {
                if (*mu_k < 0.0) fail(t.get("mu_k"), path + ".mu_k", "must be >= 0, got " + show(*mu_k));
                FrictionSlot& slot = model_.set_friction(i);
                slot.active = true;
                slot.mu_k = *mu_k;
                slot.mu_s = mu_s.value_or(*mu_k);
                if (slot.mu_s < slot.mu_k)
                    fail(t.get("mu_s"), path + ".mu_s",
                         "static coefficient must be >= mu_k = " + show(slot.mu_k) + ", got " + show(slot.mu_s));
            }
            element_names_.emplace(mass.name, path);
            model_.masses.push_back(mass);
        }
    }

    void read_springs(const toml::table& root) {
        const auto tables = table_array(root, "spring");
        for (std::size_t i = 0; i < tables.size(); ++i) {
            const toml::table& t = *tables[i];
            const std::string path = "spring[" + std::to_string(i + 1) + "]";
            check_keys(t, path, {"between", "k"});
            Spring spring;
            std::tie(spring.a, spring.b) = between(t, path);
            spring.k = required_number(t, path, "k");
            if (spring.k < 0.0) fail(t.get("k"), path + ".k", "spring stiffness must be >= 0, got " + show(spring.k));
            model_.springs.push_back(spring);
        }
    }

    void read_damping(const toml::table& root) {
        const toml::table* t = optional_table(root, "", "damping");
        if (!t && structure_damping_) {
            std::tie(model_.alpha, model_.beta) = *structure_damping_;
            model_.field_expressions["damping.alpha"] = literal_text(model_.alpha);
            model_.field_expressions["damping.beta"] = literal_text(model_.beta);
        }
        if (!t) return;
        if (structure_damping_)
            fail(t, "damping", "[damping] and structure.damping both give the damping; keep one");
        check_keys(*t, "damping", {"alpha", "beta"});
        model_.alpha = optional_number(*t, "damping", "alpha").value_or(0.0);
        model_.beta = optional_number(*t, "damping", "beta").value_or(0.0);
        if (model_.alpha < 0.0) fail(t->get("alpha"), "damping.alpha", "must be >= 0, got " + show(model_.alpha));
        if (model_.beta < 0.0) fail(t->get("beta"), "damping.beta", "must be >= 0, got " + show(model_.beta));
    }

    void read_contacts(const toml::table& root) {
        const auto tables = table_array(root, "contact");
        for (std::size_t i = 0; i < tables.size(); ++i) {
            const toml::table& t = *tables[i];
            const std::string path = "contact[" + std::to_string(i + 1) + "]";
            check_keys(t, path, {"name", "between", "direction", "gap", "k", "c", "restitution"});
            Contact contact;
            contact.name = element_name(t, path, "contact", i);
            if (const toml::node* dir = t.get("direction")) {
                if (t.get("between"))
                    fail(dir, path + ".direction", "give either 'between' or 'direction', not both");
                contact.weights = direction(*dir, path + ".direction");
            } else {
                std::tie(contact.a, contact.b) = between(t, path);
            }
            contact.gap = required_number(t, path, "gap");
            if (const std::optional<double> e = optional_number(t, path, "restitution")) {  // a rigid stop (contact.h)
                if (!(*e > 0.0 && *e <= 1.0))
                    fail(t.get("restitution"), path + ".restitution",
                         "the coefficient of restitution must be in (0, 1], got " + show(*e) +
                             " (e = 0, a stop that keeps what hits it, is not modelled)");
                for (const char* key : {"k", "c"})
                    if (t.get(key))
                        fail(t.get(key), path + "." + key,
                             "a contact with 'restitution' is a rigid stop (impacts); give either 'restitution' or "
                             "the spring 'k' (and its damping 'c'), not both");
                contact.restitution = *e;
                element_names_.emplace(contact.name, path);
                model_.contacts.push_back(contact);
                continue;
            }
            contact.k = required_number(t, path, "k");
            if (!(contact.k > 0.0)) fail(t.get("k"), path + ".k", "contact stiffness must be > 0, got " + show(contact.k));
            contact.c = optional_number(t, path, "c").value_or(0.0);
            if (!(contact.c >= 0.0)) fail(t.get("c"), path + ".c", "contact damping must be >= 0, got " + show(contact.c));
            element_names_.emplace(contact.name, path);
            model_.contacts.push_back(contact);
        }
    }

    void read_forcing(const toml::table& root) {
        const auto tables = table_array(root, "forcing");
        for (std::size_t i = 0; i < tables.size(); ++i) {
            const toml::table& t = *tables[i];
            const std::string path = "forcing[" + std::to_string(i + 1) + "]";
            check_keys(t, path, {"omega", "phase", "amplitude"});
            Harmonic h;
            h.omega = required_number(t, path, "omega");
            if (!(h.omega > 0.0))
                fail(t.get("omega"), path + ".omega",
                     "must be > 0, got " + show(h.omega) + " (a constant force belongs in [load])");
            h.phase = optional_number(t, path, "phase").value_or(0.0);
            const toml::node* amplitude = t.get("amplitude");
            if (!amplitude) fail_at(table_line(t, path), path + ".amplitude", "required key is missing");
            std::vector<double> on_condensed;
            h.amplitude = per_mass(*amplitude, path + ".amplitude", &on_condensed);
            fold_condensed(on_condensed, h.amplitude);
            if (model_.condensation.present()) model_.condensation.amplitude.push_back(on_condensed);
            model_.forcing.push_back(h);
        }
    }

    /// [[base]]: a harmonic ground motion, x_g, x_g' or x_g'' = amplitude *
    /// sin(omega t + phase) along `direction` (default: every mass, 1; a
    /// [structure] names its own); its effective force -M r x_g'' is one more
    /// harmonic of the forcing (the model is relative to the base).
    void read_base(const toml::table& root) {
        const auto tables = table_array(root, "base");
        for (std::size_t i = 0; i < tables.size(); ++i) {
            const toml::table& t = *tables[i];
            const std::string path = "base[" + std::to_string(i + 1) + "]";
            check_keys(t, path, {"motion", "omega", "amplitude", "phase", "direction"});
            // A reduced structure's -T^T M r x_g'' comes from r over the full structure
            // (base_influence); where massless dofs are condensed after the reduction its
            // rows would need that fold too: refused rather than a wrong force.
            const bool reduced = model_.reduction.present;
            if (reduced && model_.condensation.present())
                fail_at(table_line(t, path), path,
                        "a reduced structure whose massless dofs are condensed takes no base motion yet");
            BaseMotion b;
            const std::string given = required_string(t, path, "motion");
            if (given == "displacement")
                b.given = BaseMotion::Given::displacement;
            else if (given == "velocity")
                b.given = BaseMotion::Given::velocity;
            else if (given == "acceleration")
                b.given = BaseMotion::Given::acceleration;
            else
                fail(t.get("motion"), path + ".motion",
                     "'" + excerpt(given) +
                         "' is not a motion (expected \"displacement\", \"velocity\" or "
                         "\"acceleration\": what amplitude and phase describe)");
            b.omega = required_number(t, path, "omega");
            if (!(b.omega > 0.0)) fail(t.get("omega"), path + ".omega", "must be > 0, got " + show(b.omega));
            b.amplitude = required_number(t, path, "amplitude");
            b.phase = optional_number(t, path, "phase").value_or(0.0);
            b.direction.assign(model_.dof(), 0.0);
            if (const toml::node* d = t.get("direction"); d && reduced) {
                // Read by base_influence over the full structure: the boundary dofs' weights, for `check`.
                for (std::size_t r = 0; r < model_.reduction.boundary; ++r)
                    b.direction[r] = base_r_(static_cast<Eigen::Index>(model_.reduction.boundary_index[r]),
                                             static_cast<Eigen::Index>(i));
            } else if (d) {
                for (const Weight& w : direction(*d, path + ".direction"))
                    b.direction[static_cast<std::size_t>(w.body)] = w.w;
            } else if (model_.structure.present) {
                fail_at(table_line(t, path), path + ".direction",
                        "required for a [structure]: the dofs the base motion moves and by how much (the influence "
                        "vector, e.g. { u1 = 1.0, u2 = 1.0 }: rotations 0)");
            } else {
                b.direction.assign(model_.dof(), 1.0);  // every mass translates with the base
            }
            // x_g'' = s sin(omega t + phase'): the effective force -M r s sin(omega t + phase').
            Harmonic h;
            h.omega = b.omega;
            h.phase = b.phase;
            double s = b.amplitude;
            if (b.given == BaseMotion::Given::displacement) s = -b.amplitude * b.omega * b.omega;
            if (b.given == BaseMotion::Given::velocity) s = b.amplitude * b.omega, h.phase = b.phase + M_PI / 2;
            base_scale_.push_back(s);
            h.amplitude.assign(model_.dof(), 0.0);
            for (std::size_t r = 0; r < model_.dof(); ++r) {
                double mr = 0.0;
                if (reduced)  // T^T M r, projected by the reduction
                    mr = reduced_base_forces_(static_cast<Eigen::Index>(r), static_cast<Eigen::Index>(i));
                else
                    for (std::size_t c = 0; c < model_.dof(); ++c) mr += model_.mass_entry(r, c) * b.direction[c];
                h.amplitude[r] = -mr * s;
                if (!std::isfinite(h.amplitude[r]))
                    fail(t.get("amplitude"), path + ".amplitude",
                         "the effective force -M r x_g'' on " + model_.masses[r].name + " is beyond the double range");
            }
            b.harmonic = model_.forcing.size();
            if (model_.condensation.present())  // massless dofs: no inertia, no effective force
                model_.condensation.amplitude.emplace_back(model_.condensation.condensed(), 0.0);
            model_.forcing.push_back(std::move(h));
            model_.base.push_back(std::move(b));
        }
    }

    void read_load(const toml::table& root) {
        model_.load.assign(model_.dof(), 0.0);
        if (const toml::node* load = root.get("load")) {
            model_.load = per_mass(*load, "load", &model_.condensation.load);
            given_load_ = model_.load;  // before the fold: [[load_step]]s change it entry by entry
            fold_condensed(model_.condensation.load, model_.load);
        }
    }

    /// [[load_step]]: from `t` on, the named dofs' constant loads are the
    /// given values (the others keep theirs); each step's whole load vector is
    /// kept, the condensed dofs' folded in as [load]'s are.
    void read_load_steps(const toml::table& root) {
        const auto tables = table_array(root, "load_step");
        // The load before folding, as given ([load], read once by read_load).
        std::vector<double> raw = given_load_, raw_condensed = model_.condensation.load;
        raw.resize(model_.dof(), 0.0);
        raw_condensed.resize(model_.condensation.condensed(), 0.0);
        for (std::size_t i = 0; i < tables.size(); ++i) {
            const toml::table& t = *tables[i];
            const std::string path = "load_step[" + std::to_string(i + 1) + "]";
            check_keys(t, path, {"name", "t", "load"});
            LoadStep step;
            step.name = element_name(t, path, "load_step", i);
            element_names_.emplace(step.name, path);
            step.t = required_number(t, path, "t");
            if (!(step.t > model_.t0))
                fail(t.get("t"), path + ".t", "must be after t0 = " + show(model_.t0) + ", got " + show(step.t));
            if (i > 0 && !(step.t > model_.load_steps.back().t))
                fail(t.get("t"), path + ".t",
                     "must be after the previous step's t = " + show(model_.load_steps.back().t) + ", got " +
                         show(step.t) + " (steps come in increasing t)");
            const toml::node* load = t.get("load");
            if (!load) fail_at(table_line(t, path), path + ".load", "required key is missing");
            std::vector<double> on_condensed;
            const std::vector<double> values = per_mass(*load, path + ".load", &on_condensed);
            for (auto&& [k, v] : *load->as_table()) {  // the named dofs take their new values
                const std::string name(k.str());
                if (const int m = model_.mass_index(name); m >= 0)
                    raw[static_cast<std::size_t>(m)] = values[static_cast<std::size_t>(m)];
                else {
                    const auto r = static_cast<std::size_t>(condensed_row(name));
                    raw_condensed[r] = on_condensed[r];
                }
            }
            step.load = raw;
            fold_condensed(raw_condensed, step.load);
            if (model_.condensation.present()) step.condensed_load = raw_condensed;
            model_.load_steps.push_back(std::move(step));
        }
    }

    void read_initial(const toml::table& root) {
        model_.x0.assign(model_.dof(), 0.0);
        model_.v0.assign(model_.dof(), 0.0);
        if (const toml::table* t = optional_table(root, "", "initial")) {
            check_keys(*t, "initial", {"t0", "x", "v"});
            model_.t0 = optional_number(*t, "initial", "t0").value_or(0.0);
            if (const toml::node* x = t->get("x")) model_.x0 = per_mass(*x, "initial.x");
            if (const toml::node* v = t->get("v")) model_.v0 = per_mass(*v, "initial.v");
        }
        apply_state_overrides(x0_, model_.x0, "initial.x");
        apply_state_overrides(v0_, model_.v0, "initial.v");
    }

    /// A rigid stop (restitution) must not start penetrated, nor on the stop
    /// moving into it.
    void check_rigid_stops(const toml::table& root) {
        for (std::size_t c = 0; c < model_.contacts.size(); ++c) {
            const Contact& ct = model_.contacts[c];
            if (!ct.rigid()) continue;
            const std::string path = "contact[" + std::to_string(c + 1) + "]";
            const std::size_t at = line_of(root, "contact", c, "restitution");
            double u = 0.0, rate = 0.0;
            for_each_term(ct.direction(), [&](int i, double w) {
                u += w * model_.x0[static_cast<std::size_t>(i)];
                rate += w * model_.v0[static_cast<std::size_t>(i)];
            });
            if (u - ct.gap > 0.0)
                fail_at(at, path + ".restitution",
                        "the rigid stop '" + ct.name + "' starts penetrated: u - gap = " + show(u - ct.gap, 17) +
                            " > 0 at t0 (initial.x)");
            if (u - ct.gap == 0.0 && rate > 0.0)
                fail_at(at, path + ".restitution",
                        "the motion starts on the rigid stop '" + ct.name + "' moving into it (u' = " + show(rate, 17) +
                            " > 0 at t0): start it just before the impact, or after it (initial.v)");
        }
    }

    void apply_state_overrides(const std::map<std::string, Override>& overrides, std::vector<double>& state,
                               const std::string& path) {
        for (const auto& [name, o] : overrides) {
            const int i = model_.mass_index(name);
            if (i < 0)
                throw InputError(o.flag + " '" + excerpt(o.raw) + "': no " + body_word() + " named '" + excerpt(name) + "'");
            const EvaluatedExpression e = override_value(o);
            state[i] = e.value;
            model_.field_expressions[path + "." + name] = e.canonical_text;
        }
    }

    // ---- the model as a whole ----

    /// The line of key `key` of table `array`[i] (an array of tables), or 0.
    static std::size_t line_of(const toml::table& root, const char* array, std::size_t i, const char* key) {
        const toml::array* tables = root.get(array) ? root.get(array)->as_array() : nullptr;
        const toml::node* table = tables ? tables->get(i) : nullptr;
        if (!table || !table->is_table()) return 0;
        const toml::node* value = table->as_table()->get(key);
        return (value ? value : table)->source().begin.line;
    }

    /// Every rate the solvers derive from the model must be a finite double:
    /// stiffness over mass (the squared natural frequencies, bounded by
    /// Gershgorin's sum |k| / m over the stiffest configuration: every contact
    /// closed, every Jenkins element stuck), beta k/m and c/m (decay rates) and
    /// force over mass (accelerations). Beyond the double range (k = 1e300 on
    /// m = 1e-300) every solver would step NaN states to a run that ends "ok".
    /// The element whose own ratio overflows is named, else the mass.
    void check_finite_rates(const toml::table& root) {
        struct Term {
            double value;
            std::string key;
            std::size_t line;
            std::string what;  ///< the element, for the message
        };
        const std::size_t n = model_.dof();
        std::vector<std::vector<Term>> stiffness(n), damping(n);
        auto add = [&](std::vector<std::vector<Term>>& to, int a, int b, const Term& term) {
            for (int end : {a, b})
                if (end != kGround) to[static_cast<std::size_t>(end)].push_back(term);
        };
        const std::string k_file = model_.structure.stiffness_file, c_file = model_.structure.damping_file;
        auto matrix_entry = [&](const char* matrix, int a, int b) {
            return b == kGround ? std::string("the row sum of ") + matrix + " at " + model_.masses[a].name
                                : std::string("-") + matrix + "(" + model_.masses[a].name + ", " + model_.masses[b].name + ")";
        };
        std::size_t from_file = 0;
        for (const Spring& sp : model_.springs) {
            if (sp.from_structure)
                add(stiffness, sp.a, sp.b, {sp.k, "structure.stiffness", line_of_key(root, "structure", "stiffness"),
                                           k_file + ": " + matrix_entry("K", sp.a, sp.b)});
            else {
                const std::string key = "spring[" + std::to_string(from_file + 1) + "].k";
                add(stiffness, sp.a, sp.b, {sp.k, key, line_of(root, "spring", from_file, "k"), "the spring"});
                ++from_file;
            }
        }
        for (std::size_t c = 0; c < model_.contacts.size(); ++c) {
            // k w w^T: row i's sum |k w_i| sum_j |w_j| (1 and 1 between two bodies)
            const Contact& ct = model_.contacts[c];
            double norm1 = 0.0;
            for_each_term(ct.direction(), [&](int, double w) { norm1 += std::fabs(w); });
            for_each_term(ct.direction(), [&](int body, double w) {
                const double k = ct.weights.empty() ? ct.k : ct.k * std::fabs(w) * norm1;
                stiffness[static_cast<std::size_t>(body)].push_back(
                    {k, "contact[" + std::to_string(c + 1) + "].k", line_of(root, "contact", c, "k"), "contact '" + ct.name + "'"});
                if (ct.c != 0.0)
                    damping[static_cast<std::size_t>(body)].push_back(
                        {ct.weights.empty() ? ct.c : ct.c * std::fabs(w) * norm1, "contact[" + std::to_string(c + 1) + "].c",
                         line_of(root, "contact", c, "c"), "contact '" + ct.name + "'"});
            });
        }
        for (std::size_t j = 0; j < model_.jenkins.size(); ++j) {
            // k w w^T, as a contact's: row i's sum |k w_i| sum_j |w_j| (1 and 1 between two bodies)
            const Jenkins& je = model_.jenkins[j];
            const Term entry{je.k, "jenkins[" + std::to_string(j + 1) + "].k", line_of(root, "jenkins", j, "k"),
                             "Jenkins element '" + je.name + "'"};
            if (je.weights.empty()) {
                add(stiffness, je.a, je.b, entry);
                continue;
            }
            double norm1 = 0.0;
            for (const Weight& w : je.weights) norm1 += std::fabs(w.w);
            for (const Weight& w : je.weights) {
                Term e = entry;
                e.value = je.k * std::fabs(w.w) * norm1;
                stiffness[static_cast<std::size_t>(w.body)].push_back(e);
            }
        }
        for (std::size_t d = 0; d < model_.dampers.size(); ++d) {
            const Damper& dp = model_.dampers[d];
            if (dp.from_structure)
                add(damping, dp.a, dp.b, {dp.c, "structure.damping", line_of_key(root, "structure", "damping"),
                                         c_file + ": " + matrix_entry("C", dp.a, dp.b)});
            else
                add(damping, dp.a, dp.b, {dp.c, damper_keys_[d].first, damper_keys_[d].second, "the damper"});
        }

        const bool structure = model_.structure.present;
        for (std::size_t i = 0; i < n; ++i) {
            const Mass& mass = model_.masses[i];
            const std::string mass_key = structure ? "structure.mass" : "mass[" + std::to_string(i + 1) + "].m";
            const std::size_t mass_line = structure ? line_of_key(root, "structure", "mass") : line_of(root, "mass", i, "m");
            const std::string on = (structure ? "dof '" : "mass '") + mass.name + "' (m = " + literal_text(mass.m) + ")";
            // One rate: sum |value| / m over `terms`, finite or an error naming the culprit.
            auto rate = [&](const std::vector<Term>& terms, const std::string& quantity, const std::string& plural,
                            const std::string& derived) {
                double sum = 0.0;
                const Term* largest = nullptr;
                for (const Term& t : terms) {
                    sum += std::fabs(t.value);
                    if (!largest || std::fabs(t.value) > std::fabs(largest->value)) largest = &t;
                }
                if (std::isfinite(sum / mass.m)) return sum;
                const std::string why = " is beyond the double range: " + derived + " would not be finite";
                if (largest && !std::isfinite(std::fabs(largest->value) / mass.m))
                    fail_at(largest->line, largest->key,
                            largest->what + ": " + quantity + " " + literal_text(largest->value) + " over " + on + why);
                fail_at(mass_line, mass_key,
                        "the " + plural + " on " + on + " sum to " + literal_text(sum) + "; over the mass that" + why);
            };
            const double k_sum = rate(stiffness[i], "stiffness", "stiffnesses", "the natural frequency sqrt(k/m)");
            if (!std::isfinite(model_.beta * (k_sum / mass.m)))
                fail_at(line_of_key(root, "damping", "beta"), structure_damping_ ? "structure.damping" : "damping.beta",
                        "beta = " + literal_text(model_.beta) + " times the stiffness over " + on +
                            " is beyond the double range: the modal damping alpha + beta omega^2 would not be finite");
            rate(damping[i], "damping", "dampings", "the decay rate c/m");
            // Forces over the mass: the load, each harmonic's amplitude, the friction force.
            std::vector<Term> forces;
            forces.push_back({model_.load[i], "load." + mass.name, line_of_key(root, "load", mass.name.c_str()), "the load"});
            for (std::size_t s = 0; s < model_.load_steps.size(); ++s)
                forces.push_back({model_.load_steps[s].load[i],
                                  "load_step[" + std::to_string(s + 1) + "].load." + mass.name,
                                  line_of(root, "load_step", s, "load"), "the load"});
            for (std::size_t h = 0; h < model_.forcing.size(); ++h)
                forces.push_back({model_.forcing[h].amplitude[i],
                                  "forcing[" + std::to_string(h + 1) + "].amplitude." + mass.name, 0, "the amplitude"});
            if (const FrictionSlot& slot = model_.friction_slot(i); slot.active) {
                const double friction = slot.mu_s * model_.normal_force(i);  // the largest friction force
                const std::string key = slot.element >= 0 ? "friction[" + std::to_string(slot.element + 1) + "].normal"
                                                          : "mass[" + std::to_string(i + 1) + "].mu_s";
                if (!std::isfinite(friction) || (slot.normal == 0.0 && !std::isfinite(slot.mu_s * model_.g)))
                    fail_at(0, key, "the friction force mu_s*N on " + on + " is beyond the double range");
                forces.push_back({friction, key, 0, "the friction force"});
            }
            rate(forces, "force", "forces", "the acceleration F/m");
        }
    }

    /// The line of key `key` of table `table` (a table of the root), or 0.
    static std::size_t line_of_key(const toml::table& root, const char* table, const char* key) {
        const toml::node* t = root.get(table);
        const toml::node* value = t && t->is_table() ? t->as_table()->get(key) : nullptr;
        return value ? value->source().begin.line : 0;
    }

    void read_simulate(const toml::table& root) {
        const toml::table* t = optional_table(root, "", "simulate");
        if (!t) return;
        check_keys(*t, "simulate", {"t_end"});
        model_.t_end = optional_number(*t, "simulate", "t_end");
        if (model_.t_end && !t_end_override_ && !(*model_.t_end > model_.t0))
            fail(t->get("t_end"), "simulate.t_end",
                 "must be > t0 = " + show(model_.t0) + ", got " + show(*model_.t_end));
    }

    static std::string show(double value, int digits = 6) {
        std::ostringstream out;
        out.precision(digits);
        out << value;
        return out.str();
    }

    std::string source_;
    std::optional<double> t_end_override_;
    bool full_frequencies_ = false;  ///< ModelOverrides::full_frequencies
    /// With full_frequencies_ and [reduction]: the full and reduced M, K until compare_reduction.
    std::optional<SparseMatrixD> full_M_, full_K_;
    std::optional<Eigen::MatrixXd> reduced_M_, reduced_K_;
    std::optional<SparseMatrixD> full_C_;
    std::optional<Eigen::MatrixXd> reduced_C_;
    Eigen::MatrixXd full_base_forces_;     ///< with full_frequencies_: M r of each [[base]] over the full structure
    std::vector<double> base_scale_;       ///< each [[base]]'s x_g'' amplitude s (its harmonic is -M r s)
    Eigen::MatrixXd base_r_;               ///< [reduction]: r of each [[base]] over the full structure (base_influence)
    Eigen::MatrixXd reduced_base_forces_;  ///< [reduction]: T^T M r of each [[base]] (base_influence), a column each
    std::map<std::string, Override> set_, x0_, v0_;
    std::vector<std::string> parameter_names_;     ///< all parameters, file order (implicit g first)
    std::unordered_map<std::string, double> values_;  ///< parameters evaluated so far
    bool pi_is_constant_ = true;                   ///< no parameter is named pi
    std::string parameter_text_;                   ///< the text of the expression number() read last for a parameter
    std::vector<double> given_load_;               ///< [load] per mass as given, before the condensed dofs' fold
    std::map<std::string, std::string> element_names_;  ///< mass/dof/contact/friction name -> who took it
    std::vector<Spring> structure_springs_;             ///< the springs of [structure]'s K
    std::optional<std::pair<double, double>> structure_damping_;  ///< (alpha, beta) of structure.damping
    std::vector<Damper> structure_dampers_;  ///< a non-proportional structure.damping as dampers
    /// ("damper[N].c", its line) of each [[damper]] in model_.dampers
    std::vector<std::pair<std::string, std::size_t>> damper_keys_;
    Model model_;
};

}  // namespace

ModelOverrides with_t_end(ModelOverrides overrides, double t_end) {
    if (!std::isnan(t_end)) overrides.t_end = t_end;
    return overrides;
}

Model parse_model(const std::string& toml_text, const std::string& source, const ModelOverrides& overrides) {
    const auto lock = ginac_lock();    // expressions are GiNaC (ginac_lock.h)
    Reader reader(source, overrides);  // flags are checked before the file
    const auto syntax_error = [&](std::size_t line, std::size_t column, const std::string& description) {
        std::string message = source;
        if (line > 0) message += ":" + std::to_string(line);
        message += ": TOML syntax error: " + description;
        if (column > 0) message += " (column " + std::to_string(column) + ")";
        return InputError(message);
    };
    // Code points that toml++ 3.3 must not see where it looks for whitespace
    // (toml_guard.h): refused there, or written as escapes.
    const TomlGuard guard = guard_toml_text(toml_text);
    if (guard.problem) throw syntax_error(guard.problem->line, guard.problem->column, guard.problem->description);
    toml::table root;
    try {
        root = toml::parse(std::string_view(guard.text), std::string_view(source));
    } catch (const toml::parse_error& e) {
        const std::size_t line = e.source().begin.line, column = e.source().begin.column;
        throw syntax_error(line, column > 0 ? guard.original_column(line, column) : 0, std::string(e.description()));
    }
    return reader.read(root);
}

Model read_model(const std::string& path, const ModelOverrides& overrides) {
    struct stat st;
    const FileRead file = read_regular_file(path, kMaxModelFileBytes, &st);  // never a FIFO or /dev/zero
    if (file.status != FileRead::Status::ok) throw InputError("cannot read model file '" + path + "': " + file.problem);
    note_input_file(path, st);  // no output of the run may replace it
    return parse_model(file.bytes, path, overrides);
}

}  // namespace hsnc
