#include "work_precision.h"

#include <algorithm>
#include <cerrno>
#include <cmath>
#include <cstdlib>
#include <fstream>
#include <sstream>
#include <tuple>

#include "csv_writer.h"
#include "error.h"
#include "hsnc/simulate.h"  // OptionError
#include "reference.h"

namespace hsnc {

void RecordingObserver::on_sample(double t, const double* x, const double* /*v*/) {
    run_.t.push_back(t);
    run_.x.insert(run_.x.end(), x, x + run_.dof);
}

void RecordingObserver::on_event(double t, EventKind kind, int element, const double* /*x*/, const double* /*v*/) {
    run_.events.push_back({t, kind, element});
}

namespace {

std::vector<std::string> split(const std::string& line) {
    std::vector<std::string> out;
    std::istringstream in(line);
    for (std::string f; std::getline(in, f, ',');) out.push_back(f);
    if (!line.empty() && line.back() == ',') out.emplace_back();
    return out;
}

// A CSV being read: its lines, and messages "FILE:LINE: ...".
struct CsvReader {
    std::string path;
    std::ifstream in;
    std::size_t line_no = 0;
    explicit CsvReader(const std::string& p, const char* what) : path(p), in(p) {
        if (!in) throw InputError(std::string(what) + " '" + p + "': cannot read the file");
    }
    bool next(std::string& line) {
        if (!std::getline(in, line)) return false;
        ++line_no;
        if (!line.empty() && line.back() == '\r') line.pop_back();
        return true;
    }
    [[noreturn]] void fail(const std::string& what) const {
        throw InputError(path + ":" + std::to_string(line_no) + ": " + what);
    }
    double number(const std::string& field, const char* column) const {
        char* end = nullptr;
        errno = 0;
        const double v = std::strtod(field.c_str(), &end);
        if (field.empty() || *end != '\0' || errno == ERANGE || !std::isfinite(v))
            fail(std::string("column '") + column + "': '" + field + "' is not a finite number");
        return v;
    }
    void header(const std::string& expected) {
        std::string line;
        if (!next(line)) fail("empty file; expected the header '" + expected + "'");
        if (line != expected) fail("header '" + line + "' does not match the model's '" + expected + "'");
    }
};

EventKind parse_kind(const CsvReader& r, const std::string& name) {
    for (EventKind k : kEventKinds)
        if (name == event_kind_name(k)) return k;
    r.fail("column 'kind': unknown event kind '" + name + "'");
}

bool is_contact(EventKind k) {
    return k == EventKind::contact_close || k == EventKind::contact_open || k == EventKind::impact;
}

// Rows of one instant may come in any order (interface.md section 2): sort them by (kind, element).
std::vector<EventRecord> canonical(std::vector<EventRecord> events) {
    std::stable_sort(events.begin(), events.end(), [](const EventRecord& a, const EventRecord& b) {
        return std::make_tuple(a.t, static_cast<int>(a.kind), a.element) <
               std::make_tuple(b.t, static_cast<int>(b.kind), b.element);
    });
    return events;
}

}  // namespace

RecordedRun read_reference(const Model& model, const std::string& trajectory_csv, const std::string& events_csv) {
    if (model.condensation.present())  // its CSVs carry the condensed dofs too
        throw InputError("tradeoff: reading a recorded reference of a structure with massless (condensed) dofs is "
                         "not supported yet");
    RecordedRun ref;
    ref.dof = model.dof();
    const std::size_t n = model.dof();
    {
        CsvReader r(trajectory_csv, "reference trajectory");
        r.header(trajectory_header(model));
        for (std::string line; r.next(line);) {
            if (line.empty()) continue;
            const auto f = split(line);
            if (f.size() != 1 + 2 * n)
                r.fail("expected " + std::to_string(1 + 2 * n) + " columns, found " + std::to_string(f.size()));
            const double t = r.number(f[0], "t");
            if (!ref.t.empty() && !(t > ref.t.back())) r.fail("column 't': times must increase");
            ref.t.push_back(t);
            for (std::size_t i = 0; i < n; ++i) ref.x.push_back(r.number(f[1 + i], ("x_" + model.masses[i].name).c_str()));
        }
        if (ref.t.empty()) r.fail("no trajectory rows");
    }
    {
        CsvReader r(events_csv, "reference events");
        r.header(events_header(model));
        for (std::string line; r.next(line);) {
            if (line.empty()) continue;
            const auto f = split(line);
            if (f.size() != 3 + 2 * n)
                r.fail("expected " + std::to_string(3 + 2 * n) + " columns, found " + std::to_string(f.size()));
            EventRecord e{r.number(f[0], "t"), parse_kind(r, f[1]), -1};
            if (!ref.events.empty() && e.t < ref.events.back().t) r.fail("column 't': events must be in time order");
            if (is_contact(e.kind)) {
                for (std::size_t k = 0; k < model.contacts.size(); ++k)
                    if (model.contacts[k].name == f[2]) e.element = static_cast<int>(k);
                if (e.element < 0) r.fail("column 'element': '" + f[2] + "' is not a contact of the model");
            } else if (e.kind == EventKind::load_change) {
                for (std::size_t k = 0; k < model.load_steps.size(); ++k)
                    if (model.load_steps[k].name == f[2]) e.element = static_cast<int>(k);
                if (e.element < 0) r.fail("column 'element': '" + f[2] + "' is not a load step of the model");
            } else {
                e.element = model.mass_index(f[2]);
                if (e.element < 0) r.fail("column 'element': '" + f[2] + "' is not a mass of the model");
            }
            ref.events.push_back(e);
        }
    }
    return ref;
}

RunErrors compare_runs(const RecordedRun& reference, const RecordedRun& run) {
    RunErrors e;
    const std::size_t n = reference.dof;
    // Common sample times: both sorted; equal up to rounding of t0 + k*dt.
    double max_x = 0.0, magnitude = 0.0;
    bool non_finite = false;
    for (std::size_t i = 0, j = 0; i < reference.t.size() && j < run.t.size();) {
        const double a = reference.t[i], b = run.t[j];
        const double tol = 16 * std::numeric_limits<double>::epsilon() * std::max(std::fabs(a), std::fabs(b));
        if (std::fabs(a - b) <= tol) {
            for (std::size_t m = 0; m < n; ++m) {
                const double d = std::fabs(run.x[j * n + m] - reference.x[i * n + m]);
                if (std::isnan(d)) non_finite = true;
                max_x = std::max(max_x, d);
                magnitude = std::max(magnitude, std::fabs(reference.x[i * n + m]));
            }
            ++e.sample_times;
            ++i;
            ++j;
        } else if (a < b) {
            ++i;
        } else {
            ++j;
        }
    }
    if (e.sample_times) {
        e.max_position_error = non_finite ? INFINITY : max_x;
        e.response_magnitude = magnitude;
        if (magnitude > 0) e.relative_position_error = e.max_position_error / magnitude;
        e.diverged = !std::isfinite(e.max_position_error) || e.relative_position_error > kDivergedRatio;
    }

    const auto ref = canonical(reference.events), got = canonical(run.events);
    e.events = got.size();
    e.reference_events = ref.size();
    double max_dt = 0.0;
    for (std::size_t k = 0; k < std::min(ref.size(), got.size()); ++k) {
        if (ref[k].kind != got[k].kind || ref[k].element != got[k].element) break;
        max_dt = std::max(max_dt, std::fabs(got[k].t - ref[k].t));
        ++e.matched_events;
    }
    if (e.matched_events) e.max_event_time_error = max_dt;
    return e;
}

ReferenceRunner reference_runner(int digits) {
    if (digits < reference::kMinDigits || digits > reference::kMaxDigits)
        throw OptionError("hsnc::reference_runner", "digits", std::to_string(digits),
                          "must be in " + std::to_string(reference::kMinDigits) + ".." +
                              std::to_string(reference::kMaxDigits));
    return [digits](const Model& model, const EngineOptions& options, Observer& observer) {
        return reference::simulate(model, digits, options, observer);
    };
}

}  // namespace hsnc
