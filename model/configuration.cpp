#include "configuration.h"

#include <sstream>

#include "error.h"

namespace hsnc {
namespace {

std::vector<std::string> split_names(const std::string& list) {
    std::vector<std::string> out;
    std::string cur;
    std::istringstream in(list);
    while (std::getline(in, cur, ','))
        if (!cur.empty()) out.push_back(cur);
    return out;
}

// An element named twice in one list (closed=c1,c1; stuck= a mass and its
// friction element) is most likely a typo for another one: refused.
[[noreturn]] void twice(const std::string& part, const std::string& name) {
    throw InputError("--config: " + part + ": '" + name + "' names an element given before in the list");
}

}  // namespace

Configuration Configuration::all_open(const Model& model) {
    return Configuration{std::vector<char>(model.contacts.size(), 0), std::vector<char>(model.masses.size(), 0),
                         std::vector<signed char>(model.jenkins.size(), 0)};
}

Configuration Configuration::parse(const Model& model, const std::string& spec) {
    Configuration cfg = all_open(model);
    std::istringstream in(spec);
    std::string part;
    bool seen_closed = false, seen_stuck = false, seen_slip = false;
    while (in >> part) {
        const auto eq = part.find('=');
        const std::string key = part.substr(0, eq);
        if (eq == std::string::npos || (key != "closed" && key != "stuck" && key != "slip"))
            throw InputError("--config: '" + part + "': expected closed=NAMES, stuck=NAMES or slip=NAMES");
        bool& seen = key == "closed" ? seen_closed : key == "stuck" ? seen_stuck : seen_slip;
        if (seen) throw InputError("--config: '" + key + "=' given twice");
        seen = true;
        for (const std::string& name : split_names(part.substr(eq + 1))) {
            if (key == "slip") {
                const char sign = name.back();
                const int j = model.jenkins_index(name.substr(0, name.size() - 1));
                if ((sign != '+' && sign != '-') || j < 0)
                    throw InputError("--config: slip=" + name +
                                     ": expected a Jenkins element's name followed by + or - (the sign of its stretch)");
                if (cfg.slip[static_cast<std::size_t>(j)] != 0) twice(part, name.substr(0, name.size() - 1));
                cfg.slip[static_cast<std::size_t>(j)] = sign == '+' ? 1 : -1;
            } else if (key == "closed") {
                const int c = model.contact_index(name);
                if (c < 0) throw InputError("--config: closed=" + name + ": no contact named '" + name + "'");
                if (cfg.closed[c]) twice(part, name);
                cfg.closed[c] = 1;
            } else {
                int i = model.mass_index(name);
                for (std::size_t m = 0; i < 0 && m < model.masses.size(); ++m)
                    if (model.friction_slot(m).element >= 0 && model.friction_name(m) == name) i = static_cast<int>(m);
                if (i < 0)
                    throw InputError("--config: stuck=" + name + ": no mass or friction element named '" + name + "'");
                if (!model.has_friction(i))
                    throw InputError("--config: stuck=" + name + ": mass '" + name +
                                     "' has no friction (no mu_k) and cannot stick");
                if (cfg.stuck[i]) twice(part, name);
                cfg.stuck[i] = 1;
            }
        }
    }
    return cfg;
}

std::string Configuration::spec(const Model& model) const {
    std::string closed_part = "closed=", stuck_part = "stuck=";
    bool first = true;
    for (std::size_t c = 0; c < closed.size(); ++c)
        if (closed[c]) {
            closed_part += (first ? "" : ",") + model.contacts[c].name;
            first = false;
        }
    first = true;
    for (std::size_t i = 0; i < stuck.size(); ++i)
        if (stuck[i]) {
            stuck_part += (first ? "" : ",") + model.friction_name(i);
            first = false;
        }
    if (slip.empty()) return closed_part + " " + stuck_part;
    std::string slip_part = "slip=";
    first = true;
    for (std::size_t j = 0; j < slip.size(); ++j)
        if (slip[j]) {
            slip_part += (first ? "" : ",") + model.jenkins[j].name + (slip[j] > 0 ? "+" : "-");
            first = false;
        }
    return closed_part + " " + stuck_part + " " + slip_part;
}

std::string Configuration::key() const {
    std::string k = "c";
    for (char c : closed) k += c ? '1' : '0';
    k += "_s";
    for (char s : stuck) k += s ? '1' : '0';
    if (slip.empty()) return k;
    k += "_j";
    for (signed char s : slip) k += s > 0 ? 'p' : s < 0 ? 'n' : '0';
    return k;
}

}  // namespace hsnc
