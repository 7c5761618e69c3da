// Deliberately racy code that ThreadSanitizer must report with tests/tsan.supp active
// (docs/testing.md, "ThreadSanitizer and TBB"). Each case is one run of this program,
// `tsan_canary CASE`, checked by tests/tsan/expect_report.cmake: the run must end with
// ThreadSanitizer's exit code and a data-race report whose stacks name the case's function.
// A suppression that hid one of these races would hide the same race in the project's code.
//
// The cases are the shapes the suppressions are closest to:
//   parallel_for_body  two TBB threads write one int in a tbb::parallel_for body (TBB's
//                      dispatcher frames below the project's frame on both stacks);
//   task_group_task    a tbb::task_group task and the thread that runs the group write one int
//                      before the group's wait (a task of the group's context on the stack);
//   context_reuse      a thread reads a tbb::task_group_context's state
//                      (is_group_execution_cancelled, TBB's inline members compiled into the
//                      project and TBB's task_group_context_impl) while the owner destroys the
//                      context and reuses its bytes;
//   context_cancel     the same with cancel_group_execution, which writes the context;
//   callback_destroy   a callback called from a TBB task adds to a counter with a relaxed
//                      atomic, as Embree's memory monitor does, while the owner deletes the
//                      counter without waiting for the task.
// Two threads meet before their racing accesses through relaxed atomics only, which
// ThreadSanitizer does not count as synchronisation: the accesses are unordered, and both
// threads take part, so the report does not depend on the timing.
//
// In a build without ThreadSanitizer the program runs nothing; tests/CMakeLists.txt only
// builds and registers it when the flags contain -fsanitize=thread (the `tsan` preset).

#include <cstdio>
#include <cstring>

#if defined(__SANITIZE_THREAD__)
#define REBRAID_TSAN_CANARY 1
#elif defined(__has_feature)
#if __has_feature(thread_sanitizer)
#define REBRAID_TSAN_CANARY 1
#endif
#endif

#ifdef REBRAID_TSAN_CANARY

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>
#include <tbb/task_arena.h>
#include <tbb/task_group.h>

#include <atomic>
#include <chrono>
#include <cstdint>
#include <new>
#include <thread>

namespace {

// Waits until `count` threads have arrived, for at most ten seconds (a missing second thread
// then shows as a missing report, which fails the test). Relaxed atomics: no happens-before.
void meet(std::atomic<int>& arrived, int count) {
    arrived.fetch_add(1, std::memory_order_relaxed);
    const auto give_up = std::chrono::steady_clock::now() + std::chrono::seconds(10);
    while (arrived.load(std::memory_order_relaxed) < count &&
           std::chrono::steady_clock::now() < give_up) {
        std::this_thread::yield();
    }
}

int shared_value = 0;  // written by both sides of the first two races

void race_in_parallel_for_body() {
    tbb::task_arena arena(2);
    std::atomic<int> arrived{0};
    arena.execute([&] {
        tbb::parallel_for(
            tbb::blocked_range<int>(0, 2, 1),
            [&](const tbb::blocked_range<int>& range) {
                meet(arrived, 2);
                shared_value += range.begin() + 1;  // the race
            },
            tbb::simple_partitioner());
    });
}

void race_in_task_group_task() {
    tbb::task_arena arena(2);
    std::atomic<int> arrived{0};
    arena.execute([&] {
        tbb::task_group group;
        group.run([&] {
            meet(arrived, 2);
            shared_value = 1;  // the race
        });
        meet(arrived, 2);  // not a wait: a worker runs the task
        shared_value = 2;  // the race
        group.wait();
    });
}

// A task_group_context in storage the project reuses after destroying the context.
struct ContextStorage {
    alignas(tbb::task_group_context) unsigned char bytes[sizeof(tbb::task_group_context)];
};
ContextStorage context_storage;

template <class UseContext>
void race_on_reused_context(UseContext use_context) {
    auto* context = new (context_storage.bytes) tbb::task_group_context;
    std::atomic<int> arrived{0};
    std::thread user([&] {
        use_context(*context);
        meet(arrived, 2);
    });
    meet(arrived, 2);  // not a join: the user thread's accesses stay unordered
    context->~task_group_context();
    // Reuse of the bytes, as a later object in the same storage or stack frame would.
    auto* words = reinterpret_cast<volatile std::uint64_t*>(context_storage.bytes);
    for (std::size_t i = 0; i < sizeof(context_storage.bytes) / sizeof(std::uint64_t); ++i)
        words[i] = i;  // the race
    user.join();
}

void race_on_context_reuse() {
    race_on_reused_context(
        [](tbb::task_group_context& context) { (void)context.is_group_execution_cancelled(); });
}

void race_on_context_cancel() {
    race_on_reused_context(
        [](tbb::task_group_context& context) { (void)context.cancel_group_execution(); });
}

// Shaped like EmbreeDevice's memory monitor: a C callback with a user pointer.
struct Counter {
    std::atomic<std::int64_t> bytes{0};
};

bool on_counted_event(void* user, std::int64_t bytes) noexcept {
    static_cast<Counter*>(user)->bytes.fetch_add(bytes, std::memory_order_relaxed);
    return true;
}

void race_callback_with_destructor() {
    tbb::task_arena arena(2);
    std::atomic<int> arrived{0};
    arena.execute([&] {
        auto* counter = new Counter;
        tbb::task_group group;
        group.run([&arrived, counter] {
            on_counted_event(counter, 64);
            meet(arrived, 2);
        });
        meet(arrived, 2);  // not a wait: the callback is unordered with the delete
        delete counter;    // the race
        group.wait();
    });
}

struct Case {
    const char* name;
    void (*run)();
};

constexpr Case kCases[] = {
    {"parallel_for_body", race_in_parallel_for_body},
    {"task_group_task", race_in_task_group_task},
    {"context_reuse", race_on_context_reuse},
    {"context_cancel", race_on_context_cancel},
    {"callback_destroy", race_callback_with_destructor},
};

}  // namespace

int main(int argc, char** argv) {
    if (argc == 2) {
        for (const Case& c : kCases) {
            if (std::strcmp(argv[1], c.name) == 0) {
                c.run();
                // Only reached when ThreadSanitizer reported nothing (halt_on_error=1).
                std::printf("tsan_canary: %s ran without a report (value %d)\n", c.name,
                            shared_value);
                return 0;
            }
        }
    }
    std::fprintf(stderr, "usage: tsan_canary CASE, CASE one of:");
    for (const Case& c : kCases) std::fprintf(stderr, " %s", c.name);
    std::fprintf(stderr, "\n");
    return 2;
}

#else

int main() {
    std::printf("tsan_canary: not built with ThreadSanitizer; nothing to run\n");
    return 0;
}

#endif
