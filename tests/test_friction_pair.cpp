// Friction between two bodies (interface.md section 5, [[friction]] between
// two masses): the friction acts on the relative velocity w = v[a] - v[b];
// stuck, the two move as one body of their summed mass; it releases when the
// force needed to keep w = 0, D = (m_b A_a - m_a A_b)/(m_a + m_b), exceeds
// mu_s N.
//
// The truths are closed forms written here: a block on a block (the lower
// one on a spring) started moving together, and a floating pair driven by a
// harmonic force on the lower block.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <fstream>
#include <functional>
#include <iterator>
#include <string>
#include <utility>
#include <vector>

#include "cli_runner.h"
#include "engine_runner.h"
#include "error.h"
#include "hsnc/simulate.h"
#include "integrators.h"
#include "model.h"
#include "model_reader.h"
#include "reference_engine.h"
#include "sample_models.h"
#include "assembly.h"

namespace hsnc {
namespace {

using testing::Outcome;

// A lower block ("bottom", on a spring k to ground, no friction with the
// ground) and an upper block ("top") on it, friction between them with
// N = m_top g.
std::string block_on_block(double mb, double mt, double k, double mu_k, double mu_s, double v0,
                           const std::string& extra = "") {
    char text[1024];
    std::snprintf(text, sizeof text, R"(name = "block-on-block"
[parameters]
g = 9.81
[[mass]]
name = "bottom"
m = %.17g
[[mass]]
name = "top"
m = %.17g
[[spring]]
between = ["ground", "bottom"]
k = %.17g
[[friction]]
name = "interface"
between = ["top", "bottom"]
mu_k = %.17g
mu_s = %.17g
normal = "%.17g * g"
[initial]
v = { bottom = %.17g, top = %.17g }
)",
                  mb, mt, k, mu_k, mu_s, mt, v0, v0);
    return text + extra;
}

// Root of f in [a, b] (f(a), f(b) of opposite signs) by bisection to the last bit.
double root(const std::function<double(double)>& f, double a, double b) {
    const double fa = f(a);
    for (int i = 0; i < 200; ++i) {
        const double m = 0.5 * (a + b);
        if (m == a || m == b) break;
        ((f(m) > 0) == (fa > 0) ? a : b) = m;
    }
    return 0.5 * (a + b);
}

// Stuck, the pair oscillates with Omega = sqrt(k/(m_b + m_t)); it releases
// where the force the friction must hold, m_t k x/(m_b + m_t), reaches
// mu_s N; then the top slides under -mu_k N and the bottom oscillates about
// mu_k N/k with sqrt(k/m_b), until w = 0.
TEST(FrictionPairClosedForm, BlockOnBlockReleasesAtMuSNAndSlides) {
    const double mb = 1.0, mt = 0.5, k = 100.0, mu_k = 0.3, mu_s = 0.4, g = 9.81;
    const double M = mb + mt, W = std::sqrt(k / M), wb = std::sqrt(k / mb), N = mt * g;
    // On the generic solver and on the derivation's programs (the rider folded into its partner's coordinate).
    for (const testing::Solvers solvers : {testing::Solvers::generic, testing::Solvers::interp}) {
        SCOPED_TRACE(testing::solvers_name(solvers));
        std::vector<EventKind> seen;
        for (const double v0 : {1.0, 0.7}) {  // then it slides back (reversal), or sticks again
            SCOPED_TRACE("v0 = " + std::to_string(v0));
            const double xs = mu_s * g * M / k, ts = std::asin(xs * W / v0) / W, vs = v0 * std::cos(W * ts);
            const double c = mu_k * N / k;
            auto top = [&](double tau) { return xs + vs * tau - 0.5 * mu_k * g * tau * tau; };
            auto top_v = [&](double tau) { return vs - mu_k * g * tau; };
            auto bottom = [&](double tau) { return c + (xs - c) * std::cos(wb * tau) + vs / wb * std::sin(wb * tau); };
            auto bottom_v = [&](double tau) { return -(xs - c) * wb * std::sin(wb * tau) + vs * std::cos(wb * tau); };
            // w = top_v - bottom_v > 0 right after the release; its first zero ends the slide.
            double lo = 1e-9, hi = 1e-9;
            while (top_v(hi) - bottom_v(hi) > 0) lo = hi, hi *= 1.1;
            const double tau2 = root([&](double tau) { return top_v(tau) - bottom_v(tau); }, lo, hi), t2 = ts + tau2;
            // At w = 0 the force to hold is m_t k x_b / M: it sticks if below mu_s N, else slides back.
            const bool sticks = mt * k * std::fabs(bottom(tau2)) / M < mu_s * N;
            const double xb2 = bottom(tau2), xt2 = top(tau2), v2 = top_v(tau2);

            const Model md = parse_model(block_on_block(mb, mt, k, mu_k, mu_s, v0), "block.toml");
            ASSERT_EQ(md.friction_slot(1).partner, 0);
            const double t_end = t2 + (sticks ? 0.05 : 1e-3);
            const Outcome r = testing::simulate(md, t_end, 0.002, solvers);
            ASSERT_EQ(r.summary.status, RunStatus::ok) << r.summary.message;
            ASSERT_EQ(r.events.size(), 2u);
            EXPECT_EQ(r.events[0].kind, EventKind::release);
            EXPECT_EQ(r.events[0].element, 1);
            EXPECT_NEAR(r.events[0].t, ts, 1e-15);
            EXPECT_NEAR(r.events[0].x[0], xs, 1e-15);
            EXPECT_NEAR(r.events[0].x[1], xs, 1e-15);
            EXPECT_EQ(r.events[1].kind, sticks ? EventKind::stick : EventKind::reversal);
            EXPECT_NEAR(r.events[1].t, t2, 1e-13);
            seen.push_back(r.events[1].kind);
            std::printf("release at %.17g (closed form %.17g), then %s at %.17g (%.17g)\n", r.events[0].t, ts,
                        event_kind_name(r.events[1].kind), r.events[1].t, t2);
            double worst = 0.0;
            for (const auto& s : r.samples) {
                double xb, xt;
                if (s.t <= ts) {
                    xb = xt = v0 / W * std::sin(W * s.t);
                } else if (s.t <= t2) {
                    xb = bottom(s.t - ts), xt = top(s.t - ts);
                } else if (sticks) {  // one body again, the top at its new offset
                    xb = xb2 * std::cos(W * (s.t - t2)) + v2 / W * std::sin(W * (s.t - t2)), xt = xb + (xt2 - xb2);
                } else {
                    continue;
                }
                worst = std::max({worst, std::fabs(s.x[0] - xb), std::fabs(s.x[1] - xt)});
            }
            std::printf("max |x - closed form| over the stuck and sliding phases: %.2g m\n", worst);
            EXPECT_LT(worst, 1e-13);
        }
        EXPECT_EQ(seen, (std::vector<EventKind>{EventKind::reversal, EventKind::stick}));
    }
}

// Two blocks on a frictionless floor, friction between them, a harmonic
// force F sin(omega t) on the lower one: stuck they are one floating body (a
// rigid-body mode of the merged coordinate) accelerating F sin/M from rest,
// and the top slips when m_t F sin(omega t)/M reaches mu_s N.
TEST(FrictionPairClosedForm, FloatingPairDrivenByAHarmonicForce) {
    const double mb = 2.0, mt = 1.0, M = mb + mt, mu_s = 0.5, mu_k = 0.4, g = 9.81, F = 30.0, w = 3.0;
    const std::string text = std::string(R"(name = "floating-blocks"
[[mass]]
name = "bottom"
m = 2.0
[[mass]]
name = "top"
m = 1.0
[[friction]]
between = ["top", "bottom"]
mu_k = 0.4
mu_s = 0.5
normal = 9.81
[[forcing]]
omega = 3.0
amplitude = { bottom = 30.0 }
)");
    const Model md = parse_model(text, "floating.toml");
    const double ts = std::asin(mu_s * g * M / F) / w;  // m_t F sin/M = mu_s m_t g
    for (const testing::Solvers solvers : {testing::Solvers::generic, testing::Solvers::interp}) {
        SCOPED_TRACE(testing::solvers_name(solvers));
        const Outcome r = testing::simulate(md, ts + 0.2, 0.01, solvers);
        ASSERT_EQ(r.summary.status, RunStatus::ok) << r.summary.message;
        ASSERT_GE(r.events.size(), 1u);
        EXPECT_EQ(r.events[0].kind, EventKind::release);
        EXPECT_EQ(md.friction_event_name(r.events[0].element), "friction1");
        EXPECT_NEAR(r.events[0].t, ts, 1e-14);
        double worst = 0.0;
        for (const auto& s : r.samples) {
            if (s.t > ts) break;
            const double x = F / (M * w) * (s.t - std::sin(w * s.t) / w);  // from rest, together
            worst = std::max({worst, std::fabs(s.x[0] - x), std::fabs(s.x[1] - x)});
        }
        std::printf("release at %.17g (closed form %.17g); stuck phase within %.2g m\n", r.events[0].t, ts, worst);
        EXPECT_LT(worst, 1e-14);
        // Sliding, the top decelerates relative to the bottom: w' = -mu_k g - (F sin - mu_k N)/m_b.
        const auto& after = r.samples.back();
        EXPECT_GT(after.x[0], after.x[1]);  // the bottom has run ahead
    }
}

// The bundled load on a shaking table: releases and sticks alternate, and
// from each stick to the next release the load rides at a constant offset.
TEST(FrictionPairClosedForm, TheBundledLoadRidesAtAConstantOffsetWhileStuck) {
    const Model md = read_model(std::string(HSNC_SOURCE_DIR) + "/examples/friction/stacked_blocks.toml");
    for (const testing::Solvers solvers : {testing::Solvers::generic, testing::Solvers::interp}) {
        SCOPED_TRACE(testing::solvers_name(solvers));
        const Outcome r = testing::simulate(md, 5.0, 0.0, solvers);
        ASSERT_EQ(r.summary.status, RunStatus::ok) << r.summary.message;
        ASSERT_EQ(r.events.size(), 39u);
        double worst = 0.0;
        for (std::size_t e = 0; e < r.events.size(); ++e) {
            EXPECT_EQ(r.events[e].kind, e % 2 == 0 ? EventKind::release : EventKind::stick) << "event " << e;
            EXPECT_EQ(md.friction_event_name(r.events[e].element), "interface");
            if (e % 2 == 1 && e + 1 < r.events.size()) {
                const double stuck = r.events[e].x[1] - r.events[e].x[0], left = r.events[e + 1].x[1] - r.events[e + 1].x[0];
                worst = std::max(worst, std::fabs(left - stuck));
                EXPECT_EQ(r.events[e].v[0], r.events[e].v[1]) << "event " << e;  // one velocity from the stick on
            }
        }
        std::printf("19 stuck phases: the offset of the load moved by at most %.2g m\n", worst);
        EXPECT_LT(worst, 1e-15);
    }
}

// Against an independent integrator: CVODE (Adams, rtol 1e-12) with its own
// root finding on the same switch functions, on models that exercise the
// pair in every way: a block on a block on a spring, forced; the same with a
// stop that the lower block hits; a three-mass chain whose middle mass
// carries a block.
TEST(FrictionPairCvode, EventsAgreeWithCvode) {
#if !HSNC_WITH_CVODE
    GTEST_SKIP() << "built without CVODE";
#endif
    const std::string forced = block_on_block(1.0, 0.5, 100.0, 0.3, 0.4, 0.0,
                                              "[[forcing]]\nomega = 6.0\namplitude = { bottom = 8.0 }\n[damping]\nalpha = 0.1\n");
    const std::string stop = forced + "[[contact]]\nname = \"stop\"\nbetween = [\"bottom\", \"ground\"]\ngap = 0.08\nk = 3000.0\n";
    const std::string chain = R"(name = "chain-with-a-block"
[[mass]]
name = "m1"
m = 1.0
[[mass]]
name = "m2"
m = 1.5
[[mass]]
name = "m3"
m = 1.0
[[mass]]
name = "block"
m = 0.4
[[spring]]
between = ["ground", "m1"]
k = 80.0
[[spring]]
between = ["m1", "m2"]
k = 60.0
[[spring]]
between = ["m2", "m3"]
k = 60.0
[[spring]]
between = ["m3", "ground"]
k = 40.0
[[friction]]
name = "carried"
between = ["block", "m2"]
mu_k = 0.2
mu_s = 0.3
normal = 3.924
[damping]
alpha = 0.05
[[forcing]]
omega = 7.0
amplitude = { m1 = 6.0 }
)";
    for (const auto& [name, text] : {std::pair{"forced block on a block", forced}, std::pair{"with a stop", stop},
                                     std::pair{"chain carrying a block", chain}}) {
        SCOPED_TRACE(name);
        const Model md = parse_model(text, "pair.toml");
        const Outcome rec = testing::baseline(md, 10.0, 1e-12, 1e-14, Method::cvode);
        ASSERT_EQ(rec.summary.status, RunStatus::ok) << rec.summary.message;
        for (const testing::Solvers solvers : {testing::Solvers::generic, testing::Solvers::interp}) {
            const Outcome a = testing::simulate(md, 10.0, 0.0, solvers);
            ASSERT_EQ(a.summary.status, RunStatus::ok) << a.summary.message;
            ASSERT_EQ(a.events.size(), rec.events.size()) << testing::solvers_name(solvers);
            double dt = 0.0;
            std::size_t pair_events = 0;
            for (std::size_t e = 0; e < a.events.size(); ++e) {
                ASSERT_EQ(a.events[e].kind, rec.events[e].kind) << "event " << e;
                ASSERT_EQ(a.events[e].element, rec.events[e].element) << "event " << e;
                dt = std::max(dt, std::fabs(a.events[e].t - rec.events[e].t));
                const bool contact =
                    a.events[e].kind == EventKind::contact_close || a.events[e].kind == EventKind::contact_open;
                pair_events += contact ? 0 : 1;
            }
            std::printf("%s (%s): %zu events (%zu of the pair) over 10 s, hsnc against CVODE at most %.2g s apart\n",
                        name, testing::solvers_name(solvers), a.events.size(), pair_events, dt);
            EXPECT_GE(pair_events, 4u);
            EXPECT_LT(dt, 1e-9);  // measured 1.2e-11 .. 3.3e-11 s
        }
    }
}

