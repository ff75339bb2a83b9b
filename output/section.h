// hsnc -- Poincare sections at a switch kind (`--section KIND[:NAME]` of
// `hsnc simulate` and `hsnc lyapunov`): the state of every mass at each
// instant a switch event of that kind happens (of one element when NAME is
// given: a contact for contact_close / contact_open, a mass for stick,
// release, reversal), or the stroboscopic section of `hsnc simulate
// --section period[:OMEGA]` (the state at t0 + k 2 pi/OMEGA, taken from the
// samples of a grid that holds those instants), written as a CSV with the trajectory's header
// `t,x_<mass>...,v_<mass>...` (one row per instant, however many elements
// switch at it) and drawn with gnuplot as v against x, one panel per mass.
// The state is the one the events CSV gives at that instant (after the
// switch: a mass that stopped has v = 0).
#pragma once

#include <cstddef>
#include <limits>
#include <string>
#include <vector>

#include "csv_writer.h"
#include "model.h"
#include "observer.h"
#include "output_file.h"

namespace hsnc {

/// A section: the event kind and the element (-1: any element of that kind).
struct SectionSpec {
    EventKind kind = EventKind::contact_close;
    int element = -1;
    /// `period[:OMEGA]`: the section's period 2 pi/OMEGA (NaN: a switch kind's section).
    double period = std::numeric_limits<double>::quiet_NaN();
    std::string text;  ///< as given, for titles
};

/// Parses KIND[:NAME] (KIND an events CSV kind, NAME a contact of the model
/// for contact_close/contact_open, a friction mass for stick/release/reversal)
/// and, where `stroboscopic` is set, period[:OMEGA] (OMEGA > 0 in rad/s; without
/// it the forcing's one frequency). Throws InputError naming `flag`.
SectionSpec parse_section(const Model& model, const std::string& text, const std::string& flag,
                          bool stroboscopic = false);

/// Checks --section, --section-out and --section-plot together: InputError
/// when an output comes without --section, or --section without an output,
/// or the spec does not parse (`archive`: an --h5 file takes the section as
/// an output). Returns false when no section is asked for.
bool section_requested(const Model& model, const std::string& section, const std::string& out, const std::string& plot,
                       SectionSpec* spec, bool archive = false, bool stroboscopic = false);

/// Records the section: rows to `csv` (may be null; the header is written
/// here) and, when `keep` is set, in memory for the plot (at most
/// kMaxSectionPlotPoints; a stroboscopic section is always kept, for its
/// rotation number). Events before `from` are left out; samples count only
/// for a stroboscopic section, those at t0 + k period (to 1e-9 of it).
class SectionRecorder : public Observer {
public:
    static constexpr std::size_t kMaxSectionPlotPoints = 1'000'000;

    SectionRecorder(const Model& model, SectionSpec spec, CsvFile* csv, bool keep,
                    double from = -std::numeric_limits<double>::infinity());
    void on_sample(double t, const double* x, const double* v) override;
    void on_event(double t, EventKind kind, int element, const double* x, const double* v) override;

    std::size_t points() const { return points_; }
    /// The kept rows: t, x_1..x_n, v_1..v_n each.
    const std::vector<double>& rows() const { return rows_; }
    const SectionSpec& spec() const { return spec_; }

    /// The gnuplot script of the figure (terminal pngcairo, output on stdout).
    std::string script() const;
    /// Render with gnuplot and write the PNG. Throws RunError when gnuplot fails.
    void draw(const OutputTarget& png) const;

private:
    void record(double t, const double* x, const double* v);

    const Model& model_;
    SectionSpec spec_;
    CsvFile* csv_;
    bool keep_;
    double from_;
    double last_t_ = std::numeric_limits<double>::quiet_NaN();
    std::size_t points_ = 0;
    std::vector<double> rows_;
};

}  // namespace hsnc
