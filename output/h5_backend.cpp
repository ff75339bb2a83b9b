// libhsnc_h5.so: the HDF5 side of --h5 (h5_archive.h), loaded by the command
// line only when a command is given --h5, so that no other run of hsnc loads
// HDF5 and the libraries it needs. Errors are std::runtime_error; H5Archive
// names the file.
#include <hdf5.h>

#include <algorithm>
#include <cstdlib>
#include <limits>
#include <memory>
#include <sstream>
#include <stdexcept>
#include <string>
#include <vector>

#include "h5_archive.h"

namespace hsnc {

namespace {

/// An HDF5 handle closed by its own function when it goes out of scope.
class Handle {
public:
    Handle(hid_t id, herr_t (*close)(hid_t)) : id_(id), close_(close) {}
    ~Handle() {
        if (id_ >= 0) close_(id_);
    }
    Handle(const Handle&) = delete;
    Handle& operator=(const Handle&) = delete;
    hid_t get() const { return id_; }

private:
    hid_t id_;
    herr_t (*close_)(hid_t);
};

[[noreturn]] void fail(const std::string& label, const std::string& what) {
    throw std::runtime_error(label + "HDF5 could not " + what);
}

hid_t checked(hid_t id, const std::string& label, const std::string& what) {
    if (id < 0) fail(label, what);
    return id;
}

/// Variable-length UTF-8 strings.
hid_t string_type() {
    const hid_t t = H5Tcopy(H5T_C_S1);
    H5Tset_size(t, H5T_VARIABLE);
    H5Tset_cset(t, H5T_CSET_UTF8);
    return t;
}

/// Link creation that makes the groups on the way ("sweep/curve/xmax_m").
hid_t intermediate_groups() {
    const hid_t p = H5Pcreate(H5P_LINK_CREATE);
    H5Pset_create_intermediate_group(p, 1);
    return p;
}

bool parse_number(const std::string& s, double& value) {
    if (s.empty()) return false;
    char* end = nullptr;
    value = std::strtod(s.c_str(), &end);
    return end == s.c_str() + s.size();
}

constexpr hsize_t kChunkRows = 4096;

}  // namespace

/// One table: its header, rows buffered kChunkRows at a time, then appended
/// to one extendible dataset per column (float64 or strings, decided by the
/// first rows: a column is numeric when every cell there that is not empty is a number).
class H5Table final : public TableSink {
public:
    H5Table(hid_t file, std::string group, std::string label)
        : file_(file), group_(std::move(group)), label_(std::move(label)) {}
    ~H5Table() override {
        for (hid_t d : datasets_) H5Dclose(d);
    }
    H5Table(const H5Table&) = delete;
    H5Table& operator=(const H5Table&) = delete;

    void text(const char* s) override { row_.push_back({s, std::numeric_limits<double>::quiet_NaN(), true}); }
    void number(double value) override { row_.push_back({"", value, false}); }
    void end_row() override {
        if (columns_.empty())
            header();
        else if (row_.size() == 1 && row_[0].is_text && row_[0].text.rfind('#', 0) == 0)
            note_ = row_[0].text;
        else
            rows_.push_back(std::move(row_));
        row_.clear();
        if (rows_.size() == kChunkRows) flush();
    }
    void finish() {
        flush();
        if (datasets_.empty()) create();  // a table without rows: its columns, empty
        if (!note_.empty()) string_attribute(group_, "note", note_);
    }

private:
    struct Cell {
        std::string text;
        double number;
        bool is_text;
    };

    void header() {
        for (const Cell& c : row_) {
            std::stringstream names(c.text);
            for (std::string name; std::getline(names, name, ',');) columns_.push_back(name);
        }
        std::string joined;
        for (const auto& c : columns_) joined += (joined.empty() ? "" : ",") + c;
        const Handle lcpl(intermediate_groups(), H5Pclose);
        const Handle g(checked(H5Gcreate2(file_, group_.c_str(), lcpl.get(), H5P_DEFAULT, H5P_DEFAULT), label_,
                               "create the group " + group_),
                       H5Gclose);
        string_attribute(group_, "columns", joined);
    }

