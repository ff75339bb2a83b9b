// Finds the periodic orbit of a forced model and its Floquet multipliers, as
// `hsnc periodic MODEL` does, through the installed library.
// Usage: periodic_orbit MODEL.toml
#include <hsnc/hsnc.h>

#include <iostream>

int main(int argc, char** argv) try {
    if (argc < 2) return std::cerr << "usage: periodic_orbit MODEL.toml\n", 2;
    const hsnc::Model model = hsnc::read_model(argv[1]);
    const hsnc::PeriodicResult r = hsnc::periodic(model, hsnc::PeriodicOptions{});
    std::cout.precision(17);
    std::cout << "status=" << hsnc::periodic_status_name(r.status) << " period=" << r.period;
    for (std::size_t i = 0; i < model.dof(); ++i) std::cout << " x_" << model.masses[i].name << "=" << r.x[i];
    for (std::size_t i = 0; i < model.dof(); ++i) std::cout << " v_" << model.masses[i].name << "=" << r.v[i];
    std::cout << " max_multiplier=" << r.max_multiplier << "\n";
    return r.status == hsnc::PeriodicStatus::ok ? 0 : 1;
} catch (const std::exception& e) {  // hsnc::InputError (bad model or options), hsnc::RunError
    return std::cerr << "periodic_orbit: " << e.what() << "\n", 1;
}
