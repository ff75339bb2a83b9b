#include "h5_archive.h"

#include <fstream>
#include <sstream>
#include <stdexcept>

#include "error.h"

namespace hsnc {

namespace {

std::string& command_text() {
    static std::string text;
    return text;
}

}  // namespace

void set_command_line(int argc, const char* const* argv) {
    std::string& text = command_text();
    text.clear();
    for (int i = 0; i < argc; ++i) text += (i ? " " : "") + std::string(argv[i]);
}

const std::string& command_line() {
    return command_text();
}

void write_h5_provenance(H5Archive& archive, const std::string& model_name, const std::string& model_path,
                         const std::vector<std::string>& overrides) {
    archive.attribute("format", "hsnc-h5 1");
    archive.attribute("hsnc_version", HSNC_VERSION);
    archive.attribute("command", command_line());
    archive.attribute("model_name", model_name);
    std::ifstream in(model_path, std::ios::binary);
    std::stringstream text;
    text << in.rdbuf();
    archive.text("model/text", text.str());
    archive.text("model/path", model_path);
    archive.texts("model/overrides", overrides);
}

OutputTarget check_h5_output(const std::string& path) {
    OutputTarget t = check_output("--h5", path);
    if (t.mode != OutputTarget::Mode::replace)
        throw InputError(t.label() +
                         ": HDF5 needs a regular file (it seeks): not a device, a pipe or a standard stream");
    return t;
}

/// The module's table, its errors turned into RunError naming the file.
class H5Archive::Table : public TableSink {
public:
    Table(H5Archive& archive, TableSink& inner) : archive_(archive), inner_(inner) {}
    void text(const char* s) override {
        archive_.guarded([&] { inner_.text(s); });
    }
    void number(double value) override {
        archive_.guarded([&] { inner_.number(value); });
    }
    void end_row() override {
        archive_.guarded([&] { inner_.end_row(); });
    }

private:
    H5Archive& archive_;
    TableSink& inner_;
};

template <class F>
void H5Archive::guarded(F&& f) {
    try {
        f();
    } catch (const std::runtime_error& e) {
        throw RunError(label_ + ": " + e.what());
    }
}

H5Archive::H5Archive(const OutputTarget& target, H5Open open)
    : file_(std::make_unique<OutputFile>(target)), label_(target.label()) {
    guarded([&] { backend_.reset(open(file_->temporary().c_str())); });
}

H5Archive::~H5Archive() {
    tables_.clear();
    backend_.reset();  // closes the file (HDF5) before OutputFile removes it
}

void H5Archive::attribute(const std::string& name, const std::string& value) {
    guarded([&] { backend_->attribute(name, value); });
}

void H5Archive::text(const std::string& path, const std::string& value) {
    guarded([&] { backend_->text(path, value); });
}

void H5Archive::texts(const std::string& path, const std::vector<std::string>& values) {
    guarded([&] { backend_->texts(path, values); });
}

TableSink& H5Archive::table(const std::string& group) {
    TableSink* inner = nullptr;
    guarded([&] { inner = &backend_->table(group); });
    tables_.push_back(std::make_unique<Table>(*this, *inner));
    return *tables_.back();
}

void H5Archive::commit() {
    guarded([&] { backend_->close(); });
    file_->commit();
}

}  // namespace hsnc
