// hsnc -- the trajectory and events CSV files (interface.md section 4).
// Numbers with 17 significant digits (they round-trip). A file is written
// under a temporary name and renamed into place by commit(), so a run that
// fails never leaves half a file under the name the user gave.
#pragma once

#include <cstdio>
#include <string>

#include "engine.h"
#include "model.h"

namespace hsnc {

class CsvFile {
public:
    /// Opens "<path>.tmp.<pid>"; throws InputError when it cannot be created.
    explicit CsvFile(std::string path);
    ~CsvFile();  ///< removes the temporary file unless committed
    CsvFile(const CsvFile&) = delete;
    CsvFile& operator=(const CsvFile&) = delete;

    void text(const char* s);
    void number(double value);  ///< 17 significant digits, shortest exact form
    void end_row();
    /// Flush, close and rename into place. Throws RunError on I/O failure.
    void commit();

private:
    std::string path_, tmp_;
    std::FILE* file_ = nullptr;
    bool first_in_row_ = true;
};

/// Header "t,x_<mass>...,v_<mass>..." (and for events "t,kind,element,...").
std::string trajectory_header(const Model& model);
std::string events_header(const Model& model);

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
