// hsnc -- the trajectory and events CSV files (interface.md section 4).
// Numbers with 17 significant digits (they round-trip). Written through an
// OutputFile (output_file.h): a regular file under a temporary name renamed
// into place by commit(), so a run that fails never leaves half a file under
// the name the user gave; a device or FIFO directly; the first write error
// stops the run (RunError naming the file).
#pragma once

#include <memory>
#include <string>
#include <vector>

#include "model.h"
#include "observer.h"
#include "output_file.h"

namespace hsnc {

/// Where the cells of a table go besides (or instead of) a CSV file: the
/// first row is the header (text cells holding comma-separated column names),
/// then one row per end_row() (h5_archive.h: a table of an HDF5 file).
class TableSink {
public:
    virtual ~TableSink() = default;
    virtual void text(const char* s) = 0;
    virtual void number(double value) = 0;
    virtual void end_row() = 0;
};

class CsvFile {
public:
    /// Checks `path` (check_output, InputError) and opens it.
    explicit CsvFile(const std::string& path);
    /// Opens a target checked before the run.
    explicit CsvFile(const OutputTarget& target);
    /// The same table into `mirror` too (may be null); without a target (null)
    /// into the mirror alone.
    CsvFile(const OutputTarget* target, TableSink* mirror);
    CsvFile(const CsvFile&) = delete;
    CsvFile& operator=(const CsvFile&) = delete;

    void text(const char* s);
    void number(double value);  ///< 17 significant digits, shortest exact form
    void end_row();
    /// Flush, close and rename into place. Throws RunError on I/O failure.
    void commit() {
        if (file_) file_->commit();
    }
    /// The CSV file (only when it was given a target).
    const OutputFile& file() const { return *file_; }

private:
    std::unique_ptr<OutputFile> file_;  // removes its temporary file unless committed
    TableSink* mirror_ = nullptr;
    bool first_in_row_ = true;
};

/// A command's result as named values, kept once for both of its forms: the
/// `name=value ...` summary line on stdout (numbers as number_text: integers
/// without a point) and, with --h5, a one-row table of the same columns
/// (h5_archive.h). A value may belong to one form only (`Where`).
class SummaryRow {
public:
    enum class Where : unsigned char { both, line, table };
    void word(const std::string& name, const std::string& value, Where where = Where::both);
    void number(const std::string& name, double value, Where where = Where::both);
    /// "name=value name=value ...".
    std::string line() const;
    /// The header row, then the one row of values.
    void write(TableSink& table) const;

private:
    struct Field {
        std::string name, word;
        double number;
        bool is_word;
        Where where;
    };
    std::vector<Field> fields_;
};

/// Header "t,x_<mass>...,v_<mass>..." (and for events "t,kind,element,...").
std::string trajectory_header(const Model& model);
std::string events_header(const Model& model);

/// The state columns of one row at time t: the masses' x, then v, then every
/// Jenkins slider (x holds the sliders after the masses, Model::state_size());
/// with massless dofs, every dof of the structure, the condensed ones
/// recovered as x_c = R x + K_cc^-1 f_c(t) (their loads and forcing).
void state_numbers(const Model& model, CsvFile& file, double t, const double* x, const double* v);

/// An Observer that writes the CSVs it was given (either may be null).
class CsvObserver : public Observer {
public:
    CsvObserver(const Model& model, CsvFile* trajectory, CsvFile* events);
    void on_sample(double t, const double* x, const double* v) override;
    void on_event(double t, EventKind kind, int element, const double* x, const double* v) override;

private:
    void state(const double* x, const double* v);
    const Model& model_;
    CsvFile* trajectory_;
    CsvFile* events_;
};

}  // namespace hsnc
