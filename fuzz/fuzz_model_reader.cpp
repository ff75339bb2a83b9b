// libFuzzer target: the model reader (model/model_reader.h) on arbitrary
// bytes taken as the text of a model file. A model that is not valid must be
// an InputError with a message; anything else (a crash, a sanitizer report,
// another exception, a hang) is a defect. docs/development.md.
#include <cstddef>
#include <cstdint>
#include <string>

#include "error.h"
#include "model_reader.h"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
    const std::string text(reinterpret_cast<const char*>(data), size);
    try {
        const hsnc::Model model = hsnc::parse_model(text, "fuzz.toml", {});
        (void)model;
    } catch (const hsnc::InputError&) {
        // a rejected model: the expected outcome for most inputs
    }
    return 0;
}
