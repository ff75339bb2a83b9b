// hsnc -- one HDF5 file per command (--h5 FILE): the tables the command's CSV
// files hold (whether or not they are asked for), with the model text, its
// overrides, the hsnc version and the command line, so that the results carry
// what made them (docs/interface.md, "HDF5 output").
//
// Layout: root attributes `format` ("hsnc-h5 1"), `hsnc_version`, `command`,
// `model_name`; datasets `/model/text` (the model file as read), `/model/path`
// and `/model/overrides` (one string per --set/--x0/--v0 as given); then one
// group per table (`/simulate/trajectory`, `/simulate/events`, `/sweep/curve`,
// ...) with one 1-D dataset per CSV column, named as the column: float64, or
// UTF-8 strings for a column of words (`kind`, `direction`, `stable`), and an
// attribute `columns` holding the CSV header, in order.
//
// The file is written as every output is (output_file.h): under a temporary
// name beside the target, renamed into place when the command succeeds, never
// half a file; HDF5 seeks, so a device or a pipe is refused before the run.
// HDF5 itself (and the libraries it loads: curl, Kerberos, about 16 ms of
// every process's start-up) lives in libhsnc_h5.so (h5_backend.cpp), which
// the command line loads only when --h5 is given.
#pragma once

#include <cstdint>
#include <memory>
#include <string>
#include <vector>

#include "csv_writer.h"
#include "output_file.h"

namespace hsnc {

/// Checks `path` for --h5 (check_output, and a regular file or a new name:
/// InputError otherwise).
OutputTarget check_h5_output(const std::string& path);

/// What libhsnc_h5.so implements with HDF5 (h5_backend.cpp): one file, its
/// attributes, string datasets and tables. Errors are std::runtime_error.
class H5Backend {
public:
    virtual ~H5Backend() = default;
    virtual void attribute(const std::string& name, const std::string& value) = 0;
    virtual void text(const std::string& path, const std::string& value) = 0;
    virtual void texts(const std::string& path, const std::vector<std::string>& values) = 0;
    virtual TableSink& table(const std::string& group) = 0;
    /// Writes what the tables still hold and closes the file.
    virtual void close() = 0;
};

/// The module's entry point (extern "C" hsnc_h5_open): creates the HDF5 file at `path`.
using H5Open = H5Backend* (*)(const char* path);

class H5Archive {
public:
    /// Creates the file under its temporary name through `open` (the
    /// module's entry point). Throws RunError when it cannot.
    H5Archive(const OutputTarget& target, H5Open open);
    ~H5Archive();  ///< the temporary file is removed unless committed
    H5Archive(const H5Archive&) = delete;
    H5Archive& operator=(const H5Archive&) = delete;

    /// A string attribute of the root group.
    void attribute(const std::string& name, const std::string& value);
    /// A dataset holding one string, or a list of strings (groups created on the way).
    void text(const std::string& path, const std::string& value);
    void texts(const std::string& path, const std::vector<std::string>& values);
    /// A table under `group` (e.g. "sweep/curve"), fed as a CSV file is (csv_writer.h).
    TableSink& table(const std::string& group);
    /// Writes what the tables hold, closes the file and renames it into place
    /// (inside the command's OutputTransaction). Throws RunError.
    void commit();

private:
    class Table;
    template <class F>
    void guarded(F&& f);
    std::unique_ptr<OutputFile> file_;
    std::unique_ptr<H5Backend> backend_;
    std::string label_;
    std::vector<std::unique_ptr<Table>> tables_;
};

/// What every command writes first: the format, the version, the command line,
/// the model's name, text, path and overrides (as given on the command line).
void write_h5_provenance(H5Archive& archive, const std::string& model_name, const std::string& model_path,
                         const std::vector<std::string>& overrides);

/// The command line of this process, as given (set by the CLI's main).
void set_command_line(int argc, const char* const* argv);
const std::string& command_line();

}  // namespace hsnc
