#include "section.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <sstream>

#include "error.h"
#include "plot.h"

namespace hsnc {
namespace {

constexpr std::size_t kMaxPanels = 8;

bool is_contact_kind(EventKind k) {
    return k == EventKind::contact_close || k == EventKind::contact_open || k == EventKind::impact;
}

// Text inside a gnuplot string: quotes, backslashes, backquotes and control characters left out.
std::string plain(const std::string& s) {
    std::string out;
    for (char c : s)
        if (c != '"' && c != '\\' && c != '`' && c != '\'' && static_cast<unsigned char>(c) >= 32) out += c;
    return out;
}

std::string num(double v) {
    char buf[32];
    std::snprintf(buf, sizeof buf, "%.17g", v);
    return buf;
}

// The OMEGA of --section period[:OMEGA]: the text given (a number > 0), else
// the forcing's one frequency.
double stroboscopic_omega(const Model& model, const std::string& text, const std::string& given,
                          const std::string& flag) {
    if (!given.empty()) {
        char* end = nullptr;
        const double omega = std::strtod(given.c_str(), &end);
        if (end == given.c_str() || *end != '\0' || !std::isfinite(omega) || !(omega > 0))
            throw InputError(flag + " '" + text + "': OMEGA must be a finite number > 0 (rad/s)");
        if (!std::isfinite(2 * M_PI / omega))
            throw InputError(flag + " '" + text + "': OMEGA is too small (its period is beyond the double range)");
        return omega;
    }
    std::vector<double> omegas;
    for (const Harmonic& h : model.forcing)
        if (h.omega != 0.0 && std::find(omegas.begin(), omegas.end(), std::fabs(h.omega)) == omegas.end())
            omegas.push_back(std::fabs(h.omega));
    if (omegas.size() == 1) return omegas[0];
    std::string list;
    for (double w : omegas) list += (list.empty() ? "" : ", ") + num(w);
    throw InputError(flag + " '" + text + "': give period:OMEGA, the frequency whose period the section is taken at " +
                     (omegas.empty()
                          ? std::string("(model '") + model.name + "' has no harmonic forcing)"
                          : "(the forcing has " + std::to_string(omegas.size()) + " frequencies: " + list + ")"));
}

}  // namespace

SectionSpec parse_section(const Model& model, const std::string& text, const std::string& flag, bool stroboscopic) {
    SectionSpec s;
    s.text = text;
    const std::size_t colon = text.find(':');
    const std::string kind = text.substr(0, colon);
    if (kind == "period") {
        if (!stroboscopic)
            throw InputError(flag + " '" + text +
                             "': a stroboscopic section is taken by hsnc simulate --section "
                             "period[:OMEGA]; here KIND is a switch kind");
        s.period =
            2 * M_PI / stroboscopic_omega(model, text, colon == std::string::npos ? "" : text.substr(colon + 1), flag);
        return s;
    }
    bool found = false;
    for (EventKind k : kSwitchEventKinds)
        if (kind == event_kind_name(k)) s.kind = k, found = true;
    if (model.has_impacts() && kind == event_kind_name(EventKind::impact))  // the impact map of a rigid stop
        s.kind = EventKind::impact, found = true;
    if (!found)
        throw InputError(flag + " '" + text +
                         "': expected KIND[:NAME] with KIND one of contact_close, contact_open, "
                         "stick, release, reversal" +
                         std::string(model.has_impacts() ? ", impact" : "") +
                         (stroboscopic ? std::string(", or period[:OMEGA]") : std::string()));
    if (colon == std::string::npos) {
        if (is_contact_kind(s.kind) ? model.contacts.empty() : model.jenkins.empty() && !model.any_friction())
            throw InputError(flag + " '" + text + "': model '" + model.name + "' has no " +
                             (is_contact_kind(s.kind) ? "contact" : "mass with friction") + ": no such event can happen");
        return s;
    }
    const std::string name = text.substr(colon + 1);
    if (is_contact_kind(s.kind)) {
        for (std::size_t c = 0; c < model.contacts.size(); ++c)
            if (model.contacts[c].name == name) s.element = static_cast<int>(c);
        if (s.element < 0) {
            std::string names;
            for (const Contact& c : model.contacts) names += (names.empty() ? "" : ", ") + c.name;
            throw InputError(flag + " '" + text + "': no contact named '" + name + "' in model '" + model.name + "'" +
                             (names.empty() ? " (it has none)" : " (contacts: " + names + ")"));
        }
    } else {
        // A friction mass by its own name or its [[friction]] element's, or a
        // Jenkins element (element dof() + j, as in the event rows).
        for (std::size_t i = 0; i < model.masses.size(); ++i)
            if (model.has_friction(i) && (model.masses[i].name == name || model.friction_name(i) == name))
                s.element = static_cast<int>(i);
        if (const int j = model.jenkins_index(name); j >= 0) s.element = static_cast<int>(model.dof()) + j;
        if (s.element < 0) {
            std::string names;
            for (std::size_t i = 0; i < model.masses.size(); ++i)
                if (model.has_friction(i)) names += (names.empty() ? "" : ", ") + model.friction_name(i);
            for (const Jenkins& j : model.jenkins) names += (names.empty() ? "" : ", ") + j.name;
            throw InputError(flag + " '" + text + "': no mass with friction named '" + name + "' in model '" +
                             model.name + "'" + (names.empty() ? " (it has none)" : " (friction masses and elements: " + names + ")"));
        }
    }
    return s;
}

bool section_requested(const Model& model, const std::string& section, const std::string& out, const std::string& plot,
                       SectionSpec* spec, bool archive, bool stroboscopic) {
    if (section.empty() && out.empty() && plot.empty()) return false;
    if (section.empty())
        throw InputError(std::string(out.empty() ? "--section-plot" : "--section-out") +
                         ": needs --section KIND[:NAME] (the switch kind the section is taken at)" +
                         (stroboscopic ? std::string(" or --section period[:OMEGA]") : std::string()));
    if (out.empty() && plot.empty() && !archive)
        throw InputError("--section '" + section + "': needs --section-out CSV, --section-plot PNG or --h5 FILE");
    *spec = parse_section(model, section, "--section", stroboscopic);
    return true;
}

SectionRecorder::SectionRecorder(const Model& model, SectionSpec spec, CsvFile* csv, bool keep, double from)
    : model_(model), spec_(std::move(spec)), csv_(csv), keep_(keep), from_(from) {
    if (csv_) {
        csv_->text(trajectory_header(model_).c_str());
        csv_->end_row();
    }
}

void SectionRecorder::on_event(double t, EventKind kind, int element, const double* x, const double* v) {
    if (!std::isnan(spec_.period) || kind != spec_.kind || (spec_.element >= 0 && element != spec_.element) ||
        t < from_)
        return;
    record(t, x, v);
}

void SectionRecorder::on_sample(double t, const double* x, const double* v) {
    if (std::isnan(spec_.period) || t < from_) return;
    const double periods = (t - model_.t0) / spec_.period;
    if (std::fabs(periods - std::round(periods)) <= 1e-9) record(t, x, v);
}

void SectionRecorder::record(double t, const double* x, const double* v) {
    if (t == last_t_) return;  // one row per instant
    last_t_ = t;
    ++points_;
    const std::size_t n = model_.dof();
    if (csv_) {
        csv_->number(t);
        state_numbers(model_, *csv_, t, x, v);
        csv_->end_row();
    }
    if ((keep_ || !std::isnan(spec_.period)) && points_ <= kMaxSectionPlotPoints) {
        rows_.push_back(t);
        rows_.insert(rows_.end(), x, x + n);
        rows_.insert(rows_.end(), v, v + n);
    }
}

std::string SectionRecorder::script() const {
    const std::size_t n = model_.dof(), width = 1 + 2 * n, kept = rows_.size() / width;
    const std::size_t panels = std::min(n, kMaxPanels);
    const std::size_t cols = panels == 1 ? 1 : 2, lines = (panels + cols - 1) / cols;
    std::ostringstream s;
    s << "set terminal pngcairo size " << (cols == 1 ? 720 : 1200) << "," << 80 + 480 * lines << " font ',11'\n";
    std::ostringstream title;
    title << plain(model_.name) << ": Poincare section at " << plain(spec_.text) << ", " << points_ << " points";
    if (kept < points_) title << " (the first " << kept << " drawn)";
    if (panels < n) title << ", the first " << panels << " of " << n << " masses";
    s << "set multiplot layout " << lines << "," << cols << " title \"" << title.str() << "\" noenhanced\n"
      << "set grid\nunset key\n";
    if (kept > 0) {
        s << "$section << EOD\n";
        for (std::size_t r = 0; r < kept; ++r)
            for (std::size_t j = 0; j < width; ++j) s << num(rows_[r * width + j]) << (j + 1 < width ? " " : "\n");
        s << "EOD\n";
    }
    const double size = kept > 20000 ? 0.25 : kept > 2000 ? 0.4 : 0.8;
    for (std::size_t i = 0; i < panels; ++i) {
        const std::string m = plain(model_.masses[i].name);
        s << "set title \"mass " << m << "\" noenhanced\n"
          << "set xlabel \"x_" << m << " [m]\" noenhanced\nset ylabel \"v_" << m << " [m/s]\" noenhanced\n";
        if (kept > 0)
            s << "plot $section using " << 2 + i << ":" << 2 + n + i << " with points pt 7 ps " << size
              << " lc rgb '#1f4e9c'\n";
        else  // nothing to draw: an empty panel that says so
            s << "set label 1 'no section points' at graph 0.5,0.5 center\nset xrange [-1:1]\nset yrange [-1:1]\n"
              << "plot NaN notitle\nunset label 1\nset autoscale\n";
    }
    s << "unset multiplot\n";
    return s.str();
}

void SectionRecorder::draw(const OutputTarget& png) const { render_png(script(), png); }

}  // namespace hsnc
