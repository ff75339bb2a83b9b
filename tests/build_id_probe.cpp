// A program that links libhsnc.so (not the static libraries `hsnc` links):
// prints module_build_id() as the library computes it when it runs inside a
// program of its user (tests/test_build_id.cpp).
#include <cstdio>

#include "kernel_cache.h"

int main() {
    std::printf("%s\n", hsnc::module_build_id().c_str());
    return 0;
}