// The CLN reference with friction between two bodies (a stuck pair rides one
// coordinate, reference/mp_segment.cpp; the relative velocity, the force D
// and their tie series, reference/reference.cpp): at 30 and 60 digits it
// agrees with itself, the double engine (interpreter) with it, and the
// block on a block's release instant with the closed form.
TEST(FrictionPairReference, AgreesWithItselfAndWithTheInterpreter) {
    const std::string forced = block_on_block(1.0, 0.5, 100.0, 0.3, 0.4, 0.0,
                                              "[[forcing]]\nomega = 6.0\namplitude = { bottom = 8.0 }\n[damping]\nalpha = 0.1\n");
    const std::string stop = forced + "[[contact]]\nname = \"stop\"\nbetween = [\"bottom\", \"ground\"]\ngap = 0.08\nk = 3000.0\n";
    std::vector<Model> models = {parse_model(forced, "forced.toml"), parse_model(stop, "stop.toml"),
                                 read_model(std::string(HSNC_SOURCE_DIR) + "/examples/friction/stacked_blocks.toml")};
    for (const Model& m : sample_models())
        if (!friction_pairs(m).empty()) models.push_back(m);
    ASSERT_EQ(models.size(), 5u);
    std::size_t all_pair_events = 0;
    for (const Model& m : models) {
        const double t_end = 5.0;
        testing::Recorder r30(m.dof(), m.state_size()), r60(m.dof(), m.state_size());
        EngineOptions opt;
        opt.t_end = t_end;
        const reference::PreciseRun a = reference::simulate_precise(m, 30, opt, r30);
        const reference::PreciseRun b = reference::simulate_precise(m, 60, opt, r60);
        ASSERT_EQ(a.summary.status, RunStatus::ok) << m.name << ": " << a.summary.message;
        ASSERT_EQ(b.summary.status, RunStatus::ok) << m.name << ": " << b.summary.message;
        const Outcome h = testing::simulate(m, t_end, 0.0, testing::Solvers::interp);
        ASSERT_EQ(a.events.size(), b.events.size()) << m.name;
        ASSERT_EQ(h.events.size(), b.events.size()) << m.name;
        double self = 0.0, vs_double = 0.0;
        std::size_t pair_events = 0;
        for (std::size_t k = 0; k < b.events.size(); ++k) {
            EXPECT_EQ(a.events[k].kind, b.events[k].kind) << m.name << " event " << k;
            EXPECT_EQ(h.events[k].kind, b.events[k].kind) << m.name << " event " << k;
            EXPECT_EQ(h.events[k].element, b.events[k].element) << m.name << " event " << k;
            self = std::max(self, reference::relative_difference(a.events[k].t, b.events[k].t, 1.0));
            vs_double = std::max(vs_double, std::fabs(h.events[k].t - cln::double_approx(b.events[k].t)));
            pair_events += b.events[k].kind == EventKind::stick || b.events[k].kind == EventKind::release;
        }
        std::printf("%s: %zu events (%zu stick or release); reference 30 vs 60 digits %.2g s, interpreter %.2g s\n",
                    m.name.c_str(), b.events.size(), pair_events, self, vs_double);
        EXPECT_GE(pair_events, 1u) << m.name;
        EXPECT_LT(self, 1e-25) << m.name;
        EXPECT_LT(vs_double, 1e-12) << m.name;
        all_pair_events += pair_events;
    }
    EXPECT_GE(all_pair_events, 60u);
}

