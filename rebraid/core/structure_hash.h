#pragma once

#include <cstddef>
#include <cstdint>
#include <span>
#include <type_traits>

namespace rebraid {

/// 64-bit FNV-1a over the bytes of a structure's arrays: equal hashes mean (with
/// overwhelming probability) bit-identical trees. Used to prove builds deterministic.
class StructureHash {
public:
    void add_bytes(const void* data, std::size_t size) {
        const auto* bytes = static_cast<const unsigned char*>(data);
        for (std::size_t i = 0; i < size; ++i) {
            value_ ^= bytes[i];
            value_ *= 0x100000001b3ull;
        }
    }
    template <class T>
    void add(std::span<const T> items) {
        static_assert(std::is_trivially_copyable_v<T>);
        const std::uint64_t count = items.size();
        add_bytes(&count, sizeof count);  // so [a][bc] and [ab][c] differ
        add_bytes(items.data(), items.size_bytes());
    }
    template <class T>
    void add_value(const T& value) {
        add(std::span<const T>(&value, 1));
    }
    std::uint64_t value() const { return value_; }

private:
    std::uint64_t value_ = 0xcbf29ce484222325ull;
};

}  // namespace rebraid
