#include "csv_writer.h"

#include <algorithm>
#include <charconv>
#include <cmath>
#include <cstring>
#include <vector>

#include "error.h"
#include "number_text.h"

namespace hsnc {

CsvFile::CsvFile(const std::string& path) : CsvFile(check_output("", path)) {}

CsvFile::CsvFile(const OutputTarget& target) : file_(std::make_unique<OutputFile>(target)) {}

CsvFile::CsvFile(const OutputTarget* target, TableSink* mirror)
    : file_(target ? std::make_unique<OutputFile>(*target) : nullptr), mirror_(mirror) {}

void CsvFile::text(const char* s) {
    if (mirror_) mirror_->text(s);
    if (!file_) return;
    if (!first_in_row_) file_->put(',');
    file_->write(s, std::strlen(s));
    first_in_row_ = false;
}

void CsvFile::number(double value) {
    if (mirror_) mirror_->number(value);
    if (!file_) return;
    char buf[40];
    // 17 significant digits always round-trip a double (max_digits10).
    const auto res = std::to_chars(buf, buf + sizeof buf, value, std::chars_format::general, 17);
    if (!first_in_row_) file_->put(',');
    file_->write(buf, static_cast<std::size_t>(res.ptr - buf));
    first_in_row_ = false;
}

void CsvFile::end_row() {
    if (mirror_) mirror_->end_row();
    if (!file_) return;
    file_->put('\n');
    first_in_row_ = true;
}

namespace {

// Positions and velocities of the masses, then the slider position of every
// Jenkins element (interface.md: new columns only at the end).
// A structure with massless dofs (model.h Condensation): every dof in the
// structure's order, the condensed ones recovered from the others.
std::string state_columns(const Model& model) {
    std::string h;
    if (model.condensation.present()) {
        for (const std::string& d : model.condensation.dofs) h += ",x_" + d;
        for (const std::string& d : model.condensation.dofs) h += ",v_" + d;
        for (const Jenkins& j : model.jenkins) h += ",s_" + j.name;
        return h;
    }
    for (const Mass& m : model.masses) h += ",x_" + m.name;
    for (const Mass& m : model.masses) h += ",v_" + m.name;
    for (const Jenkins& j : model.jenkins) h += ",s_" + j.name;
    return h;
}

}  // namespace

void state_numbers(const Model& model, CsvFile& file, double t, const double* x, const double* v) {
    const std::size_t n = model.dof();
    const Condensation& c = model.condensation;
    if (c.present()) {  // x_c = R x + K_cc^-1 f_c(t) and v_c = R v + K_cc^-1 f_c'(t), rows in the order of the condensed dofs
        const std::size_t nc = c.condensed();
        const std::vector<double>& load = model.condensed_load_at(t);  // [[load_step]]: the load from t on
        const bool loaded = c.loaded() || std::any_of(load.begin(), load.end(), [](double l) { return l != 0.0; });
        std::vector<double> f(nc, 0.0), df(nc, 0.0);  // the forces on the condensed dofs and their rates
        if (loaded) {
            for (std::size_t r = 0; r < nc; ++r) f[r] = load.empty() ? 0.0 : load[r];
            for (std::size_t h = 0; h < c.amplitude.size(); ++h) {
                const Harmonic& hm = model.forcing[h];
                const double s = std::sin(hm.omega * t + hm.phase), co = std::cos(hm.omega * t + hm.phase);
                for (std::size_t r = 0; r < nc; ++r) {
                    f[r] += c.amplitude[h][r] * s;
                    df[r] += c.amplitude[h][r] * hm.omega * co;
                }
            }
        }
        auto all = [&](const double* y, const std::vector<double>& force) {
            std::size_t row = 0;
            for (int i : c.mass) {
                if (i >= 0) {
                    file.number(y[i]);
                    continue;
                }
                double sum = 0.0;
                for (std::size_t j = 0; j < n; ++j) sum += c.recovery[row * n + j] * y[j];
                if (loaded)
                    for (std::size_t q = 0; q < nc; ++q) sum += c.flexibility[row * nc + q] * force[q];
                file.number(sum);
                ++row;
            }
        };
        all(x, f);
        all(v, df);
    } else {
        for (std::size_t i = 0; i < n; ++i) file.number(x[i]);
        for (std::size_t i = 0; i < n; ++i) file.number(v[i]);
    }
    for (std::size_t j = 0; j < model.jenkins.size(); ++j) file.number(x[n + j]);
}

void SummaryRow::word(const std::string& name, const std::string& value, Where where) {
    fields_.push_back({name, value, 0.0, true, where});
}

void SummaryRow::number(const std::string& name, double value, Where where) {
    fields_.push_back({name, "", value, false, where});
}

std::string SummaryRow::line() const {
    std::string s;
    for (const Field& f : fields_)
        if (f.where != Where::table)
            s += (s.empty() ? "" : " ") + f.name + "=" + (f.is_word ? f.word : number_text(f.number));
    return s;
}

void SummaryRow::write(TableSink& table) const {
    CsvFile t(nullptr, &table);
    std::string header;
    for (const Field& f : fields_)
        if (f.where != Where::line) header += (header.empty() ? "" : ",") + f.name;
    t.text(header.c_str());
    t.end_row();
    for (const Field& f : fields_) {
        if (f.where == Where::line) continue;
        if (f.is_word)
            t.text(f.word.c_str());
        else
            t.number(f.number);
    }
    t.end_row();
}

std::string trajectory_header(const Model& model) { return "t" + state_columns(model); }

std::string events_header(const Model& model) { return "t,kind,element" + state_columns(model); }

CsvObserver::CsvObserver(const Model& model, CsvFile* trajectory, CsvFile* events)
    : model_(model), trajectory_(trajectory), events_(events) {
    if (trajectory_) {
        trajectory_->text(trajectory_header(model).c_str());
        trajectory_->end_row();
    }
    if (events_) {
        events_->text(events_header(model).c_str());
        events_->end_row();
    }
}

void CsvObserver::on_sample(double t, const double* x, const double* v) {
    if (!trajectory_) return;
    trajectory_->number(t);
    state_numbers(model_, *trajectory_, t, x, v);
    trajectory_->end_row();
}

void CsvObserver::on_event(double t, EventKind kind, int element, const double* x, const double* v) {
    if (!events_) return;
    events_->number(t);
    events_->text(event_kind_name(kind));
    events_->text(event_element_name(model_, kind, element).c_str());
    state_numbers(model_, *events_, t, x, v);
    events_->end_row();
}

}  // namespace hsnc