    void string_attribute(const std::string& object, const char* name, const std::string& value) const {
        const Handle type(string_type(), H5Tclose);
        const Handle space(H5Screate(H5S_SCALAR), H5Sclose);
        const Handle a(checked(H5Acreate_by_name(file_, object.c_str(), name, type.get(), space.get(), H5P_DEFAULT,
                                                 H5P_DEFAULT, H5P_DEFAULT),
                               label_, std::string("write the attribute ") + name + " of " + object),
                       H5Aclose);
        const char* p = value.c_str();
        if (H5Awrite(a.get(), type.get(), &p) < 0) fail(label_, std::string("write the attribute ") + name);
    }

    bool numeric_column(std::size_t c) const {
        for (const auto& row : rows_) {
            if (c >= row.size() || !row[c].is_text || row[c].text.empty()) continue;
            double v = 0;
            if (!parse_number(row[c].text, v)) return false;
        }
        return true;
    }

    void create() {
        const Handle lcpl(intermediate_groups(), H5Pclose);
        const Handle dcpl(H5Pcreate(H5P_DATASET_CREATE), H5Pclose);
        // A table that fits one buffer is one chunk of its size (a chunk is allocated whole).
        const hsize_t chunk = std::max<hsize_t>(1, std::min<hsize_t>(kChunkRows, rows_.size())), zero = 0,
                      unlimited = H5S_UNLIMITED;
        H5Pset_chunk(dcpl.get(), 1, &chunk);
        const Handle space(H5Screate_simple(1, &zero, &unlimited), H5Sclose);
        const Handle text(string_type(), H5Tclose);
        for (std::size_t c = 0; c < columns_.size(); ++c) {
            numeric_.push_back(numeric_column(c));
            const std::string path = group_ + "/" + columns_[c];
            datasets_.push_back(checked(H5Dcreate2(file_, path.c_str(), numeric_[c] ? H5T_IEEE_F64LE : text.get(),
                                                   space.get(), lcpl.get(), dcpl.get(), H5P_DEFAULT),
                                        label_, "create the dataset " + path));
        }
    }

    void flush() {
        if (rows_.empty()) return;
        if (datasets_.empty()) create();
        const hsize_t n = rows_.size(), size = written_ + n;
        const Handle memory(H5Screate_simple(1, &n, nullptr), H5Sclose);
        const Handle text(string_type(), H5Tclose);
        std::vector<double> numbers(n);
        std::vector<std::string> words(n);
        std::vector<const char*> pointers(n);
        for (std::size_t c = 0; c < columns_.size(); ++c) {
            const hid_t d = datasets_[c];
            if (H5Dset_extent(d, &size) < 0) fail(label_, "extend " + group_ + "/" + columns_[c]);
            const Handle file_space(H5Dget_space(d), H5Sclose);
            H5Sselect_hyperslab(file_space.get(), H5S_SELECT_SET, &written_, nullptr, &n, nullptr);
            herr_t status = 0;
            if (numeric_[c]) {
                for (hsize_t r = 0; r < n; ++r) numbers[r] = number_at(rows_[r], c);
                status = H5Dwrite(d, H5T_NATIVE_DOUBLE, memory.get(), file_space.get(), H5P_DEFAULT, numbers.data());
            } else {
                for (hsize_t r = 0; r < n; ++r) {
                    words[r] = text_at(rows_[r], c);
                    pointers[r] = words[r].c_str();
                }
                status = H5Dwrite(d, text.get(), memory.get(), file_space.get(), H5P_DEFAULT, pointers.data());
            }
            if (status < 0) fail(label_, "write " + group_ + "/" + columns_[c]);
        }
        written_ = size;
        rows_.clear();
    }