std::string input_error(const std::string& text) {
    try {
        parse_model(text, "pair.toml");
    } catch (const InputError& e) {
        return e.what();
    }
    ADD_FAILURE() << "no error for:\n" << text;
    return "";
}

TEST(FrictionPairReader, KeysAndRefusals) {
    const std::string two = "name = \"p\"\n[[mass]]\nname = \"a\"\nm = 1\n[[mass]]\nname = \"b\"\nm = 2\n";
    const std::string element = "[[friction]]\nbetween = [\"a\", \"b\"]\nmu_k = 0.3\n";
    EXPECT_EQ(input_error(two + element),
              "pair.toml:8: key 'friction[1].normal': required key is missing (between two bodies the normal force is "
              "not a weight m*g: give it)");
    const Model md = parse_model(two + element + "normal = 5\n", "pair.toml");
    EXPECT_EQ(md.friction_slot(0).partner, 1);
    EXPECT_TRUE(md.has_friction(0));
    EXPECT_FALSE(md.has_friction(1));
    // A partner may have a friction of its own (a chain, tests/test_shared_partner.cpp); a body
    // with one against the ground is the partner, whichever way `between` is written.
    const std::string b_friction = "name = \"p\"\n[[mass]]\nname = \"a\"\nm = 1\n[[mass]]\nname = \"b\"\nm = 2\nmu_k = 0.1\n";
    for (const std::string& text :
         {b_friction + element + "normal = 5\n",
          two + element + "normal = 5\n[[friction]]\nbetween = [\"b\", \"ground\"]\nmu_k = 0.2\n",
          two + "[[friction]]\nbetween = [\"b\", \"a\"]\nmu_k = 0.3\nnormal = 5\n[[friction]]\nbetween = [\"b\", "
                "\"ground\"]\nmu_k = 0.2\n"}) {
        const Model chain = parse_model(text, "pair.toml");
        EXPECT_EQ(chain.friction_slot(0).partner, 1);
        EXPECT_EQ(chain.friction_slot(1).partner, kGround);
        EXPECT_TRUE(chain.friction_chain());
    }
    // Two frictions against the ground on one body are still one too many.
    EXPECT_NE(input_error(two + "[[friction]]\nbetween = [\"a\", \"ground\"]\nmu_k = 0.3\n[[friction]]\nbetween = "
                                "[\"a\", \"ground\"]\nmu_k = 0.2\n")
                  .find("'a' already has friction"),
              std::string::npos);
    EXPECT_NE(input_error(two + "[[damper]]\nbetween = [\"a\", \"b\"]\nc = 1\n" + element + "normal = 5\n")
                  .find("non-proportional damping"),
              std::string::npos);
}

