#include "rebraid/render/interrupt.h"

#include <csignal>

#include "rebraid/core/error.h"

namespace rebraid::viewer {

namespace {

// A signal handler may only touch lock-free atomics.
std::atomic<bool> g_interrupted{false};
static_assert(std::atomic<bool>::is_always_lock_free);

bool g_is_guard_alive = false;
struct sigaction g_previous_action {};

extern "C" void on_interrupt(int /*signal*/) {
    g_interrupted.store(true, std::memory_order_relaxed);
}

}  // namespace

InterruptGuard::InterruptGuard() {
    if (g_is_guard_alive) throw Error("InterruptGuard: another guard is already installed");
    g_is_guard_alive = true;
    g_interrupted.store(false, std::memory_order_relaxed);
    struct sigaction action {};
    action.sa_handler = &on_interrupt;
    sigemptyset(&action.sa_mask);
    // One-shot: the handler resets to the default, so a second Ctrl-C ends the process.
    action.sa_flags = SA_RESETHAND;
    sigaction(SIGINT, &action, &g_previous_action);
}

InterruptGuard::~InterruptGuard() {
    sigaction(SIGINT, &g_previous_action, nullptr);
    g_is_guard_alive = false;
}

const std::atomic<bool>& InterruptGuard::flag() const {
    return g_interrupted;
}

}  // namespace rebraid::viewer
