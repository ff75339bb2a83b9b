#include "model_reader.h"

#include "error.h"

namespace hsnc {

Model read_model(const std::string& path, const ModelOverrides&) {
    throw InputError(path + ": model reader not implemented yet");
}

Model parse_model(const std::string&, const std::string& source, const ModelOverrides&) {
    throw InputError(source + ": model reader not implemented yet");
}

}  // namespace hsnc
