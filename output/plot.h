// hsnc -- the `hsnc simulate --plot` figure, drawn by gnuplot (Debian gnuplot-nox).
//
// A PlotRecorder observes the run (it needs no --out file) and keeps, in
// bounded memory, what the figure draws: x(t) of every mass over the whole
// run (every sample, or the min/max envelope of 2000 time buckets when there
// are more samples than that), the same in a zoom window (the last 5 forcing
// periods, else the first 10% of the run), and the switch events. The figure:
// top panel, the whole run with the events as ticks below the curves, one row
// per kind; bottom panel, the zoom window with each event marked on its
// curve. Axes in seconds and metres, or rad for rotations (dof_unit). Every
// dof, or those of --plot-dofs; up to 8 get distinct colours and a legend;
// more (up to any number) are coloured along a colour scale by their index,
// with a colour box naming dofs on it.
#pragma once

#include <cstddef>
#include <string>
#include <vector>

#include "model.h"
#include "observer.h"
#include "output_file.h"

namespace hsnc {

/// At most this many dofs on a figure that gives each a colour and a legend entry.
inline constexpr std::size_t kMaxPlotDofs = 8;

/// The dofs the model's elements act on (contacts, friction, Jenkins elements,
/// discrete dampers), that carry friction, forcing or a load, in model order
/// (indices of Model::masses): what a figure of a large structure draws by default.
std::vector<std::size_t> named_dofs(const Model& model);

/// The dofs a figure draws. `list` (--plot-dofs: names, comma-separated) when
/// given: each must be one of `names` (InputError naming `flag` otherwise),
/// at most kMaxPlotDofs. Else every dof when there are at most kMaxPlotDofs,
/// or the first kMaxPlotDofs of `named` (of the dofs when `named` is empty).
std::vector<std::size_t> plot_dofs(const std::vector<std::string>& names, const std::string& list,
                                   const std::vector<std::size_t>& named, const std::string& flag = "--plot-dofs");
/// The same with the model's dof names.
std::vector<std::size_t> plot_dofs(const Model& model, const std::string& list, const std::vector<std::size_t>& named,
                                   const std::string& flag = "--plot-dofs");

/// The unit of a dof's position by its name: "rad" for a rotation (a name
/// that is t, th, theta, rot, phi or psi followed by digits, `_` or the end:
/// t3, theta_2, rot), else "m".
std::string dof_unit(const std::string& name);

/// The unit of a figure's axis drawing `names`: their dof_unit when they
/// agree ("m" for none), else "mixed" (each legend entry then says its own).
std::string common_unit(const std::vector<std::string>& names);

/// Throws RunError when gnuplot is not on PATH (called before a run).
void require_gnuplot();

/// gnuplot with `script` on stdin, the PNG read from its stdout, its
/// diagnostics from stderr: nothing of it reaches our stdout. Returns the
/// PNG bytes; throws RunError with the first lines of its diagnostics.
std::string run_gnuplot(const std::string& script);
/// Renders a gnuplot script (terminal pngcairo, no `set output`: the PNG
/// comes on gnuplot's stdout) and writes the PNG to `png`. Throws RunError
/// when gnuplot fails (the first lines of its diagnostics in the message).
void render_png(const std::string& script, const OutputTarget& png);

class PlotRecorder : public Observer {
public:
    /// Samples come every `dt` from t0 to t_end. `dofs`: the dofs drawn
    /// (indices of Model::masses, plot_dofs); empty: every dof.
    PlotRecorder(const Model& model, double t0, double t_end, double dt, std::vector<std::size_t> dofs = {});
    void on_sample(double t, const double* x, const double* v) override;
    void on_event(double t, EventKind kind, int element, const double* x, const double* v) override;

    /// The gnuplot script of the figure (terminal pngcairo, output on stdout).
    std::string script() const;
    /// Render with gnuplot and write the PNG to `png`. Throws RunError when
    /// gnuplot fails (its first lines of diagnostics in the message; nothing
    /// of it reaches stdout).
    void draw(const OutputTarget& png) const;

    /// One panel's data: every sample, or a min/max envelope per time bucket.
    struct Series {
        double a = 0, b = 0;  // the time window
        bool envelope = false;
        std::vector<double> rows;  // raw: t, x_1..x_n per row
        // envelope: per bucket, count, then for each mass min, max, and whether the min came first
        std::vector<std::size_t> count;
        std::vector<double> lo, hi;
        std::vector<char> lo_first;
        void add(double t, const double* x, std::size_t n);
    };

private:
    struct Mark {
        double t;
        EventKind kind;
        double y;
    };
    const Model& model_;
    std::vector<std::size_t> dofs_;  // drawn, in their order
    std::vector<double> drawn_;      // one sample's x of the dofs drawn
    Series whole_, zoom_;
    std::string zoom_title_;
    std::vector<Mark> marks_;
    std::size_t unmarked_ = 0;  // events past the cap, not drawn
};

}  // namespace hsnc
