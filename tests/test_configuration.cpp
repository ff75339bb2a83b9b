#include <gtest/gtest.h>

#include "assembly.h"
#include "configuration.h"
#include "error.h"
#include "switch_function.h"

namespace hsnc {
namespace {

// Paper Fig. 4 topology with unit-ish numbers, built in code.
Model two_mass() {
    Model m;
    m.name = "two";
    m.masses = {{"m1", 1.0}, {"m2", 2.0}};
    m.friction_slots = {{true, 0.6, 0.75}, {true, 0.6, 0.75}};
    m.springs = {{kGround, 0, 5.0}, {0, 1, 10.0}, {1, kGround, 40.0}};
    m.contacts = {{"c1", 0, 1, 0.2, 100.0}};
    m.load = {0.0, 1.0};
    m.x0 = {0.0, 0.0};
    m.v0 = {0.0, 0.0};
    return m;
}

TEST(Configuration, SpecRoundTrips) {
    const Model m = two_mass();
    const Configuration c = Configuration::parse(m, "closed=c1 stuck=m2");
    EXPECT_TRUE(c.closed[0]);
    EXPECT_FALSE(c.stuck[0]);
    EXPECT_TRUE(c.stuck[1]);
    EXPECT_EQ(c.spec(m), "closed=c1 stuck=m2");
    EXPECT_EQ(Configuration::parse(m, c.spec(m)), c);
    EXPECT_EQ(c.key(), "c1_s01");
    EXPECT_EQ(Configuration::parse(m, ""), Configuration::all_open(m));
}

TEST(Configuration, UnknownNamesAreInputErrors) {
    const Model m = two_mass();
    try {
        Configuration::parse(m, "closed=c9");
        FAIL();
    } catch (const InputError& e) {
        EXPECT_NE(std::string(e.what()).find("no contact named 'c9'"), std::string::npos);
    }
    EXPECT_THROW(Configuration::parse(m, "stuck=m3"), InputError);
    EXPECT_THROW(Configuration::parse(m, "open=c1"), InputError);
}

TEST(Assembly, ClosedContactAddsStiffnessAndPreload) {
    const Model m = two_mass();
    const Configuration c = Configuration::parse(m, "closed=c1");
    const Eigen::MatrixXd K = stiffness_matrix(m, c);
    EXPECT_DOUBLE_EQ(K(0, 0), 5.0 + 10.0 + 100.0);
    EXPECT_DOUBLE_EQ(K(0, 1), -110.0);
    EXPECT_DOUBLE_EQ(K(1, 1), 10.0 + 40.0 + 100.0);
    const Eigen::VectorXd f = constant_force(m, c);
    EXPECT_DOUBLE_EQ(f(0), 100.0 * 0.2);        // +k*d on a
    EXPECT_DOUBLE_EQ(f(1), 1.0 - 100.0 * 0.2);  // load - k*d on b
}

// The friction decisions' force on a mass from its own elements
// (ElementIndex) is the force from the model's whole list, bit for bit: every
// kind of element, every state of each (contacts open and closed, Jenkins
// elements stuck and slipping), grounded and between masses.
TEST(Assembly, ForceFromAMassOwnElementsIsTheForceFromAll) {
    Model m = two_mass();
    m.masses.push_back({"m3", 0.5});
    m.set_friction(m.masses.size() - 1) = {true, 0.3, 0.4};
    m.springs.push_back({1, 2, 7.0});
    m.contacts.push_back({"c2", 2, kGround, -0.1, 300.0});
    m.dampers = {{0, 2, 0.3}, {2, kGround, 0.05}};
    m.jenkins = {{"j1", 0, 2, 20.0, 0.5}, {"j2", kGround, 1, 15.0, 0.2}};
    m.load = {0.1, 1.0, -0.4};
    m.alpha = 0.02;
    m.beta = 0.003;
    m.forcing.push_back({3.0, 0.2, {1.0, 0.0, -2.0}});
    const ElementIndex elements(m);
    const double x[] = {0.013, -0.27, 0.191, 0.031, -0.007}, v[] = {0.5, -1.25, 0.75};
    for (int closed = 0; closed < 4; ++closed)
        for (int slip0 = -1; slip0 <= 1; ++slip0)
            for (int slip1 = -1; slip1 <= 1; ++slip1) {
                Configuration c = Configuration::all_open(m);
                c.closed[0] = closed & 1, c.closed[1] = closed >> 1;
                c.slip[0] = static_cast<signed char>(slip0), c.slip[1] = static_cast<signed char>(slip1);
                for (int i = 0; i < 3; ++i) {
                    const double all = force_on_mass(m, c, i, 0.7, x, v);
                    EXPECT_EQ(force_on_mass(m, c, i, 0.7, x, v, &elements), all) << c.spec(m) << " m" << i + 1;
                    EXPECT_NE(all, 0.0);
                }
            }
}

TEST(Segment, SwitchFunctionOrder) {
    const Model m = two_mass();
    const auto sf = switch_functions(m, Configuration::parse(m, "stuck=m2"));
    ASSERT_EQ(sf.size(), 4u);
    EXPECT_EQ(sf[0], (SwitchFunction{SwitchKind::gap, 0}));
    EXPECT_EQ(sf[1], (SwitchFunction{SwitchKind::velocity, 0}));
    EXPECT_EQ(sf[2], (SwitchFunction{SwitchKind::release_pos, 1}));
    EXPECT_EQ(sf[3], (SwitchFunction{SwitchKind::release_neg, 1}));
}

}  // namespace
}  // namespace hsnc
