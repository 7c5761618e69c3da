// Replays fuzz inputs through a fuzz target's LLVMFuzzerTestOneInput without libFuzzer, so the
// committed corpora run as ordinary tests in any build (the `asan` preset runs them under
// AddressSanitizer + UBSan; tests/fuzz/replay.cmake declares them):
//
//     fuzz_gltf_replay FILE_OR_FOLDER...
//
// Every regular file given, and every regular file below every folder given, is read and passed
// to the target once, in sorted path order. A target signals a bug by crashing or aborting (a
// sanitizer report ends the process); the replay itself fails when it finds no input at all,
// so a missing corpus cannot pass unnoticed. Prints the number of inputs and the time taken.
#include <algorithm>
#include <chrono>
#include <cstddef>
#include <cstdint>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <string>
#include <system_error>
#include <vector>

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size);

namespace fs = std::filesystem;

int main(int argc, char** argv) {
    if (argc < 2) {
        std::fprintf(stderr, "usage: %s FILE_OR_FOLDER...\n", argv[0]);
        return 2;
    }
    std::vector<fs::path> inputs;
    for (int i = 1; i < argc; ++i) {
        const fs::path argument = argv[i];
        std::error_code ec;
        if (fs::is_directory(argument, ec)) {
            for (const fs::directory_entry& entry :
                 fs::recursive_directory_iterator(argument, ec))
                if (entry.is_regular_file()) inputs.push_back(entry.path());
        } else if (fs::is_regular_file(argument, ec)) {
            inputs.push_back(argument);
        } else {
            std::fprintf(stderr, "%s: no such file or folder: %s\n", argv[0], argv[i]);
            return 2;
        }
        if (ec) {
            std::fprintf(stderr, "%s: cannot read %s: %s\n", argv[0], argv[i],
                         ec.message().c_str());
            return 2;
        }
    }
    if (inputs.empty()) {
        std::fprintf(stderr, "%s: no input files found\n", argv[0]);
        return 1;
    }
    std::sort(inputs.begin(), inputs.end());
    const auto start = std::chrono::steady_clock::now();
    std::size_t bytes = 0;
    for (const fs::path& path : inputs) {
        std::ifstream in(path, std::ios::binary);
        const std::vector<char> contents((std::istreambuf_iterator<char>(in)),
                                         std::istreambuf_iterator<char>());
        if (in.bad()) {
            std::fprintf(stderr, "%s: cannot read %s\n", argv[0], path.c_str());
            return 2;
        }
        // A copy of exactly `size` bytes on the heap, as libFuzzer passes it: an overread by
        // the target is caught by ASan instead of landing in the vector's spare capacity.
        std::vector<std::uint8_t> data(contents.begin(), contents.end());
        data.shrink_to_fit();
        std::fprintf(stderr, "running %s (%zu bytes)\n", path.c_str(), data.size());
        static const std::uint8_t no_byte = 0;  // libFuzzer never passes a null pointer
        LLVMFuzzerTestOneInput(data.empty() ? &no_byte : data.data(), data.size());
        bytes += data.size();
    }
    const double seconds =
        std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
    std::printf("replayed %zu inputs (%zu bytes) in %.2f s\n", inputs.size(), bytes, seconds);
    return 0;
}
