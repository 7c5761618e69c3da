// kernel_ab SCENE RAYS ACCEL ROUNDS [located]: the earlier and the current kernels
// (kernels.cpp, compiled twice by bench/tools/kernel_ab.py) trace the same rays through the
// same structure in turns, one thread; prints the median of the rounds' speed ratios and
// their quartiles, as one JSON object.
#include <algorithm>
#include <cstdio>
#include <cstdlib>
#include <exception>
#include <memory>
#include <string>
#include <vector>

#include "accel_factory.h"
#include "rebraid/io/ray_file.h"
#include "rebraid/rebraid.h"
#include "rebraid/top_level/flat_accel.h"
#include "rebraid/top_level/instanced_accel.h"

namespace kernel_ab {
double run_earlier(const rebraid::FlatAccel*, const rebraid::InstancedAccel*,
                   const std::vector<rebraid::Ray>&, bool, double&);
double run_current(const rebraid::FlatAccel*, const rebraid::InstancedAccel*,
                   const std::vector<rebraid::Ray>&, bool, double&);
}  // namespace kernel_ab

namespace {

double quantile(std::vector<double> values, double q) {
    std::sort(values.begin(), values.end());
    return values[std::size_t(q * double(values.size() - 1) + 0.5)];
}

}  // namespace

int main(int argc, char** argv) {
    if (argc < 5) {
        std::fprintf(stderr, "usage: kernel_ab SCENE|default RAYS ACCEL ROUNDS [located]\n");
        return 1;
    }
    try {
        const std::string path = argv[1];
        const rebraid::Scene scene =
            path == "default" ? rebraid::make_default_scene() : rebraid::load_gltf_scene(path);
        const std::vector<rebraid::Ray> rays = rebraid::read_ray_file(argv[2]);
        const std::unique_ptr<rebraid::Accel> accel = rebraid::cli::build_accel(argv[3], scene);
        const int rounds = std::max(std::atoi(argv[4]), 2);
        const bool located = argc > 5 && std::string(argv[5]) == "located";
        const auto* flat = dynamic_cast<const rebraid::FlatAccel*>(accel.get());
        const auto* instanced = dynamic_cast<const rebraid::InstancedAccel*>(accel.get());
        if (flat == nullptr && instanced == nullptr)
            throw rebraid::Error(std::string(argv[3]) + " is not one of the project's structures");
        std::vector<double> ratios, earlier_seconds, current_seconds;
        double earlier_sum = 0.0, current_sum = 0.0;
        // Turns alternate which copy goes first; the first round warms the caches up.
        for (int round = 0; round < rounds; ++round) {
            double earlier, current;
            if (round % 2 == 0) {
                earlier = kernel_ab::run_earlier(flat, instanced, rays, located, earlier_sum);
                current = kernel_ab::run_current(flat, instanced, rays, located, current_sum);
            } else {
                current = kernel_ab::run_current(flat, instanced, rays, located, current_sum);
                earlier = kernel_ab::run_earlier(flat, instanced, rays, located, earlier_sum);
            }
            if (round == 0) continue;
            ratios.push_back(earlier / current);
            earlier_seconds.push_back(earlier);
            current_seconds.push_back(current);
        }
        const double n = double(rays.size());
        std::printf(
            "{\"accel\": \"%s\", \"rays\": %zu, \"located\": %s, \"rounds\": %d, "
            "\"earlier_mrays\": %.3f, \"current_mrays\": %.3f, \"current_over_earlier\": %.4f, "
            "\"quartiles\": [%.4f, %.4f], \"same_hits\": %s}\n",
            argv[3], rays.size(), located ? "true" : "false", rounds - 1,
            n / quantile(earlier_seconds, 0.5) * 1e-6, n / quantile(current_seconds, 0.5) * 1e-6,
            quantile(ratios, 0.5), quantile(ratios, 0.25), quantile(ratios, 0.75),
            earlier_sum == current_sum ? "true" : "false");
        return 0;
    } catch (const std::exception& error) {
        std::fprintf(stderr, "kernel_ab: %s\n", error.what());
        return 1;
    }
}
