// hsnc -- the output files of `hsnc simulate` (--out, --events, --plot):
// every path checked before the run (exit code 2, nothing written), written
// while it runs (stopping at the first write error), committed after it.
#pragma once

#include <cmath>
#include <cstdint>
#include <memory>
#include <string>

#include "csv_writer.h"
#include "model.h"
#include "observer.h"
#include "output_file.h"
#include "plot.h"
#include "section.h"

namespace hsnc {

/// Without --allow-large-output, a trajectory of more rows than this, or of
/// more than kLargeOutputBytes (estimated), is refused before the run.
inline constexpr std::uint64_t kLargeOutputRows = 10'000'000;
inline constexpr double kLargeOutputBytes = 1e9;

struct OutputRequest {
    std::string out, events, plot;
    bool allow_large_output = false;
    /// --section KIND[:NAME] with --section-out CSV and/or --section-plot PNG (section.h).
    std::string section, section_out, section_plot;
    /// --h5 FILE (h5_archive.h; checked and written by the command line).
    std::string h5;
    /// --plot-dofs NAME,...: the dofs --plot draws (plot.h plot_dofs); empty: every dof.
    std::string plot_dofs;
};

/// Rows of the trajectory CSV sampled every dt from t0 to t_end (without the header).
double trajectory_rows(double t0, double t_end, double dt);

/// Where the tables of `hsnc simulate` go besides their CSV files (an --h5
/// file; null for none): the trajectory, the events and the section, each
/// written even without its CSV.
struct SimulateMirror {
    TableSink* trajectory = nullptr;
    TableSink* events = nullptr;
    TableSink* section = nullptr;
};

class SimulateOutputs : public Observer {
public:
    /// Checks every path (check_output, check_distinct), gnuplot for --plot,
    /// and the size of the trajectory; throws InputError (RunError when
    /// gnuplot is missing). Opens nothing: call open() once every other
    /// check has passed.
    /// `archive`: the --h5 target (checked by the caller), one more output
    /// that must be distinct from the others and holds the trajectory too.
    SimulateOutputs(const Model& model, const OutputRequest& request, double t_end, double dt,
                    const OutputTarget* archive = nullptr);
    /// `mirror`: where the tables go besides their CSV files (SimulateMirror).
    void open(const SimulateMirror& mirror = SimulateMirror());
    /// Whether the run must report samples (a trajectory, an archive, a plot or a stroboscopic section).
    bool samples() const { return out_ || archive_ || plot_ || stroboscopic(); }
    /// The spacing the run samples at: dt with a trajectory (--out); for the
    /// plot alone at least (t_end - t0) / kLargeOutputRows (the figure keeps
    /// 2000 buckets: a tiny --dt must not make a run of endless samples);
    /// with `--section period` the widest period/m (m whole) up to that.
    double sample_dt() const;
    /// `--section period[:OMEGA]` is asked for.
    bool stroboscopic() const { return section_asked_ && !std::isnan(section_spec_.period); }
    /// Its period 2 pi/OMEGA (NaN for a switch kind's section).
    double section_period() const { return section_spec_.period; }
    /// The section's points when there is one (section.h), else null.
    const SectionRecorder* section() const { return section_.get(); }

    void on_sample(double t, const double* x, const double* v) override;
    void on_event(double t, EventKind kind, int element, const double* x, const double* v) override;

    /// Commit the CSVs, then draw the plots.
    void commit();
    /// Section points recorded (0 without --section).
    std::size_t section_points() const { return section_ ? section_->points() : 0; }

private:
    const Model& model_;
    double t_end_, dt_;
    const OutputTarget* archive_;
    std::vector<std::size_t> plot_dofs_;  // empty: every dof
    std::unique_ptr<OutputTarget> out_, events_, plot_, section_out_, section_plot_;
    SectionSpec section_spec_;
    bool section_asked_ = false;  // --section given
    std::unique_ptr<CsvFile> traj_file_, events_file_, section_file_;
    std::unique_ptr<SectionRecorder> section_;
    std::unique_ptr<CsvObserver> csv_;
    std::unique_ptr<PlotRecorder> recorder_;
};

}  // namespace hsnc
