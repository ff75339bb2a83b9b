#include "simulate_outputs.h"

#include <cmath>
#include <cstdio>
#include <vector>

#include "error.h"
#include "sample_grid.h"

namespace hsnc {
namespace {

std::string short_number(double v) {
    char buf[32];
    std::snprintf(buf, sizeof buf, "%.3g", v);
    return buf;
}

std::string bytes_text(double b) {
    const char* units[] = {"B", "kB", "MB", "GB", "TB", "PB", "EB"};
    int u = 0;
    while (b >= 1000 && u < 6) b /= 1000, ++u;
    return short_number(b) + " " + units[u];
}

}  // namespace

double trajectory_rows(double t0, double t_end, double dt) { return SampleGrid(t0, t_end, dt).count(); }

SimulateOutputs::SimulateOutputs(const Model& model, const OutputRequest& r, double t_end, double dt,
                                 const OutputTarget* archive)
    : model_(model), t_end_(t_end), dt_(dt), archive_(archive) {
    std::vector<const OutputTarget*> all;
    if (archive) all.push_back(archive);
    if (!r.out.empty()) all.push_back((out_ = std::make_unique<OutputTarget>(check_output("--out", r.out))).get());
    if (!r.events.empty())
        all.push_back((events_ = std::make_unique<OutputTarget>(check_output("--events", r.events))).get());
    if (!r.plot.empty()) all.push_back((plot_ = std::make_unique<OutputTarget>(check_output("--plot", r.plot))).get());
    section_asked_ =
        section_requested(model, r.section, r.section_out, r.section_plot, &section_spec_, archive != nullptr, true);
    if (section_asked_) {
        if (!r.section_out.empty())
            all.push_back((section_out_ = std::make_unique<OutputTarget>(check_output("--section-out", r.section_out))).get());
        if (!r.section_plot.empty())
            all.push_back(
                (section_plot_ = std::make_unique<OutputTarget>(check_output("--section-plot", r.section_plot))).get());
    }
    check_distinct(all);
    if ((out_ || archive_) && !r.allow_large_output) {
        // Every number is printed with 17 significant digits: about 22 bytes with its comma.
        const double rows = trajectory_rows(model.t0, t_end, sample_dt());
        const double bytes = rows * static_cast<double>(1 + 2 * model.dof()) * 22;
        if (rows > static_cast<double>(kLargeOutputRows) || bytes > kLargeOutputBytes)
            throw InputError("--dt " + short_number(dt) + ": the trajectory " + (out_ ? "--out" : "of --h5") +
                             " would have " + short_number(rows) + " rows, about " + bytes_text(bytes) +
                             " (the limit is 1e7 rows or 1 GB): give a larger " +
                             "--dt or a shorter --t-end, or --allow-large-output to write it anyway");
    }
    if (plot_ || section_plot_) require_gnuplot();
    if (!r.plot_dofs.empty()) plot_dofs_ = plot_dofs(model, r.plot_dofs, {});
}

double SimulateOutputs::sample_dt() const {
    double dt = dt_;
    if (!out_ && !archive_ && plot_) {
        const double coarsest = (t_end_ - model_.t0) / static_cast<double>(kLargeOutputRows);
        dt = dt_ < coarsest ? coarsest : dt_;
    }
    if (stroboscopic()) {
        // The widest spacing up to dt that puts a sample at every t0 + k period:
        // period / m, m whole (dt itself when it is one already, to 1e-9).
        const double period = section_spec_.period;
        const double m = std::fmax(1.0, std::ceil(period / dt - 1e-9));
        dt = period / m;
    }
    return dt;
}

void SimulateOutputs::open(const SimulateMirror& mirror) {
    if (out_ || mirror.trajectory) traj_file_ = std::make_unique<CsvFile>(out_.get(), mirror.trajectory);
    if (events_ || mirror.events) events_file_ = std::make_unique<CsvFile>(events_.get(), mirror.events);
    csv_ = std::make_unique<CsvObserver>(model_, traj_file_.get(), events_file_.get());
    if (plot_) recorder_ = std::make_unique<PlotRecorder>(model_, model_.t0, t_end_, sample_dt(), plot_dofs_);
    if (section_out_ || (mirror.section && section_asked_))
        section_file_ = std::make_unique<CsvFile>(section_out_.get(), mirror.section);
    if (section_file_ || section_plot_)
        section_ = std::make_unique<SectionRecorder>(model_, section_spec_, section_file_.get(), section_plot_ != nullptr);
}

void SimulateOutputs::on_sample(double t, const double* x, const double* v) {
    csv_->on_sample(t, x, v);
    if (recorder_) recorder_->on_sample(t, x, v);
    if (section_) section_->on_sample(t, x, v);
}

void SimulateOutputs::on_event(double t, EventKind kind, int element, const double* x, const double* v) {
    csv_->on_event(t, kind, element, x, v);
    if (recorder_) recorder_->on_event(t, kind, element, x, v);
    if (section_) section_->on_event(t, kind, element, x, v);
}

void SimulateOutputs::commit() {
    if (traj_file_) traj_file_->commit();
    if (events_file_) events_file_->commit();
    if (section_file_) section_file_->commit();
    if (recorder_) recorder_->draw(*plot_);
    if (section_ && section_plot_) section_->draw(*section_plot_);
}

}  // namespace hsnc
