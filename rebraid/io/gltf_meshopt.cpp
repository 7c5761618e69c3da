#include "rebraid/io/gltf_meshopt.h"

#include <meshoptimizer.h>
#include <tiny_gltf.h>

#include <cstdint>
#include <limits>

#include "rebraid/core/error.h"
#include "rebraid/io/gltf_accessor.h"

namespace rebraid {
namespace {

constexpr std::uint64_t kMaxExpansion = 128;
constexpr std::uint64_t kExpansionAllowance = 64 * 1024;

class MeshoptViewDecoder {
public:
    MeshoptViewDecoder(tinygltf::Model& model, std::size_t view_id, const std::string& error_prefix)
        : model_(model),
          view_id_(view_id),
          error_prefix_(error_prefix),
          label_("bufferView " + std::to_string(view_id) + " " + kGltfMeshoptCompression) {}

    void decode() {
        const tinygltf::Value& extension =
            model_.bufferViews[view_id_].extensions.at(kGltfMeshoptCompression);
        if (!extension.IsObject()) fail("is not an object");
        const std::uint64_t buffer = whole_number(extension, "buffer", true);
        const std::uint64_t offset = whole_number(extension, "byteOffset", false);
        const std::uint64_t length = whole_number(extension, "byteLength", true);
        const std::uint64_t stride = whole_number(extension, "byteStride", true);
        const std::uint64_t count = whole_number(extension, "count", true);
        const std::string mode = text(extension, "mode", "");
        const std::string filter = text(extension, "filter", "NONE");
        if (buffer >= model_.buffers.size())
            fail("references buffer " + std::to_string(buffer) + ", file has " +
                 std::to_string(model_.buffers.size()) + " buffers");
        const std::vector<unsigned char>& source = model_.buffers[buffer].data;
        if (!gltf_elements_fit(offset, 1, 1, length, source.size()))
            fail("(byteOffset " + std::to_string(offset) + ", byteLength " +
                 std::to_string(length) + ") runs past the end of buffer " +
                 std::to_string(buffer) + " (" + std::to_string(source.size()) + " bytes)");
        check_mode(mode, filter, stride, count);
        if (count > (kMaxExpansion * length + kExpansionAllowance) / stride)
            fail("claims " + std::to_string(count) + " elements of " + std::to_string(stride) +
                 " bytes from " + std::to_string(length) + " compressed bytes");

        std::vector<unsigned char> decoded(count * stride);
        const unsigned char* compressed = source.data() + offset;
        int status = 0;
        if (mode == "ATTRIBUTES")
            status = meshopt_decodeVertexBuffer(decoded.data(), count, stride, compressed, length);
        else if (mode == "TRIANGLES")
            status = meshopt_decodeIndexBuffer(decoded.data(), count, stride, compressed, length);
        else
            status = meshopt_decodeIndexSequence(decoded.data(), count, stride, compressed, length);
        if (status != 0)
            fail("the " + mode + " data is corrupt (meshoptimizer error " + std::to_string(status) +
                 ")");
        if (filter == "OCTAHEDRAL") meshopt_decodeFilterOct(decoded.data(), count, stride);
        if (filter == "QUATERNION") meshopt_decodeFilterQuat(decoded.data(), count, stride);
        if (filter == "EXPONENTIAL") meshopt_decodeFilterExp(decoded.data(), count, stride);

        tinygltf::Buffer decoded_buffer;
        decoded_buffer.data = std::move(decoded);
        model_.buffers.push_back(std::move(decoded_buffer));
        tinygltf::BufferView& view = model_.bufferViews[view_id_];
        view.buffer = int(model_.buffers.size() - 1);
        view.byteOffset = 0;
        view.byteLength = count * stride;
        view.extensions.erase(kGltfMeshoptCompression);
    }

private:
    [[noreturn]] void fail(const std::string& what) const {
        throw Error(error_prefix_ + label_ + " " + what);
    }

    std::uint64_t whole_number(const tinygltf::Value& object, const char* key,
                               bool is_required) const {
        if (!object.Has(key)) {
            if (is_required) fail("has no " + std::string(key));
            return 0;
        }
        const tinygltf::Value& value = object.Get(key);
        if (!value.IsNumber() || !(value.GetNumberAsDouble() >= 0) ||
            value.GetNumberAsDouble() > double(std::numeric_limits<std::uint32_t>::max()) ||
            value.GetNumberAsDouble() != double(std::uint64_t(value.GetNumberAsDouble())))
            fail(std::string(key) + " is not a whole number from 0 to 2^32-1");
        return std::uint64_t(value.GetNumberAsDouble());
    }

    std::string text(const tinygltf::Value& object, const char* key,
                     const std::string& fallback) const {
        if (!object.Has(key)) {
            if (fallback.empty()) fail("has no " + std::string(key));
            return fallback;
        }
        if (!object.Get(key).IsString()) fail(std::string(key) + " is not a string");
        return object.Get(key).Get<std::string>();
    }

    /// The glTF extension's rules for each mode and filter (strides the codecs support).
    void check_mode(const std::string& mode, const std::string& filter, std::uint64_t stride,
                    std::uint64_t count) const {
        if (stride == 0) fail("has byteStride 0");
        if (mode == "ATTRIBUTES") {
            if (stride % 4 != 0 || stride > 256)
                fail("mode ATTRIBUTES needs a byteStride that is a multiple of 4 up to 256, got " +
                     std::to_string(stride));
        } else if (mode == "TRIANGLES" || mode == "INDICES") {
            if (stride != 2 && stride != 4)
                fail("mode " + mode + " needs byteStride 2 or 4, got " + std::to_string(stride));
            if (mode == "TRIANGLES" && count % 3 != 0)
                fail("mode TRIANGLES needs a count that is a multiple of 3, got " +
                     std::to_string(count));
        } else {
            fail("has unknown mode '" + mode + "'");
        }
        if (filter == "NONE") return;
        if (mode != "ATTRIBUTES") fail("filter " + filter + " needs mode ATTRIBUTES");
        if (filter == "OCTAHEDRAL" && stride != 4 && stride != 8)
            fail("filter OCTAHEDRAL needs byteStride 4 or 8, got " + std::to_string(stride));
        else if (filter == "QUATERNION" && stride != 8)
            fail("filter QUATERNION needs byteStride 8, got " + std::to_string(stride));
        else if (filter != "OCTAHEDRAL" && filter != "QUATERNION" && filter != "EXPONENTIAL")
            fail("has unknown filter '" + filter + "'");
    }

    tinygltf::Model& model_;
    std::size_t view_id_;
    const std::string& error_prefix_;
    std::string label_;
};

}  // namespace

void decode_gltf_meshopt_views(tinygltf::Model& model, const std::string& error_prefix) {
    for (std::size_t v = 0; v < model.bufferViews.size(); ++v)
        if (model.bufferViews[v].extensions.count(kGltfMeshoptCompression) != 0)
            MeshoptViewDecoder(model, v, error_prefix).decode();
}

}  // namespace rebraid
