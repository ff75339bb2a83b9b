#include "sample_models.h"

#include <cstdint>

namespace hsnc {
namespace {

// A contact and a Jenkins element between two bodies, by their fields' names.
Contact make_contact(const std::string& name, int a, int b, double gap, double k) {
    Contact c;
    c.name = name, c.a = a, c.b = b, c.gap = gap, c.k = k;
    return c;
}
Jenkins make_jenkins(const std::string& name, int a, int b, double k, double slip_force) {
    Jenkins e;
    e.name = name, e.a = a, e.b = b, e.k = k, e.slip_force = slip_force;
    return e;
}

// One mass on a spring to ground: omega = sqrt(k/m), c = alpha + beta k/m.
Model oscillator(const std::string& name, double m, double k, double alpha, double beta) {
    Model md;
    md.name = name;
    md.masses = {{"m1", m}};
    md.springs = {{kGround, 0, k}};
    md.alpha = alpha;
    md.beta = beta;
    md.load = {0.3};
    md.x0 = {0.1};
    md.v0 = {-0.2};
    return md;
}

Model forced(Model md, double omega, double amplitude, double phase) {
    md.forcing.push_back({omega, phase, std::vector<double>(md.dof(), amplitude)});
    return md;
}

// SplitMix64 (Steele, Lea, Flood 2014): a tiny generator with a fixed output
// on every platform, unlike the <random> distributions.
struct SplitMix {
    std::uint64_t s;
    double uniform(double lo, double hi) {
        std::uint64_t z = (s += 0x9e3779b97f4a7c15ull);
        z = (z ^ (z >> 30)) * 0xbf58476d1ce4e5b9ull;
        z = (z ^ (z >> 27)) * 0x94d049bb133111ebull;
        z ^= z >> 31;
        return lo + (hi - lo) * static_cast<double>(z >> 11) * 0x1.0p-53;
    }
};

// A chain ground - m1 - ... - mn (- ground) with random values, one contact
// per neighbouring pair, friction on every other mass, and one harmonic.
Model random_chain(const std::string& name, std::uint64_t seed, int n, double beta_hi, bool grounded_end) {
    SplitMix r{seed};
    Model md;
    md.name = name;
    for (int i = 0; i < n; ++i) {
        md.masses.push_back({"m" + std::to_string(i + 1), r.uniform(0.5, 3.0)});
        if (i % 2 == 0) {
            FrictionSlot& f = md.set_friction(static_cast<std::size_t>(i));
            f.active = true;
            f.mu_k = r.uniform(0.1, 0.5);
            f.mu_s = f.mu_k * r.uniform(1.0, 1.5);
        }
    }
    md.springs.push_back({kGround, 0, r.uniform(1.0, 50.0)});
    for (int i = 0; i + 1 < n; ++i) md.springs.push_back({i, i + 1, r.uniform(1.0, 50.0)});
    if (grounded_end) md.springs.push_back({n - 1, kGround, r.uniform(1.0, 50.0)});
    for (int i = 0; i + 1 < n; ++i) {
        const double gap = r.uniform(-0.1, 0.2), k = r.uniform(20.0, 200.0);  // in this order (the bundled kernels)
        md.contacts.push_back(make_contact("c" + std::to_string(i + 1), i, i + 1, gap, k));
    }
    md.alpha = r.uniform(0.0, 0.2);
    md.beta = r.uniform(0.0, beta_hi);
    Harmonic h{r.uniform(1.0, 20.0), r.uniform(0.0, 3.0), {}};
    for (int i = 0; i < n; ++i) h.amplitude.push_back(r.uniform(-5.0, 5.0));
    md.forcing.push_back(h);
    for (int i = 0; i < n; ++i) {
        md.load.push_back(r.uniform(-1.0, 1.0));
        md.x0.push_back(r.uniform(-0.3, 0.3));
        md.v0.push_back(r.uniform(-1.0, 1.0));
    }
    md.t0 = r.uniform(0.0, 2.0);
    return md;
}

}  // namespace

std::vector<Model> sample_models() {
    std::vector<Model> s;
    // Two-mass system of the paper (Fig. 4, Table 1 scenario 1 with k* = 100, gap 0.2).
    {
        Model md;
        md.name = "paper_fig4";
        md.masses = {{"m1", 1.0}, {"m2", 2.0}};
        md.friction_slots = {{true, 0.6, 0.75}, {true, 0.6, 0.75}};
        md.springs = {{kGround, 0, 5.0}, {0, 1, 10.0}, {1, kGround, 40.0}};
        md.contacts = {make_contact("contact1", 0, 1, 0.2, 100.0)};
        md.beta = 0.1;
        md.forcing = {{175.5151, 0.0, {22500.0, -15000.0}}};
        md.load = {0.0, 0.0};
        md.x0 = {0.2, -0.1};
        md.v0 = {-5.0, -2.0};
        s.push_back(md);
    }
    // omega = 2 in every damping regime and at xi = 1 +- 1e-9.
    s.push_back(forced(oscillator("osc_undamped", 1.0, 4.0, 0.0, 0.0), 3.0, 0.7, 0.4));
    s.push_back(forced(oscillator("osc_under", 1.0, 4.0, 0.5, 0.0), 3.0, 0.7, 0.4));
    s.push_back(forced(oscillator("osc_critical", 1.0, 4.0, 4.0, 0.0), 3.0, 0.7, 0.4));
    s.push_back(forced(oscillator("osc_crit_below", 1.0, 4.0, 4.0 * (1 - 1e-9), 0.0), 3.0, 0.7, 0.4));
    s.push_back(forced(oscillator("osc_crit_above", 1.0, 4.0, 4.0 * (1 + 1e-9), 0.0), 3.0, 0.7, 0.4));
    s.push_back(forced(oscillator("osc_over", 1.0, 4.0, 10.0, 0.0), 3.0, 0.7, 0.4));
    s.push_back(forced(oscillator("osc_stiff_over", 1.0, 4.0, 0.0, 400.0), 3.0, 0.7, 0.4));  // xi ~ 400
    // Resonance (c = 0, omega = 2): exact, 1e-9 off, and both sides of the sinc-form band.
    s.push_back(forced(oscillator("res_exact", 1.0, 4.0, 0.0, 0.0), 2.0, 0.7, 0.4));
    s.push_back(forced(oscillator("res_near", 1.0, 4.0, 0.0, 0.0), 2.0 * (1 + 1e-9), 0.7, 0.4));
    s.push_back(forced(oscillator("res_band_in", 1.0, 4.0, 0.0, 0.0), 2.0 * (1 + 0.999 * kResonanceBand), 0.7, 0.4));
    s.push_back(forced(oscillator("res_band_out", 1.0, 4.0, 0.0, 0.0), 2.0 * (1 + 1.001 * kResonanceBand), 0.7, 0.4));
    // Floating pair (rigid-body mode), undamped and damped, with a contact to ground.
    for (double alpha : {0.0, 0.3}) {
        Model md;
        md.name = alpha == 0.0 ? "float_pair" : "float_pair_damped";
        md.masses = {{"m1", 1.5}, {"m2", 0.5}};
        md.friction_slots = {{true, 0.2, 0.3}, {false, 0.0, 0.0}};
        md.springs = {{0, 1, 8.0}};
        md.contacts = {make_contact("stop", 1, kGround, 0.5, 50.0)};
        md.alpha = alpha;
        md.beta = 0.01;
        md.forcing = {{1.3, 0.2, {0.0, 0.8}}};
        md.load = {0.1, -0.2};
        md.x0 = {0.0, 0.3};
        md.v0 = {0.4, -0.1};
        s.push_back(md);
    }
    // Jenkins elements (a slider per element; every configuration: stuck,
    // slipping + and -): a friction mass held by one element to its neighbour,
    // the other to ground, Rayleigh damping with the stuck elements in beta K;
    // and a free pair joined only by an element (rigid-body modes when it slips).
    {
        Model md;
        md.name = "jenkins_chain";
        md.masses = {{"m1", 1.2}, {"m2", 0.7}};
        md.friction_slots = {{true, 0.2, 0.3}, {false, 0.0, 0.0}};
        md.springs = {{kGround, 0, 6.0}, {0, 1, 3.0}};
        md.jenkins = {make_jenkins("j1", 0, 1, 12.0, 0.8), make_jenkins("j2", 1, kGround, 20.0, 1.5)};
        md.alpha = 0.1;
        md.beta = 0.02;
        md.forcing = {{2.3, 0.5, {0.4, 1.1}}};
        md.load = {0.2, -0.1};
        md.x0 = {0.05, -0.08};
        md.v0 = {0.3, -0.6};
        md.t0 = 0.4;
        s.push_back(md);
    }
    {
        Model md;
        md.name = "jenkins_free_pair";
        md.masses = {{"m1", 1.0}, {"m2", 3.0}};
        md.jenkins = {make_jenkins("j1", 0, 1, 9.0, 0.6)};
        md.forcing = {{1.7, 0.0, {1.0, 0.0}}};
        md.load = {0.0, 0.3};
        md.x0 = {0.1, 0.0};
        md.v0 = {0.5, 0.0};
        s.push_back(md);
    }
    // Friction between two bodies (FrictionSlot::partner): m2 rides m1 while stuck (one
    // coordinate, the pair's mass and stiffness gathered), slides on it otherwise;
    // grounded with a stop, and floating (rigid-body modes of the pair).
    {
        Model md;
        md.name = "friction_pair";
        md.masses = {{"m1", 2.0}, {"m2", 0.6}};
        md.friction_slots = {{false, 0.0, 0.0}, {true, 0.25, 0.4, -1, 0}};
        md.springs = {{kGround, 0, 30.0}, {1, kGround, 4.0}};
        md.contacts = {make_contact("stop", 0, kGround, 0.15, 300.0)};
        md.alpha = 0.2;
        md.beta = 0.005;
        md.forcing = {{4.1, 0.3, {5.0, -1.2}}};
        md.load = {0.1, 0.2};
        md.x0 = {0.02, 0.07};
        md.v0 = {0.4, -0.3};
        md.t0 = 0.2;
        s.push_back(md);
    }
    {
        Model md;
        md.name = "friction_pair_floating";
        md.masses = {{"m1", 1.0}, {"m2", 0.5}, {"m3", 0.8}};
        md.friction_slots = {{false, 0.0, 0.0}, {true, 0.3, 0.45, -1, 0}, {false, 0.0, 0.0}};
        md.springs = {{1, 2, 6.0}};
        md.alpha = 0.0;
        md.beta = 0.01;
        md.forcing = {{1.9, 0.0, {2.0, 0.0, 0.5}}};
        md.load = {0.0, 0.1, -0.1};
        md.x0 = {0.0, 0.1, 0.3};
        md.v0 = {0.2, 0.5, 0.0};
        s.push_back(md);
    }
    // Dampers (non-proportional damping: state-space pseudo-modes) beside Rayleigh
    // damping: a stop and friction on m1, so that the configurations take
    // complex pairs (all free; the stop closed) and real eigenvalues only (m1
    // stuck, the stop open: m2 alone at zeta 1.28).
    {
        Model md;
        md.name = "dashpot_pair";
        md.masses = {{"m1", 1.0}, {"m2", 0.8}};
        md.friction_slots = {{true, 0.2, 0.3}, {false, 0.0, 0.0}};
        md.springs = {{kGround, 0, 20.0}, {0, 1, 8.0}};
        md.dampers = {{1, kGround, 6.0}, {0, 1, 0.5}};
        md.contacts = {make_contact("stop", 1, kGround, 0.1, 60.0)};
        md.alpha = 0.05;
        md.beta = 0.002;
        md.forcing = {{2.5, 0.3, {1.0, 0.0}}};
        md.load = {0.1, -0.05};
        md.x0 = {0.05, 0.12};
        md.v0 = {-0.3, 0.2};
        md.t0 = 0.1;
        s.push_back(md);
    }
    // Pseudo-random chains: light and heavy damping, grounded and free end.
    s.push_back(random_chain("rand_a", 1, 2, 0.02, true));
    s.push_back(random_chain("rand_b", 2, 3, 0.5, true));
    s.push_back(random_chain("rand_c", 3, 3, 0.05, false));
    s.push_back(random_chain("rand_d", 4, 4, 0.01, true));
    return s;
}

std::vector<Configuration> all_configurations(const Model& model) {
    std::vector<int> friction;
    for (std::size_t i = 0; i < model.dof(); ++i)
        if (model.has_friction(i)) friction.push_back(static_cast<int>(i));
    const std::size_t nc = model.contacts.size(), bits = nc + friction.size(), nj = model.jenkins.size();
    std::uint64_t states = 1;  // of the Jenkins elements: stuck, slipping + or -
    for (std::size_t j = 0; j < nj; ++j) states *= 3;
    std::vector<Configuration> out;
    for (std::uint64_t code = 0; code < (std::uint64_t{1} << bits); ++code) {
        for (std::uint64_t js = 0; js < states; ++js) {
            Configuration cfg = Configuration::all_open(model);
            for (std::size_t c = 0; c < nc; ++c) cfg.closed[c] = (code >> c) & 1u;
            for (std::size_t k = 0; k < friction.size(); ++k) cfg.stuck[friction[k]] = (code >> (nc + k)) & 1u;
            std::uint64_t rest = js;
            for (std::size_t j = 0; j < nj; ++j, rest /= 3)
                cfg.slip[j] = static_cast<signed char>(rest % 3 == 0 ? 0 : rest % 3 == 1 ? 1 : -1);
            out.push_back(cfg);
        }
    }
    return out;
}

}  // namespace hsnc