    static double number_at(const std::vector<Cell>& row, std::size_t c) {
        double v = std::numeric_limits<double>::quiet_NaN();
        if (c < row.size() && !row[c].is_text) return row[c].number;
        if (c < row.size()) parse_number(row[c].text, v);
        return v;
    }
    static std::string text_at(const std::vector<Cell>& row, std::size_t c) {
        if (c >= row.size()) return "";
        if (row[c].is_text) return row[c].text;
        std::ostringstream s;
        s.precision(17);
        s << row[c].number;
        return s.str();
    }

    hid_t file_;
    std::string group_, label_;
    std::vector<std::string> columns_;
    std::string note_;  // a comment row ("# interrupted ..."): the group's attribute `note`
    std::vector<bool> numeric_;
    std::vector<hid_t> datasets_;
    std::vector<Cell> row_;
    std::vector<std::vector<Cell>> rows_;
    hsize_t written_ = 0;
};

/// One HDF5 file written by tables (H5Backend).
class H5File final : public H5Backend {
public:
    explicit H5File(const char* path) {
        H5Eset_auto2(H5E_DEFAULT, nullptr, nullptr);  // errors become exceptions, not HDF5's own printout
        h5_ = checked(H5Fcreate(path, H5F_ACC_TRUNC, H5P_DEFAULT, H5P_DEFAULT), "", "create the file");
    }
    ~H5File() override {
        tables_.clear();
        if (h5_ >= 0) H5Fclose(h5_);
    }
    H5File(const H5File&) = delete;
    H5File& operator=(const H5File&) = delete;

    void attribute(const std::string& name, const std::string& value) override {
        const Handle type(string_type(), H5Tclose);
        const Handle space(H5Screate(H5S_SCALAR), H5Sclose);
        const Handle a(checked(H5Acreate2(h5_, name.c_str(), type.get(), space.get(), H5P_DEFAULT, H5P_DEFAULT), "",
                               "write the attribute " + name),
                       H5Aclose);
        const char* p = value.c_str();
        if (H5Awrite(a.get(), type.get(), &p) < 0) fail("", "write the attribute " + name);
    }

    void text(const std::string& path, const std::string& value) override {
        const Handle type(string_type(), H5Tclose);
        const Handle space(H5Screate(H5S_SCALAR), H5Sclose);
        const Handle d(create_dataset(path, type.get(), space.get()), H5Dclose);
        const char* p = value.c_str();
        if (H5Dwrite(d.get(), type.get(), H5S_ALL, H5S_ALL, H5P_DEFAULT, &p) < 0) fail("", "write " + path);
    }

    void texts(const std::string& path, const std::vector<std::string>& values) override {
        const Handle type(string_type(), H5Tclose);
        const hsize_t n = values.size();
        const Handle space(H5Screate_simple(1, &n, nullptr), H5Sclose);
        const Handle d(create_dataset(path, type.get(), space.get()), H5Dclose);
        std::vector<const char*> p;
        for (const auto& v : values) p.push_back(v.c_str());
        if (n > 0 && H5Dwrite(d.get(), type.get(), H5S_ALL, H5S_ALL, H5P_DEFAULT, p.data()) < 0)
            fail("", "write " + path);
    }

    TableSink& table(const std::string& group) override {
        tables_.push_back(std::make_unique<H5Table>(h5_, group, ""));
        return *tables_.back();
    }

    void close() override {
        for (auto& t : tables_) t->finish();
        tables_.clear();
        const herr_t closed = H5Fclose(h5_);
        h5_ = -1;
        if (closed < 0) fail("", "close the file");
    }

private:
    hid_t create_dataset(const std::string& path, hid_t type, hid_t space) const {
        const Handle lcpl(intermediate_groups(), H5Pclose);
        return checked(H5Dcreate2(h5_, path.c_str(), type, space, lcpl.get(), H5P_DEFAULT, H5P_DEFAULT), "",
                       "create the dataset " + path);
    }

    hid_t h5_ = -1;
    std::vector<std::unique_ptr<H5Table>> tables_;
};

}  // namespace hsnc

/// The entry point hsnc looks up after dlopen()ing libhsnc_h5.so (H5Open).
extern "C" hsnc::H5Backend* hsnc_h5_open(const char* path) {
    return new hsnc::H5File(path);
}
