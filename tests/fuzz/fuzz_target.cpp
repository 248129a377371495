// A libFuzzer target over one reader (fuzz_entries.h). Built once per target with
// PRT_FUZZ_TARGET_NAME set to the target's name ("ply", "pcd", ...), by tests/fuzz/CMakeLists.txt
// when PRT_FUZZ=ON (clang only). Run through scripts/fuzz.sh.
#include <cstdio>
#include <cstdlib>
#include <string_view>

#include "fuzz_entries.h"

namespace {

prt::fuzz::Target target_of(std::string_view name) {
    for (const prt::fuzz::TargetInfo& t : prt::fuzz::k_targets)
        if (name == t.name) return t.target;
    std::fprintf(stderr, "prt-fuzz: unknown target '%s'\n", name.data());
    std::abort();
}

const prt::fuzz::Target k_target = target_of(PRT_FUZZ_TARGET_NAME);

}  // namespace

extern "C" int LLVMFuzzerInitialize(int*, char***) {
    if (!prt::fuzz::available(k_target)) {
        std::fprintf(stderr, "prt-fuzz-%s: this build lacks the library the reader needs\n",
                     PRT_FUZZ_TARGET_NAME);
        std::exit(1);
    }
    (void)prt::fuzz::scratch_dir();  // created before the first input, removed at exit
    return 0;
}

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
    const prt::fuzz::Result r = prt::fuzz::run(k_target, {data, size});
    if (!r.violation.empty()) {
        std::fprintf(stderr, "prt-fuzz-%s: oracle violated: %s\n", PRT_FUZZ_TARGET_NAME, r.violation.c_str());
        std::abort();  // libFuzzer saves the input as crash-*
    }
    return 0;
}
