#include "mat_file.h"

#include <dlfcn.h>

#include <cmath>
#include <cstdio>
#include <memory>

#include "error.h"
#include "file_read.h"

#if HSNC_WITH_MATIO
#include <matio.h>
#endif

namespace hsnc {
namespace {

bool ends_with(const std::string& s, const std::string& tail) {
    return s.size() >= tail.size() && s.compare(s.size() - tail.size(), tail.size(), tail) == 0;
}

}  // namespace

bool is_mat_spec(const std::string& spec) {
    const std::size_t colon = spec.rfind(':');
    return ends_with(spec, ".mat") || (colon != std::string::npos && ends_with(spec.substr(0, colon), ".mat"));
}

std::pair<std::string, std::string> split_mat_spec(const std::string& spec, const std::string& default_variable) {
    if (ends_with(spec, ".mat")) return {spec, default_variable};
    const std::size_t colon = spec.rfind(':');
    return {spec.substr(0, colon), spec.substr(colon + 1)};
}

#if HSNC_WITH_MATIO

namespace {

/// The few libmatio functions hsnc calls, resolved once.
struct Matio {
    decltype(&Mat_Open) open = nullptr;
    decltype(&Mat_Close) close = nullptr;
    decltype(&Mat_VarRead) read = nullptr;
    decltype(&Mat_VarFree) free = nullptr;
    std::string error;

    Matio() {
        void* lib = dlopen("libmatio.so.11", RTLD_NOW | RTLD_LOCAL);
        if (!lib) lib = dlopen("libmatio.so", RTLD_NOW | RTLD_LOCAL);
        if (!lib) {
            error = std::string("libmatio is not installed (Debian package libmatio11): ") + dlerror();
            return;
        }
        open = reinterpret_cast<decltype(open)>(dlsym(lib, "Mat_Open"));
        close = reinterpret_cast<decltype(close)>(dlsym(lib, "Mat_Close"));
        read = reinterpret_cast<decltype(read)>(dlsym(lib, "Mat_VarRead"));
        free = reinterpret_cast<decltype(free)>(dlsym(lib, "Mat_VarFree"));
        if (!open || !close || !read || !free) error = "libmatio lacks Mat_Open, Mat_Close, Mat_VarRead or Mat_VarFree";
    }
};

const Matio& matio() {
    static const Matio m;  // thread-safe initialisation
    return m;
}

std::string show(double v) {
    char buf[32];
    std::snprintf(buf, sizeof buf, "%.17g", v);
    return buf;
}

double checked(double v, const std::string& where, std::size_t i, std::size_t j) {
    if (v != 0.0 && !std::isnormal(v))
        throw InputError(where + ": entry (" + std::to_string(i + 1) + ", " + std::to_string(j + 1) + ") = " + show(v) +
                         " is not a finite normal double");
    return v == 0.0 ? 0.0 : v;  // -0 as 0
}

}  // namespace

MarketMatrix read_mat_variable(const std::string& path, const std::string& variable) {
    const Matio& m = matio();
    const std::string where = path + ":" + variable;
    if (!m.error.empty()) throw InputError(where + ": cannot read .mat files: " + m.error);
    // A regular file of bounded size first (file_read.h): libmatio would open a FIFO or a device.
    const FileRead check = read_regular_file(path, kMaxMatrixFileBytes);
    if (check.status != FileRead::Status::ok) throw InputError("cannot read matrix file '" + path + "': " + check.problem);
    std::unique_ptr<mat_t, int (*)(mat_t*)> file(m.open(path.c_str(), MAT_ACC_RDONLY), m.close);
    if (!file) throw InputError("cannot read matrix file '" + path + "': not a MATLAB .mat file, or missing");
    std::unique_ptr<matvar_t, void (*)(matvar_t*)> var(m.read(file.get(), variable.c_str()), m.free);
    if (!var) throw InputError(where + ": the file has no variable '" + variable + "'");
    if (var->rank != 2) throw InputError(where + ": a " + std::to_string(var->rank) + "-dimensional array, expected a matrix");
    if (var->isComplex) throw InputError(where + ": complex, expected a real matrix");
    const std::size_t rows = var->dims[0], cols = var->dims[1];
    if (rows > kMaxMatrixDimension || cols > kMaxMatrixDimension)
        throw InputError(where + ": " + std::to_string(rows) + " x " + std::to_string(cols) + " exceeds " +
                         std::to_string(kMaxMatrixDimension) + " in a dimension");
    MarketMatrix out;
    out.rows = rows;
    out.cols = cols;
    out.values.assign(rows * cols, 0.0);
    if (var->class_type == MAT_C_DOUBLE && var->data_type == MAT_T_DOUBLE) {
        const double* d = static_cast<const double*>(var->data);
        for (std::size_t j = 0; j < cols; ++j)  // column-major
            for (std::size_t i = 0; i < rows; ++i) out.values[i * cols + j] = checked(d[j * rows + i], where, i, j);
        return out;
    }
    if (var->class_type == MAT_C_SPARSE && var->data_type == MAT_T_DOUBLE) {
        const auto* s = static_cast<const mat_sparse_t*>(var->data);
        const double* d = static_cast<const double*>(s->data);
        if (s->njc != cols + 1) throw InputError(where + ": a damaged sparse matrix (column index)");
        for (std::size_t j = 0; j < cols; ++j)
            for (mat_uint32_t k = s->jc[j]; k < s->jc[j + 1]; ++k) {
                if (k >= s->nir || k >= s->ndata || s->ir[k] >= rows)
                    throw InputError(where + ": a damaged sparse matrix (row index)");
                out.values[s->ir[k] * cols + j] = checked(d[k], where, s->ir[k], j);
            }
        return out;
    }
    throw InputError(where + ": expected a real double matrix (dense or sparse), not MATLAB class " +
                     std::to_string(static_cast<int>(var->class_type)));
}

#else

MarketMatrix read_mat_variable(const std::string& path, const std::string& variable) {
    throw InputError(path + ":" + variable + ": this hsnc was built without .mat support (CMake option HSNC_WITH_MATIO)");
}

#endif

}  // namespace hsnc
