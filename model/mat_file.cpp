#include "mat_file.h"

#include <dlfcn.h>

#include <cmath>
#include <cstdint>
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

/// HDF5's hid_t (int64_t since HDF5 1.10) and the two constants used: H5E_DEFAULT, H5P_DEFAULT.
using Hid = std::int64_t;
constexpr Hid kH5Default = 0;
constexpr unsigned kH5ReadOnly = 0;  // H5F_ACC_RDONLY

/// The messages libmatio logs while hsnc reads one file (instead of its own
/// "ERROR: ..." lines on stderr); the reader holds the model reader's lock, so one at a time.
std::string& matio_log() {
    static std::string log;
    return log;
}

void quiet_log(int /*level*/, char* message) {
    if (message && matio_log().size() < 400) matio_log() += (matio_log().empty() ? "" : "; ") + std::string(message);
}

/// The few libmatio functions hsnc calls, resolved once; and HDF5's, through
/// libmatio's own dependency (version 7.3 files are HDF5 files).
struct Matio {
    decltype(&Mat_Open) open = nullptr;
    decltype(&Mat_Close) close = nullptr;
    decltype(&Mat_VarReadInfo) read_info = nullptr;
    decltype(&Mat_VarRead) read = nullptr;
    decltype(&Mat_VarFree) free = nullptr;
    Hid (*h5_open)(const char*, unsigned, Hid) = nullptr;
    int (*h5_close)(Hid) = nullptr;
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
        read_info = reinterpret_cast<decltype(read_info)>(dlsym(lib, "Mat_VarReadInfo"));
        read = reinterpret_cast<decltype(read)>(dlsym(lib, "Mat_VarRead"));
        free = reinterpret_cast<decltype(free)>(dlsym(lib, "Mat_VarFree"));
        if (!open || !close || !read_info || !read || !free)
            error = "libmatio lacks Mat_Open, Mat_Close, Mat_VarReadInfo, Mat_VarRead or Mat_VarFree";
        using LogInit = int (*)(const char*, void (*)(int, char*));
        if (const auto log_init = reinterpret_cast<LogInit>(dlsym(lib, "Mat_LogInitFunc"))) log_init("hsnc", quiet_log);
        // HDF5 prints its whole error stack (14 lines) on stderr for a file it
        // cannot open; hsnc says what went wrong in one message instead.
        using SetAuto = int (*)(Hid, void*, void*);
        if (const auto set_auto = reinterpret_cast<SetAuto>(dlsym(lib, "H5Eset_auto2"))) set_auto(kH5Default, nullptr, nullptr);
        h5_open = reinterpret_cast<decltype(h5_open)>(dlsym(lib, "H5Fopen"));
        h5_close = reinterpret_cast<decltype(h5_close)>(dlsym(lib, "H5Fclose"));
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

/// What the layout check found out about a file.
struct Layout {
    bool hdf5 = false;        ///< version 7.3
    bool compressed = false;  ///< a version 5 file with a compressed variable
};

/// deflate's largest expansion (RFC 1951: a 258-byte match in at most 2 bits
/// of a fixed block, about 1032:1): bytes a compressed file of size S can hold.
constexpr std::uint64_t kMaxInflation = 1032;

/// The layout of a .mat file held in `bytes`, checked before libmatio reads
/// it: libmatio reads a variable cut short by the end of the file as zeros
/// (a truncated file gives K = 0 or half its couplings, silently), so every
/// top-level element of a version 5 file (128-byte header, then elements
/// "type (4 bytes), size (4 bytes), data") must lie whole inside the file.
/// A version 7.3 file must be an HDF5 file (its signature at byte 512, 1024,
/// ...: the 128-byte MATLAB header sits in HDF5's user block). Throws InputError.
Layout check_layout(const std::string& bytes, const std::string& where) {
    const std::size_t size = bytes.size();
    if (size < 128)
        throw InputError(where + ": not a MATLAB .mat file, or truncated (" + std::to_string(size) +
                         " bytes, shorter than the 128-byte header)");
    const bool swap = bytes[126] == 'M' && bytes[127] == 'I';  // written on a machine of the other byte order
    if (!swap && !(bytes[126] == 'I' && bytes[127] == 'M'))
        throw InputError(where + ": not a MATLAB .mat file of version 5 or 7.3 (no 'MATLAB 5.0' header; hsnc does not "
                                 "read version 4: save with -v7 or -v7.3)");
    auto u16 = [&](std::size_t at) {
        const auto b0 = static_cast<unsigned char>(bytes[at]), b1 = static_cast<unsigned char>(bytes[at + 1]);
        return static_cast<std::uint16_t>(swap ? (b0 << 8) | b1 : (b1 << 8) | b0);
    };
    auto u32 = [&](std::size_t at) {
        std::uint32_t v = 0;
        for (int k = 0; k < 4; ++k)
            v |= static_cast<std::uint32_t>(static_cast<unsigned char>(bytes[at + k])) << (swap ? 8 * (3 - k) : 8 * k);
        return v;
    };
    Layout layout;
    const std::uint16_t version = u16(124);
    if (version == 0x0200) {
        static const char kSignature[] = "\x89HDF\r\n\x1a\n";
        for (std::size_t at = 512; at + 8 <= size; at *= 2)
            if (bytes.compare(at, 8, kSignature, 8) == 0) {
                layout.hdf5 = true;
                return layout;
            }
        throw InputError(where + ": a MATLAB version 7.3 header, but not an HDF5 file (no HDF5 signature at byte 512, "
                                 "1024, ...): truncated or damaged");
    }
    if (version != 0x0100)
        throw InputError(where + ": not a MATLAB .mat file of version 5 or 7.3 (header version " +
                         std::to_string(version) + ")");
    constexpr std::uint32_t kMatrix = 14, kCompressed = 15;  // miMATRIX, miCOMPRESSED
    for (std::size_t at = 128; at < size;) {
        if (size - at < 8)
            throw InputError(where + ": the file is truncated or damaged (it ends inside the tag of the element at byte " +
                             std::to_string(at) + ")");
        const std::uint32_t type = u32(at), length = u32(at + 4);
        if (type != kMatrix && type != kCompressed)
            throw InputError(where + ": the file is damaged (an element of type " + std::to_string(type) + " at byte " +
                             std::to_string(at) + ", expected a variable)");
        if (length > size - at - 8)
            throw InputError(where + ": the file is truncated (the variable at byte " + std::to_string(at) + " needs " +
                             std::to_string(length) + " bytes, the file ends " + std::to_string(size - at - 8) +
                             " bytes after its tag)");
        layout.compressed = layout.compressed || type == kCompressed;
        at += 8 + length;
    }
    return layout;
}

}  // namespace

