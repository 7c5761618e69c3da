// libFuzzer target: build every project structure (flat, twolevel, rebraid with the default
// settings and with opening forced everywhere) over a scene decoded from the fuzzer's bytes
// (fuzzed_scene.h) and check its answers against Embree flat (answer_check.h). Any
// disagreement, crash or exception other than a documented rejection aborts.
#include <tbb/global_control.h>

#include <cstddef>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <memory>

#include "answer_check.h"
#include "embree_glue/reference/embree_reference.h"
#include "fuzzed_scene.h"
#include "rebraid/core/error.h"
#include "rebraid/rebraiding/rebraid_accel.h"
#include "rebraid/rebraiding/rebraid_builder.h"
#include "rebraid/top_level/flat_accel.h"
#include "rebraid/top_level/instanced_accel.h"

namespace {

void expect_agreement(const rebraid::Scene& scene, const rebraid::Accel& reference,
                      const rebraid::Accel& candidate, std::span<const rebraid::Ray> rays,
                      const char* name) {
    const std::string disagreement =
        rebraid::fuzz::compare_answers(scene, reference, candidate, rays).disagreement;
    if (disagreement.empty()) return;
    std::fprintf(stderr, "%s disagrees with embree-flat: %s\n", name, disagreement.c_str());
    std::abort();
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
    // One thread: the fuzzer measures coverage per input, and the machine is shared.
    static tbb::global_control one_thread(tbb::global_control::max_allowed_parallelism, 1);
    const rebraid::fuzz::FuzzedCase fuzzed = rebraid::fuzz::decode_case({data, size});
    const rebraid::Scene& scene = fuzzed.scene;
    scene.validate();  // decode_case promises a valid scene: an Error here is a bug
    const rebraid::glue::EmbreeFlatAccel reference(scene, {.device_config = "threads=1"});
    expect_agreement(scene, reference, rebraid::FlatAccel(scene), fuzzed.rays, "flat");
    expect_agreement(scene, reference, rebraid::build_two_level_accel(scene), fuzzed.rays,
                     "twolevel");
    expect_agreement(scene, reference, rebraid::build_rebraid_accel(scene), fuzzed.rays, "rebraid");
    const rebraid::RebraidSettings open_everything{.open_threshold = 0.0f, .budget_factor = 64.0f};
    expect_agreement(
        scene, reference,
        rebraid::build_rebraid_accel(scene, rebraid::own_object_bvh_builder(), open_everything),
        fuzzed.rays, "rebraid-open-everything");
    return 0;
}
