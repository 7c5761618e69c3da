#include "embree_glue/reference/embree_device.h"

#include <atomic>
#include <cstddef>
#include <mutex>
#include <utility>

#include "rebraid/core/error.h"

namespace rebraid::glue {

struct EmbreeDevice::Monitor {
    std::mutex mutex;  // Embree may report errors from any thread that calls into it
    RTCError first_code = RTC_ERROR_NONE;
    std::string first_message;
    std::size_t later_error_count = 0;  ///< errors reported after the first, before a check
    // A sum does not depend on the order in which Embree's build threads report, so an atomic
    // add keeps the count deterministic. The adds release and release() acquires: see there.
    std::atomic<std::int64_t> allocated_bytes{0};
};

const char* embree_error_name(RTCError code) {
    switch (code) {
        case RTC_ERROR_NONE:
            return "RTC_ERROR_NONE";
        case RTC_ERROR_UNKNOWN:
            return "RTC_ERROR_UNKNOWN";
        case RTC_ERROR_INVALID_ARGUMENT:
            return "RTC_ERROR_INVALID_ARGUMENT";
        case RTC_ERROR_INVALID_OPERATION:
            return "RTC_ERROR_INVALID_OPERATION";
        case RTC_ERROR_OUT_OF_MEMORY:
            return "RTC_ERROR_OUT_OF_MEMORY";
        case RTC_ERROR_UNSUPPORTED_CPU:
            return "RTC_ERROR_UNSUPPORTED_CPU";
        case RTC_ERROR_CANCELLED:
            return "RTC_ERROR_CANCELLED";
    }
    return "RTC_ERROR_(unrecognized code)";
}

EmbreeDevice::EmbreeDevice(const std::string& config) : monitor_(std::make_unique<Monitor>()) {
    device_ = rtcNewDevice(config.c_str());
    if (device_ == nullptr) {
        // No device means no callback and no message: only the thread's error code is left.
        throw Error(std::string("rtcNewDevice: Embree error ") +
                    embree_error_name(rtcGetDeviceError(nullptr)) +
                    ": cannot create a device with config \"" + config + "\"");
    }
    rtcSetDeviceErrorFunction(device_, &EmbreeDevice::on_error, monitor_.get());
    rtcSetDeviceMemoryMonitorFunction(device_, &EmbreeDevice::on_memory, monitor_.get());
}

EmbreeDevice::~EmbreeDevice() {
    release();
}

EmbreeDevice::EmbreeDevice(EmbreeDevice&& other) noexcept
    : monitor_(std::move(other.monitor_)), device_(std::exchange(other.device_, nullptr)) {}

EmbreeDevice& EmbreeDevice::operator=(EmbreeDevice&& other) noexcept {
    if (this != &other) {
        release();
        monitor_ = std::move(other.monitor_);
        device_ = std::exchange(other.device_, nullptr);
    }
    return *this;
}

void EmbreeDevice::release() noexcept {
    if (device_ == nullptr) return;
    // Scenes hold their own reference to the device, so it can outlive this wrapper: unhook
    // the callbacks first, or Embree would call them with a dangling Monitor pointer.
    rtcSetDeviceErrorFunction(device_, nullptr, nullptr);
    rtcSetDeviceMemoryMonitorFunction(device_, nullptr, nullptr);
    rtcReleaseDevice(device_);
    device_ = nullptr;
    // Embree calls on_memory from its build threads and joins them before the build call
    // returns, so every call has happened before this point; but the join is in Embree's code,
    // which ThreadSanitizer does not see. Reading the counter with acquire after the callbacks'
    // release adds orders them before the Monitor's deletion in the project's own code. A
    // callback that Embree made after this point would still race with the deletion, and
    // ThreadSanitizer reports it (tests/tsan/tsan_canary.cpp, case callback_destroy).
    (void)monitor_->allocated_bytes.load(std::memory_order_acquire);
}

void EmbreeDevice::on_error(void* user, RTCError code, const char* message) noexcept {
    auto* monitor = static_cast<Monitor*>(user);
    try {
        std::lock_guard lock(monitor->mutex);
        // Keep the first error: later ones are usually consequences of it.
        if (monitor->first_code == RTC_ERROR_NONE) {
            monitor->first_code = code;
            monitor->first_message = message != nullptr ? message : "(no message)";
        } else {
            ++monitor->later_error_count;
        }
    } catch (...) {
        // Nothing may escape into Embree; losing an error message under memory exhaustion is
        // the lesser evil.
    }
}

bool EmbreeDevice::on_memory(void* user, ssize_t bytes, bool /*post*/) noexcept {
    // Embree passes positive byte counts before allocations and negative ones after frees.
    // Release: the add happens before the Monitor's deletion (release()).
    static_cast<Monitor*>(user)->allocated_bytes.fetch_add(bytes, std::memory_order_release);
    return true;  // never veto an allocation
}

void EmbreeDevice::throw_if_error(const char* call) {
    if (!monitor_) return;
    RTCError code = RTC_ERROR_NONE;
    std::string message;
    std::size_t later_error_count = 0;
    {
        std::lock_guard lock(monitor_->mutex);
        code = std::exchange(monitor_->first_code, RTC_ERROR_NONE);
        message = std::exchange(monitor_->first_message, std::string());
        later_error_count = std::exchange(monitor_->later_error_count, 0);
    }
    if (code == RTC_ERROR_NONE) return;
    std::string text =
        std::string(call) + ": Embree error " + embree_error_name(code) + ": " + message;
    if (later_error_count > 0)
        text += " (and " + std::to_string(later_error_count) + " later error(s))";
    throw Error(text);
}

std::int64_t EmbreeDevice::allocated_bytes() const {
    return monitor_ ? monitor_->allocated_bytes.load(std::memory_order_relaxed) : 0;
}

}  // namespace rebraid::glue