TEST(FrictionPairCli, EventsNameTheElementAndWhatCannotTakeItRefuses) {
    const std::string model = testing::temp_path("pair-cli.toml"), events = testing::temp_path("pair-cli.csv");
    std::ofstream(model) << block_on_block(1.0, 0.5, 100.0, 0.3, 0.4, 1.0);
    const testing::CliRun ok = testing::run_hsnc("simulate " + model + " --t-end 2 --events " + events);
    ASSERT_EQ(ok.exit_code, 0) << ok.err;
    std::ifstream in(events);
    std::string header, first;
    std::getline(in, header);
    std::getline(in, first);
    EXPECT_EQ(header, "t,kind,element,x_bottom,x_top,v_bottom,v_top");
    EXPECT_NE(first.find(",release,interface,"), std::string::npos) << first;
    const testing::CliRun bad = testing::run_hsnc("simulate " + model + " --t-end 1 --method ab4 --h 1e-3");
    EXPECT_EQ(bad.exit_code, 2) << bad.err;
    EXPECT_NE(bad.err.find("friction between two bodies ([[friction]] 'interface')"), std::string::npos) << bad.err;
    // The reference takes it, and gives the same events as the double engine.
    const testing::CliRun ref = testing::run_hsnc("simulate " + model + " --t-end 2 --precision mp:30");
    EXPECT_EQ(ref.exit_code, 0) << ref.err;
    EXPECT_NE(ref.out.find("events=7 contact_close=0 contact_open=0 stick=3 release=3 reversal=1"), std::string::npos)
        << ref.out;
    EXPECT_NE(ok.out.find("events=7 contact_close=0 contact_open=0 stick=3 release=3 reversal=1"), std::string::npos)
        << ok.out;
    const testing::CliRun sweep_kernels = testing::run_hsnc("generate " + model + " --params g -o " + testing::temp_path("pair-gen-p"));
    EXPECT_EQ(sweep_kernels.exit_code, 2);
    EXPECT_NE(sweep_kernels.err.find("friction between two bodies"), std::string::npos) << sweep_kernels.err;
    // The derivation folds a stuck pair into one coordinate: the interpreter and
    // the JIT write the same events; generate and inspect take the model.
    const std::string bytes[2] = {testing::events_csv(model, "--t-end 2 --no-cache --kernels interp"),
                                  testing::events_csv(model, "--t-end 2 --no-cache --kernels jit")};
    EXPECT_EQ(bytes[0], bytes[1]);
    EXPECT_NE(bytes[0].find(",release,interface,"), std::string::npos) << bytes[0];
    const testing::CliRun gen = testing::run_hsnc("generate " + model + " -o " + testing::temp_path("pair-gen"));
    EXPECT_EQ(gen.exit_code, 0) << gen.err;
    EXPECT_NE(gen.out.find("wrote 2 kernels"), std::string::npos) << gen.out;
    const testing::CliRun cpp = testing::run_hsnc("inspect " + model + " --config stuck=interface --format cpp");
    EXPECT_EQ(cpp.exit_code, 0) << cpp.err;
    EXPECT_NE(cpp.out.find("top (rides bottom)"), std::string::npos) << cpp.out;
}

}  // namespace
}  // namespace hsnc
