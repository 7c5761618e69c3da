#pragma once

#include <embree3/rtcore.h>

#include <cstdint>
#include <memory>
#include <string>

namespace rebraid::glue {

/// Owns one RTCDevice (move-only). Embree reports errors through a C callback, and an
/// exception must never unwind through Embree's C frames, so the callback only RECORDS the
/// error here; the glue calls throw_if_error() after each rtc* call that can fail, turning the
/// record into a rebraid::Error on the glue's side of the boundary.
///
/// The device also keeps a running count of the bytes Embree allocates through it (Embree's
/// memory monitor callback), which the reference structures report as their memory use.
class EmbreeDevice {
public:
    /// Creates a device from Embree's config string ("threads=2", "verbose=1", ...; empty =
    /// Embree's defaults). Throws rebraid::Error when Embree refuses the config or the CPU.
    explicit EmbreeDevice(const std::string& config = "");
    ~EmbreeDevice();

    EmbreeDevice(EmbreeDevice&& other) noexcept;
    EmbreeDevice& operator=(EmbreeDevice&& other) noexcept;
    EmbreeDevice(const EmbreeDevice&) = delete;
    EmbreeDevice& operator=(const EmbreeDevice&) = delete;

    /// The raw handle for rtc* calls; null only in a moved-from device.
    RTCDevice get() const { return device_; }

    /// When Embree reported an error since the last check, clears it and throws
    /// rebraid::Error("<call>: Embree error <name>: <message>"). `call` names the rtc* call
    /// (and, if useful, its object) the caller just made. Does nothing otherwise.
    void throw_if_error(const char* call);

    /// Bytes Embree currently holds through this device (BVHs and the buffers it allocated),
    /// counted since construction. 0 for a moved-from device.
    std::int64_t allocated_bytes() const;

private:
    /// Error record and byte counter. Heap-allocated because its address is the user pointer
    /// Embree hands to the callbacks: it must not change when the device is moved.
    struct Monitor;

    static void on_error(void* user, RTCError code, const char* message) noexcept;
    static bool on_memory(void* user, ssize_t bytes, bool post) noexcept;
    void release() noexcept;

    std::unique_ptr<Monitor> monitor_;
    RTCDevice device_ = nullptr;
};

/// Embree's name for an error code, e.g. "RTC_ERROR_INVALID_ARGUMENT".
const char* embree_error_name(RTCError code);

}  // namespace rebraid::glue
