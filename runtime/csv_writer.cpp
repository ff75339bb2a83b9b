#include "csv_writer.h"

#include <cerrno>
#include <charconv>
#include <cstring>
#include <unistd.h>

#include "error.h"

namespace hsnc {

CsvFile::CsvFile(std::string path) : path_(std::move(path)) {
    tmp_ = path_ + ".tmp." + std::to_string(::getpid());
    file_ = std::fopen(tmp_.c_str(), "w");
    if (!file_) throw InputError("cannot write '" + path_ + "': " + std::strerror(errno));
    static thread_local char buffer[1 << 16];
    std::setvbuf(file_, buffer, _IOFBF, sizeof buffer);
}

CsvFile::~CsvFile() {
    if (file_) {
        std::fclose(file_);
        std::remove(tmp_.c_str());
    }
}

void CsvFile::text(const char* s) {
    if (!first_in_row_) std::fputc(',', file_);
    std::fputs(s, file_);
    first_in_row_ = false;
}

void CsvFile::number(double value) {
    char buf[40];
    // 17 significant digits always round-trip a double (max_digits10).
    const auto res = std::to_chars(buf, buf + sizeof buf - 1, value, std::chars_format::general, 17);
    *res.ptr = '\0';
    text(buf);
}

void CsvFile::end_row() {
    std::fputc('\n', file_);
    first_in_row_ = true;
}

void CsvFile::commit() {
    const bool failed = std::ferror(file_) != 0;
    const bool closed = std::fclose(file_) == 0;
    file_ = nullptr;
    if (failed || !closed || std::rename(tmp_.c_str(), path_.c_str()) != 0) {
        std::remove(tmp_.c_str());
        throw RunError("cannot write '" + path_ + "': " + std::strerror(errno));
    }
}

std::string trajectory_header(const Model& model) {
    std::string h = "t";
    for (const Mass& m : model.masses) h += ",x_" + m.name;
    for (const Mass& m : model.masses) h += ",v_" + m.name;
    return h;
}

std::string events_header(const Model& model) {
    std::string h = "t,kind,element";
    for (const Mass& m : model.masses) h += ",x_" + m.name;
    for (const Mass& m : model.masses) h += ",v_" + m.name;
    return h;
}

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
    for (std::size_t i = 0; i < model_.dof(); ++i) trajectory_->number(x[i]);
    for (std::size_t i = 0; i < model_.dof(); ++i) trajectory_->number(v[i]);
    trajectory_->end_row();
}

void CsvObserver::on_event(double t, EventKind kind, int element, const double* x, const double* v) {
    if (!events_) return;
    events_->number(t);
    events_->text(event_kind_name(kind));
    const bool contact = kind == EventKind::contact_close || kind == EventKind::contact_open;
    events_->text(contact ? model_.contacts[element].name.c_str() : model_.masses[element].name.c_str());
    for (std::size_t i = 0; i < model_.dof(); ++i) events_->number(x[i]);
    for (std::size_t i = 0; i < model_.dof(); ++i) events_->number(v[i]);
    events_->end_row();
}

}  // namespace hsnc
