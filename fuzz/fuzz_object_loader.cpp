// libFuzzer target: the cached-kernel object loader (runtime/jit/object_loader.h)
// on arbitrary bytes taken as an object file, as a cache entry's payload would
// be. It must map the object or refuse it with a reason; a crash, a sanitizer
// report or a write outside its own pages is a defect. Nothing it maps is
// executed. docs/development.md.
#include <cstddef>
#include <cstdint>
#include <memory>
#include <string>

#include "object_loader.h"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
    const std::string bytes(reinterpret_cast<const char*>(data), size);
    std::string why;
    const std::unique_ptr<hsnc::LoadedObject> object = hsnc::LoadedObject::load(bytes, why);
    if (!object) {
        if (why.empty()) __builtin_trap();  // a refusal always says why
        return 0;
    }
    // What a caller does next: find symbols, and check pointers against the object.
    for (const std::string& name : object->symbol_names()) {
        const void* p = object->symbol(name);
        if (p && !object->contains(p, 0)) __builtin_trap();  // a symbol outside the object
        if (p) (void)object->contains_string(static_cast<const char*>(p));
    }
    return 0;
}
