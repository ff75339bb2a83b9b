#include "input_files.h"

#include <mutex>
#include <stdexcept>
#include <vector>

namespace hsnc {
namespace {

struct Input {
    dev_t dev;
    ino_t ino;
    std::string path;
};

std::mutex g_mutex;
bool g_active = false;
std::vector<Input> g_inputs;  // a handful per run: a model and up to three matrices, or the parts

}  // namespace

InputFileScope::InputFileScope() {
    std::lock_guard<std::mutex> lock(g_mutex);
    if (g_active) throw std::logic_error("InputFileScope: scopes do not nest");
    g_active = true;
    g_inputs.clear();
}

InputFileScope::~InputFileScope() {
    std::lock_guard<std::mutex> lock(g_mutex);
    g_active = false;
    g_inputs.clear();
}

void note_input_file(const std::string& path, const struct stat& status) {
    std::lock_guard<std::mutex> lock(g_mutex);
    if (!g_active) return;
    for (const Input& i : g_inputs)
        if (i.dev == status.st_dev && i.ino == status.st_ino) return;
    g_inputs.push_back({status.st_dev, status.st_ino, path});
}

void note_input_file(const std::string& path) {
    struct stat st;
    if (::stat(path.c_str(), &st) == 0) note_input_file(path, st);
}

std::string input_file_named(dev_t dev, ino_t ino) {
    std::lock_guard<std::mutex> lock(g_mutex);
    for (const Input& i : g_inputs)
        if (i.dev == dev && i.ino == ino) return i.path;
    return {};
}

}  // namespace hsnc
