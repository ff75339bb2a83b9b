#include "model_hash.h"

#include <cstdio>

namespace hsnc {
namespace {

// %.17g round-trips every finite double (max_digits10 = 17).
std::string num(double v) {
    char buf[40];
    std::snprintf(buf, sizeof buf, "%.17g", v == 0.0 ? 0.0 : v);  // -0 and +0 hash alike
    return buf;
}

}  // namespace

std::string model_canonical_text(const Model& model) {
    std::string t = "hsnc-model-v1\nname " + model.name + "\ng " + num(model.g) + "\n";
    for (std::size_t i = 0; i < model.dof(); ++i) {
        const Mass& m = model.masses[i];
        const FrictionSlot& f = model.friction_slot(i);
        t += "mass " + m.name + " " + num(m.m) + " " + (f.active ? "friction " : "nofriction ") + num(f.mu_k) + " " +
             num(f.mu_s) + "\n";
    }
    for (const Spring& s : model.springs)
        t += "spring " + std::to_string(s.a) + " " + std::to_string(s.b) + " " + num(s.k) + "\n";
    for (const Contact& c : model.contacts) {
        t += "contact " + c.name + " " + std::to_string(c.a) + " " + std::to_string(c.b) + " " +
             num(c.gap) + " " + num(c.k);
        if (c.c != 0.0) t += " c=" + num(c.c);                                                 // only when given
        if (c.rigid()) t += " e=" + num(c.restitution);                                        // only when given
        for (const Weight& w : c.weights) t += " " + std::to_string(w.body) + ":" + num(w.w);  // only when given
        t += "\n";
    }
    t += "damping " + num(model.alpha) + " " + num(model.beta) + "\n";
    for (const Harmonic& h : model.forcing) {
        t += "forcing " + num(h.omega) + " " + num(h.phase);
        for (double a : h.amplitude) t += " " + num(a);
        t += "\n";
    }
    // Added only when present, so the hash of a model without them is unchanged.
    for (const FrictionElement& f : model.frictions)
        t += "friction " + f.name + " " + std::to_string(f.a) + " " + std::to_string(f.b) + " " + num(f.mu_k) + " " +
             num(f.mu_s) + " " + num(f.normal) + "\n";
    for (const Damper& d : model.dampers)
        t += "damper " + std::to_string(d.a) + " " + std::to_string(d.b) + " " + num(d.c) + "\n";
    if (model.coupled_mass()) {  // the off-diagonal entries, upper triangle (M_ii is each mass's m)
        const std::size_t n = model.dof();
        t += "mass_matrix";
        for (std::size_t i = 0; i < n; ++i)
            for (std::size_t j = i + 1; j < n; ++j) t += " " + num(model.mass_entry(i, j));
        t += "\n";
    }
    for (const Jenkins& j : model.jenkins) {
        t += "jenkins " + j.name + " " + std::to_string(j.a) + " " + std::to_string(j.b) + " " + num(j.k) + " " +
             num(j.slip_force);
        for (const Weight& w : j.weights) t += " " + std::to_string(w.body) + ":" + num(w.w);  // only when given
        t += "\n";
    }
    t += "load";
    for (double l : model.load) t += " " + num(l);
    t += "\n";
    return t;
}

std::uint64_t fnv1a64(const std::string& bytes) {
    std::uint64_t h = 14695981039346656037ull;  // FNV offset basis
    for (unsigned char c : bytes) {
        h ^= c;
        h *= 1099511628211ull;  // FNV prime
    }
    return h;
}

std::uint64_t model_hash(const Model& model) { return fnv1a64(model_canonical_text(model)); }

}  // namespace hsnc
