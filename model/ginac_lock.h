// hsnc -- one lock for every use of GiNaC and CLN in a process.
//
// GiNaC and CLN are not thread-safe: their numbers share reference-counted
// constants whose counts are not atomic, and GiNaC::Digits is global. Two
// threads evaluating model expressions at once (a continuation on two
// threads re-reads the model at each parameter value) corrupted the heap
// ("unaligned tcache chunk" at thread exit, one run in two). Every entry
// point that creates GiNaC objects where threads may run (the model reader,
// the program and kernel sources of the interpreter and the JIT) holds this
// lock for the whole life of those objects; what they return holds none.
#pragma once

#include <mutex>

namespace hsnc {

/// Held for the scope of the returned lock (recursive: an entry point may call another).
inline std::unique_lock<std::recursive_mutex> ginac_lock() {
    static std::recursive_mutex mutex;
    return std::unique_lock<std::recursive_mutex>(mutex);
}

}  // namespace hsnc
