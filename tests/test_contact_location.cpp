// Where a contact switches, the engine's located instant puts its gap
// function at zero to rounding, and the switch is taken once: no close, open,
// close of one contact within a hair of time (issue: a contact closing at a
// clean crossing was located with G = -2.9e-14, 30 times its tolerance, and
// wrote close, open, close within 2.5e-14 s on a Jenkins + dampers model,
// where the 40-digit reference writes one close). Random chains with contacts,
// friction, Jenkins elements and dampers, on the Eigen solver and on the
// programs.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <limits>
#include <random>
#include <string>
#include <vector>

#include "engine_runner.h"
#include "error.h"
#include "random_model.h"

namespace hsnc {
namespace {

constexpr double kEps = std::numeric_limits<double>::epsilon();

// testing::draw's chain with dampers and one or two Jenkins elements.
Model jenkins_damper_model(unsigned seed) {
    testing::Drawn d = testing::draw(7000 + seed, 2 + static_cast<int>(seed % 2));
    testing::add_random_dampers(d, seed);
    Model& m = d.model;
    std::mt19937 rng(seed * 7919u + 1u);
    const int n = static_cast<int>(m.dof());
    for (int j = 0, nj = 1 + static_cast<int>(seed % 2); j < nj; ++j) {
        const int a = static_cast<int>(testing::uni(rng, 0, n - 0.001));
        int b = static_cast<int>(testing::uni(rng, -1, n - 0.001));
        if (b == a) b = kGround;
        m.jenkins.push_back({"j" + std::to_string(j + 1), a, b, testing::uni(rng, 5.0, 200.0), testing::uni(rng, 0.05, 2.0)});
    }
    return m;
}

struct Finding {
    int triples = 0;       // close, open, close (or open, close, open) of one contact within 1e-12 s
    double worst = 0.0;    // max |G| / its tolerance at a contact event
    std::string where;
};

void inspect(const Model& m, const testing::Outcome& o, const std::string& name, Finding& f) {
    const auto gap = [&](const testing::Recorded& e, const Contact& c, double& G, double& mag, double& rate) {
        const auto at = [&](const std::vector<double>& y, int b) { return b == kGround ? 0.0 : y[static_cast<std::size_t>(b)]; };
        G = at(e.x, c.a) - at(e.x, c.b) - c.gap;
        mag = std::fabs(at(e.x, c.a)) + std::fabs(at(e.x, c.b)) + std::fabs(c.gap);
        rate = at(e.v, c.a) - at(e.v, c.b);
    };
    for (std::size_t i = 0; i < o.events.size(); ++i) {
        const testing::Recorded& e = o.events[i];
        if (e.kind != EventKind::contact_close && e.kind != EventKind::contact_open) continue;
        const Contact& c = m.contacts[static_cast<std::size_t>(e.element)];
        double G, mag, rate;
        gap(e, c, G, mag, rate);
        // The rounding of G's terms and of the time (|G'| ulp(t)), as the engine's noise level.
        const double tol = 16 * kEps * (mag + std::fabs(rate) * std::fabs(e.t));
        if (std::fabs(G) / tol > f.worst) {
            f.worst = std::fabs(G) / tol;
            char text[200];
            std::snprintf(text, sizeof text, "%s at t = %.17g: %s of contact %d with G = %.3g (tolerance %.3g)",
                          name.c_str(), e.t, e.kind == EventKind::contact_close ? "close" : "open", e.element, G, tol);
            f.where = text;
        }
        // The same contact switching twice more within 1e-12 s.
        int again = 0;
        for (std::size_t k = i + 1; k < o.events.size() && o.events[k].t - e.t <= 1e-12; ++k)
            if (o.events[k].element == e.element &&
                (o.events[k].kind == EventKind::contact_close || o.events[k].kind == EventKind::contact_open))
                ++again;
        if (again >= 2) {
            ++f.triples;
            std::printf("%s: contact %d switches %d times within 1e-12 s of t = %.17g\n", name.c_str(), e.element,
                        again + 1, e.t);
        }
    }
}

// Runs model `seed` on both solvers; false (with a failure) when it does not run.
bool run_both(unsigned seed, Finding& f, int& runs) {
    const Model m = jenkins_damper_model(seed);
    for (testing::Solvers s : {testing::Solvers::generic, testing::Solvers::interp}) {
        const std::string name = "seed " + std::to_string(seed) + " " + testing::solvers_name(s);
        testing::Outcome o;
        try {
            o = testing::simulate(m, 4.0, 0.0, s);
        } catch (const RunError& e) {
            ADD_FAILURE() << name << ": " << e.what();
            return false;
        }
        if (o.summary.status != RunStatus::ok) {
            ADD_FAILURE() << name << ": " << o.summary.message;
            return false;
        }
        ++runs;
        inspect(m, o, name, f);
    }
    return true;
}

// A model where a contact was located far outside its rounding: the level a
// function inherits at an event was passed on from event to event (it only
// grew), and the locating Newton step, clamped to the last instant inside
// that level, was not refined: 43.8 times the contact's rounding on the Eigen
// solver (seed 265 of the test below: 14.1 times).
TEST(ContactLocation, AContactIsLocatedWithinItsRoundingAfterAnyEvent) {
    for (unsigned seed : {1217u}) {
        Finding f;
        int runs = 0;
        ASSERT_TRUE(run_both(seed, f, runs));
        std::printf("seed %u: worst located |G| %.3g times its tolerance (%s)\n", seed, f.worst, f.where.c_str());
        EXPECT_EQ(f.triples, 0);
        EXPECT_LE(f.worst, 4.0) << f.where;  // measured 0.044
    }
}

// The property on a few hundred random models: no contact switches three
// times within 1e-12 s, and none is located beyond a few times the rounding
// of its gap (its terms and the time's: the solvers' own terms may be larger,
// so the bound is 8, not 1; measured 3.9 here, 14.5 over 5000 models where a
// program's gap has terms of 54 m).
TEST(ContactLocation, RandomJenkinsDamperModelsSwitchOnceAtTheirZero) {
    Finding f;
    int runs = 0;
    for (unsigned seed = 0; seed < 300; ++seed) run_both(seed, f, runs);
    std::printf("%d runs: %d close/open/close triples, worst located |G| %.3g times its tolerance (%s)\n", runs,
                f.triples, f.worst, f.where.c_str());
    EXPECT_EQ(runs, 600);
    EXPECT_EQ(f.triples, 0);
    EXPECT_LE(f.worst, 8.0) << f.where;
}

}  // namespace
}  // namespace hsnc
