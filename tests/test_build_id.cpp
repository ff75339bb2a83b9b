// The index of the kernel cache is keyed by the GNU build ID of the object
// that holds the generator and emitter code (runtime/jit/kernel_cache.h,
// module_build_id): `hsnc` itself, or libhsnc.so when a user's program links
// the library -- never the user's executable, whose build ID says nothing
// about the code that derives the kernels. Build IDs are read independently
// from the files with readelf (binutils).
#include <gtest/gtest.h>

#include <cstdio>
#include <filesystem>
#include <string>

#include "kernel_cache.h"

namespace hsnc {
namespace {

std::string command_output(const std::string& command) {
    std::string out;
    if (std::FILE* p = ::popen(command.c_str(), "r")) {
        char buf[256];
        while (std::fgets(buf, sizeof buf, p)) out += buf;
        ::pclose(p);
    }
    return out;
}

// "Build ID: 3f2a..." of `readelf -n FILE`; "" when it has none.
std::string build_id_of_file(const std::string& path) {
    const std::string notes = command_output("readelf -n '" + path + "' 2>/dev/null");
    const std::string tag = "Build ID: ";
    const std::size_t at = notes.find(tag);
    if (at == std::string::npos) return "";
    const std::size_t start = at + tag.size();
    return notes.substr(start, notes.find_first_of(" \n", start) - start);
}

TEST(KernelCacheBuildId, IsTheExecutablesWhenTheCodeIsLinkedIntoIt) {
    // The test program links the runtime statically, as `hsnc` does. (The
    // path of this process's file: /proc/self/exe in readelf's own process
    // would name readelf.)
    const std::string exe = build_id_of_file(std::filesystem::read_symlink("/proc/self/exe").string());
    ASSERT_FALSE(exe.empty()) << "readelf found no build ID in the test executable";
    EXPECT_EQ(module_build_id(), exe);
}

TEST(KernelCacheBuildId, IsLibhsncsWhenAProgramLinksTheLibrary) {
    const std::string library = build_id_of_file(HSNC_LIBRARY_FILE);
    const std::string probe = build_id_of_file(HSNC_BUILD_ID_PROBE);
    ASSERT_FALSE(library.empty()) << HSNC_LIBRARY_FILE;
    ASSERT_FALSE(probe.empty()) << HSNC_BUILD_ID_PROBE;
    ASSERT_NE(library, probe);
    std::string reported = command_output(std::string("'") + HSNC_BUILD_ID_PROBE + "'");
    if (!reported.empty() && reported.back() == '\n') reported.pop_back();
    EXPECT_EQ(reported, library) << "the probe's own build ID is " << probe;
}

}  // namespace
}  // namespace hsnc