MarketMatrix read_mat_variable(const std::string& path, const std::string& variable) {
    const Matio& m = matio();
    const std::string where = path + ":" + variable;
    if (!m.error.empty()) throw InputError(where + ": cannot read .mat files: " + m.error);
    // A regular file of bounded size first (file_read.h): libmatio would open a FIFO or a device.
    const FileRead file = read_regular_file(path, kMaxMatrixFileBytes);
    if (file.status != FileRead::Status::ok) throw InputError("cannot read matrix file '" + path + "': " + file.problem);
    const Layout layout = check_layout(file.bytes, where);
    if (layout.hdf5 && m.h5_open && m.h5_close) {
        // HDF5 refuses a file shorter than its superblock says (a truncated
        // one); libmatio would open it anyway and then find no variable.
        const Hid h = m.h5_open(path.c_str(), kH5ReadOnly, kH5Default);
        if (h < 0) throw InputError(where + ": a MATLAB version 7.3 file that HDF5 cannot open: truncated or damaged");
        m.h5_close(h);
    }
    matio_log().clear();
    auto log = [] { return matio_log().empty() ? std::string() : " (libmatio: " + matio_log() + ")"; };
    std::unique_ptr<mat_t, int (*)(mat_t*)> mat(m.open(path.c_str(), MAT_ACC_RDONLY), m.close);
    if (!mat) throw InputError("cannot read matrix file '" + path + "': not a MATLAB .mat file" + log());

    // The header first (class, rank, dimensions), against the limits and the
    // file's size, before libmatio allocates and reads the data.
    {
        std::unique_ptr<matvar_t, void (*)(matvar_t*)> info(m.read_info(mat.get(), variable.c_str()), m.free);
        if (!info) throw InputError(where + ": the file has no variable '" + variable + "'" + log());
        if (info->rank != 2)
            throw InputError(where + ": a " + std::to_string(info->rank) + "-dimensional array, expected a matrix");
        if (info->isComplex) throw InputError(where + ": complex, expected a real matrix");
        if (info->class_type != MAT_C_DOUBLE && info->class_type != MAT_C_SPARSE)
            throw InputError(where + ": expected a real double matrix (dense or sparse), not MATLAB class " +
                             std::to_string(static_cast<int>(info->class_type)));
        const std::size_t rows = info->dims[0], cols = info->dims[1];
        if (rows > kMaxMatrixDimension || cols > kMaxMatrixDimension)
            throw InputError(where + ": " + std::to_string(rows) + " x " + std::to_string(cols) + " exceeds " +
                             std::to_string(kMaxMatrixDimension) + " in a dimension");
        // A dense variable's doubles must fit in the file (or, compressed, in what the file can inflate to).
        const std::uint64_t need = std::uint64_t{8} * rows * cols;
        const std::uint64_t room = file.bytes.size() * (layout.compressed || layout.hdf5 ? kMaxInflation : 1);
        if (info->class_type == MAT_C_DOUBLE && need > room)
            throw InputError(where + ": the header says " + std::to_string(rows) + " x " + std::to_string(cols) + " (" +
                             std::to_string(need) + " bytes of doubles), more than the " +
                             std::to_string(file.bytes.size()) + "-byte file holds: truncated or damaged");
    }

    std::unique_ptr<matvar_t, void (*)(matvar_t*)> var(m.read(mat.get(), variable.c_str()), m.free);
    if (!var) throw InputError(where + ": cannot read the variable: truncated or damaged" + log());
    const std::size_t rows = var->dims[0], cols = var->dims[1];
    if (var->rank != 2 || rows > kMaxMatrixDimension || cols > kMaxMatrixDimension || var->isComplex)
        throw InputError(where + ": the variable's data does not match its header: damaged");
    MarketMatrix out;
    out.rows = rows;
    out.cols = cols;
    out.values.assign(rows * cols, 0.0);
    if (var->class_type == MAT_C_DOUBLE && var->data_type == MAT_T_DOUBLE && var->data) {
        const double* d = static_cast<const double*>(var->data);
        for (std::size_t j = 0; j < cols; ++j)  // column-major
            for (std::size_t i = 0; i < rows; ++i) out.values[i * cols + j] = checked(d[j * rows + i], where, i, j);
        return out;
    }
    if (var->class_type == MAT_C_SPARSE && var->data_type == MAT_T_DOUBLE && var->data) {
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
