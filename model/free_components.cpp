#include "free_components.h"

#include <numeric>

#include "assembly.h"
#include "error.h"

namespace hsnc {

int FreeComponents::n_floating() const {
    int n = 0;
    for (char f : floating) n += f ? 1 : 0;
    return n;
}

std::vector<std::vector<int>> FreeComponents::floating_members() const {
    std::vector<std::vector<int>> members(floating.size());
    for (std::size_t s = 0; s < free.size(); ++s) members[static_cast<std::size_t>(component[s])].push_back(free[s]);
    std::vector<std::vector<int>> out;
    for (std::size_t c = 0; c < members.size(); ++c)
        if (floating[c]) out.push_back(std::move(members[c]));
    return out;
}

FreeComponents free_components(const Model& model, const Configuration& cfg) {
    const int n = static_cast<int>(model.dof());
    FreeComponents fc;
    std::vector<int> slot(static_cast<std::size_t>(n), -1);  // mass -> index in `free`, -1 when stuck
    for (int i = 0; i < n; ++i)
        if (!cfg.stuck[i]) {
            slot[i] = static_cast<int>(fc.free.size());
            fc.free.push_back(i);
        }
    // A mass stuck to its friction partner moves with it: its links are the partner's.
    for (int i = 0; i < n; ++i)
        if (const int c = carrier(model, cfg, static_cast<std::size_t>(i)); cfg.stuck[i] && c != kGround)
            slot[i] = slot[c];
    const int nf = static_cast<int>(fc.free.size());
    std::vector<int> parent(static_cast<std::size_t>(nf));  // union-find over the free masses
    std::iota(parent.begin(), parent.end(), 0);
    auto find = [&](int s) {
        while (parent[s] != s) s = parent[s] = parent[parent[s]];
        return s;
    };
    std::vector<char> anchored(static_cast<std::size_t>(nf), 0);  // per free mass, then per root
    auto link = [&](int a, int b, double k) {
        if (k == 0.0) return;  // a [structure]'s springs may be negative (structure.h)
        const int sa = a == kGround ? -1 : slot[a], sb = b == kGround ? -1 : slot[b];
        if (sa >= 0 && sb >= 0)
            parent[find(sa)] = find(sb);
        else if (sa >= 0)
            anchored[sa] = 1;  // to ground or to a stuck mass
        else if (sb >= 0)
            anchored[sb] = 1;
    };
    for (const Spring& s : model.springs) link(s.a, s.b, s.k);
    for (std::size_t c = 0; c < model.contacts.size(); ++c)
        if (cfg.closed[c] && !model.contacts[c].direction().weighted())
            link(model.contacts[c].a, model.contacts[c].b, model.contacts[c].k);
    for (std::size_t j = 0; j < model.jenkins.size(); ++j)  // a stuck Jenkins element is a spring
        if (cfg.slip[j] == 0 && !model.jenkins[j].direction().weighted())
            link(model.jenkins[j].a, model.jenkins[j].b, model.jenkins[j].k);

    fc.component.assign(static_cast<std::size_t>(nf), -1);
    std::vector<int> id_of_root(static_cast<std::size_t>(nf), -1);
    for (int s = 0; s < nf; ++s) {
        const int r = find(s);
        if (id_of_root[r] < 0) {
            id_of_root[r] = static_cast<int>(fc.floating.size());
            fc.floating.push_back(1);
        }
        fc.component[s] = id_of_root[r];
    }
    for (int s = 0; s < nf; ++s)
        if (anchored[s]) fc.floating[static_cast<std::size_t>(fc.component[s])] = 0;
    // A contact along a general direction is no edge: w w^T may hold a combination of a
    // floating part's rigid motions and leave others, which its bodies do not say. Closed
    // on a floating part, its rigid-body modes are not decided by the structure: refused.
    // The same holds for a stuck Jenkins element along a direction (its spring k w w^T).
    auto refuse_floating = [&](const Direction& d, const std::string& what) {
        for_each_term(d, [&](int body, double) {
            const int sb = slot[static_cast<std::size_t>(body)];
            if (sb >= 0 && fc.floating[static_cast<std::size_t>(fc.component[sb])])
                throw InputError("model '" + model.name + "': " + what + " acts along a direction on '" +
                                 model.masses[static_cast<std::size_t>(body)].name +
                                 "', which floats (no spring to the ground); a direction needs an anchored structure");
        });
    };
    for (std::size_t c = 0; c < model.contacts.size(); ++c)
        if (cfg.closed[c] && model.contacts[c].direction().weighted())
            refuse_floating(model.contacts[c].direction(), "contact '" + model.contacts[c].name + "'");
    for (std::size_t j = 0; j < model.jenkins.size(); ++j)
        if (cfg.slip[j] == 0 && model.jenkins[j].direction().weighted())
            refuse_floating(model.jenkins[j].direction(), "Jenkins element '" + model.jenkins[j].name + "'");
    return fc;
}

}  // namespace hsnc
