// Reads a model, simulates it to its [simulate].t_end and prints the summary.
// Usage: simulate_model MODEL.toml [auto|aot|jit|generic]
#include <hsnc/hsnc.h>

#include <iostream>

int main(int argc, char** argv) try {
    if (argc < 2) return std::cerr << "usage: simulate_model MODEL.toml [auto|aot|jit|generic]\n", 2;
    const hsnc::Model model = hsnc::read_model(argv[1]);
    hsnc::SimulateOptions options;
    options.kernels = hsnc::kernel_choice_from_name(argc > 2 ? argv[2] : "auto");
    const hsnc::SimulateSummary s = hsnc::simulate(model, options);
    std::cout.precision(17);
    std::cout << "status=" << hsnc::run_status_name(s.status) << " t=" << s.t << " events=" << s.events;
    for (std::size_t i = 0; i < model.dof(); ++i) std::cout << " x_" << model.masses[i].name << "=" << s.x[i];
    for (std::size_t i = 0; i < model.dof(); ++i) std::cout << " v_" << model.masses[i].name << "=" << s.v[i];
    std::cout << " solver=" << hsnc::solver_kind_name(s.solver) << "\n";
} catch (const std::exception& e) {  // hsnc::InputError (bad model or options), hsnc::RunError
    return std::cerr << "simulate_model: " << e.what() << "\n", 1;
}
