#pragma once
// Determinism checks across thread counts: run the same build in arenas of different sizes
// and compare the structure hashes of what it made.

#include <gtest/gtest.h>
#include <tbb/global_control.h>
#include <tbb/task_arena.h>

#include <algorithm>
#include <cstddef>
#include <cstdint>
#include <initializer_list>

namespace rebraid::test {

/// The hash `hash_of_build()` returns when run inside an arena of `thread_count` threads
/// (its parallel loops then use at most that many).
template <class HashOfBuild>
std::uint64_t hash_on_threads(int thread_count, const HashOfBuild& hash_of_build) {
    std::uint64_t hash = 0;
    tbb::task_arena arena(thread_count);
    arena.execute([&] { hash = hash_of_build(); });
    return hash;
}

/// Expects `hash_of_build()` to give the same hash on every thread count of `thread_counts`
/// as on the first. Allows arenas as large as the largest count even on a machine with fewer
/// cores, so an 8-thread arena really runs 8 threads.
template <class HashOfBuild>
void expect_same_hash_on_threads(std::initializer_list<int> thread_counts,
                                 const HashOfBuild& hash_of_build) {
    int most_threads = 1;
    for (const int threads : thread_counts) most_threads = std::max(most_threads, threads);
    const tbb::global_control allow_all(tbb::global_control::max_allowed_parallelism,
                                        std::size_t(most_threads));
    const int first_threads = *thread_counts.begin();
    const std::uint64_t first = hash_on_threads(first_threads, hash_of_build);
    for (auto threads = thread_counts.begin() + 1; threads != thread_counts.end(); ++threads)
        EXPECT_EQ(first, hash_on_threads(*threads, hash_of_build))
            << *threads << " threads against " << first_threads;
}

}  // namespace rebraid::test
