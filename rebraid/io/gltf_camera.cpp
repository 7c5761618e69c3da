#include "rebraid/io/gltf_camera.h"

#include <tiny_gltf.h>

#include <algorithm>
#include <array>
#include <cmath>

#include "rebraid/core/error.h"

namespace rebraid {
namespace {

using Vec3d = std::array<double, 3>;

/// A node transform in double precision: columns x, y, z of the linear part, then the
/// translation. Long node chains compose without float drift.
struct NodeTransform {
    std::array<Vec3d, 4> columns{{{1, 0, 0}, {0, 1, 0}, {0, 0, 1}, {0, 0, 0}}};

    Vec3d apply_linear(const Vec3d& v) const {
        Vec3d out{};
        for (int row = 0; row < 3; ++row)
            out[row] = columns[0][row] * v[0] + columns[1][row] * v[1] + columns[2][row] * v[2];
        return out;
    }
    /// The map "first `child`, then this".
    NodeTransform compose(const NodeTransform& child) const {
        NodeTransform out;
        for (int c = 0; c < 3; ++c) out.columns[c] = apply_linear(child.columns[c]);
        out.columns[3] = apply_linear(child.columns[3]);
        for (int row = 0; row < 3; ++row) out.columns[3][row] += columns[3][row];
        return out;
    }
};

/// The node's own transform: its `matrix`, else translation * rotation * scale. The loader
/// has already checked the array sizes of every node it visited.
NodeTransform local_transform(const tinygltf::Node& node) {
    NodeTransform local;
    if (node.matrix.size() == 16) {
        for (int c = 0; c < 4; ++c)
            for (int row = 0; row < 3; ++row) local.columns[c][row] = node.matrix[4 * c + row];
        return local;
    }
    double x = 0, y = 0, z = 0, w = 1;
    if (node.rotation.size() == 4) {
        const double norm =
            std::sqrt(node.rotation[0] * node.rotation[0] + node.rotation[1] * node.rotation[1] +
                      node.rotation[2] * node.rotation[2] + node.rotation[3] * node.rotation[3]);
        if (norm > 0) {
            x = node.rotation[0] / norm, y = node.rotation[1] / norm;
            z = node.rotation[2] / norm, w = node.rotation[3] / norm;
        }
    }
    // Columns of the rotation matrix of the unit quaternion (x, y, z, w).
    const std::array<Vec3d, 3> rotation{{
        {1 - 2 * (y * y + z * z), 2 * (x * y + z * w), 2 * (x * z - y * w)},
        {2 * (x * y - z * w), 1 - 2 * (x * x + z * z), 2 * (y * z + x * w)},
        {2 * (x * z + y * w), 2 * (y * z - x * w), 1 - 2 * (x * x + y * y)},
    }};
    const Vec3d scale = node.scale.size() == 3 ? Vec3d{node.scale[0], node.scale[1], node.scale[2]}
                                               : Vec3d{1, 1, 1};
    for (int c = 0; c < 3; ++c)
        for (int row = 0; row < 3; ++row) local.columns[c][row] = rotation[c][row] * scale[c];
    if (node.translation.size() == 3)
        local.columns[3] = {node.translation[0], node.translation[1], node.translation[2]};
    return local;
}

Vec3d normalized(const Vec3d& v) {
    const double norm = std::sqrt(v[0] * v[0] + v[1] * v[1] + v[2] * v[2]);
    if (!(norm > 0) || !std::isfinite(norm)) return {0, 0, 0};
    return {v[0] / norm, v[1] / norm, v[2] / norm};
}

Vec3d cross(const Vec3d& a, const Vec3d& b) {
    return {a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0]};
}

Vec3f to_float(const Vec3d& v) {
    return {static_cast<float>(v[0]), static_cast<float>(v[1]), static_cast<float>(v[2])};
}

class CameraReader {
public:
    explicit CameraReader(const tinygltf::Model& model) : model_(model) {}

    std::vector<GltfCamera> read(std::uint32_t scene_id) {
        if (scene_id < model_.scenes.size()) {
            visited_.assign(model_.nodes.size(), false);
            for (int root : model_.scenes[scene_id].nodes) visit(root, NodeTransform{});
        }
        std::ranges::sort(cameras_, {}, &GltfCamera::camera_id);
        return std::move(cameras_);
    }

private:
    std::string camera_label(int id) const {
        return "glTF camera " + std::to_string(id) + " ('" +
               model_.cameras[static_cast<std::size_t>(id)].name + "')";
    }

    // Depth-first with an explicit stack: node chains in real files can be thousands deep.
    void visit(int root, const NodeTransform& root_parent) {
        struct Pending {
            int node;
            NodeTransform parent_to_world;
        };
        std::vector<Pending> stack{{root, root_parent}};
        while (!stack.empty()) {
            const Pending top = stack.back();
            stack.pop_back();
            // The loader rejected cycles and shared children; skip them anyway.
            if (top.node < 0 || static_cast<std::size_t>(top.node) >= model_.nodes.size() ||
                visited_[static_cast<std::size_t>(top.node)])
                continue;
            visited_[static_cast<std::size_t>(top.node)] = true;
            const tinygltf::Node& node = model_.nodes[static_cast<std::size_t>(top.node)];
            const NodeTransform to_world = top.parent_to_world.compose(local_transform(node));
            if (node.camera >= 0) add_camera(node.camera, top.node, to_world);
            // Pushed in reverse so children are visited in listed order.
            for (auto child = node.children.rbegin(); child != node.children.rend(); ++child)
                stack.push_back({*child, to_world});
        }
    }

    void add_camera(int camera_id, int node_id, const NodeTransform& to_world) {
        if (static_cast<std::size_t>(camera_id) >= model_.cameras.size())
            throw Error("glTF cameras: node " + std::to_string(node_id) +
                        " references missing camera " + std::to_string(camera_id) + ", file has " +
                        std::to_string(model_.cameras.size()));
        for (const GltfCamera& known : cameras_)
            if (known.camera_id == static_cast<std::uint32_t>(camera_id)) return;

        const tinygltf::Camera& source = model_.cameras[static_cast<std::size_t>(camera_id)];
        GltfCamera camera;
        camera.camera_id = static_cast<std::uint32_t>(camera_id);
        camera.node_id = static_cast<std::uint32_t>(node_id);
        camera.name = source.name.empty() ? model_.nodes[static_cast<std::size_t>(node_id)].name
                                          : source.name;

        // Orthonormal frame from the node's -Z and +Y, with scale and shear removed.
        const Vec3d forward = normalized(to_world.apply_linear({0, 0, -1}));
        const Vec3d right = normalized(cross(forward, to_world.apply_linear({0, 1, 0})));
        if (forward == Vec3d{0, 0, 0} || right == Vec3d{0, 0, 0})
            throw Error(camera_label(camera_id) + ": node " + std::to_string(node_id) +
                        " transform leaves no view direction");
        camera.position = to_float(to_world.columns[3]);
        camera.forward = to_float(forward);
        camera.up = to_float(cross(right, forward));

        if (source.type == "perspective") {
            camera.yfov_radians = static_cast<float>(source.perspective.yfov);
            if (!(camera.yfov_radians > 0.0f && camera.yfov_radians < 3.14159f))
                throw Error(camera_label(camera_id) + ": yfov " +
                            std::to_string(source.perspective.yfov) + " is outside (0, pi)");
            camera.aspect_ratio = static_cast<float>(std::max(0.0, source.perspective.aspectRatio));
            camera.znear = static_cast<float>(source.perspective.znear);
            camera.zfar = static_cast<float>(source.perspective.zfar);
        } else if (source.type == "orthographic") {
            camera.is_orthographic = true;
            camera.xmag = static_cast<float>(std::fabs(source.orthographic.xmag));
            camera.ymag = static_cast<float>(std::fabs(source.orthographic.ymag));
            if (!(camera.xmag > 0.0f && camera.ymag > 0.0f))
                throw Error(camera_label(camera_id) + ": orthographic xmag/ymag " +
                            std::to_string(source.orthographic.xmag) + "/" +
                            std::to_string(source.orthographic.ymag) + " must not be 0");
            camera.znear = static_cast<float>(source.orthographic.znear);
            camera.zfar = static_cast<float>(source.orthographic.zfar);
        } else {
            throw Error(camera_label(camera_id) + ": unknown type '" + source.type + "'");
        }
        cameras_.push_back(std::move(camera));
    }

    const tinygltf::Model& model_;
    std::vector<bool> visited_;
    std::vector<GltfCamera> cameras_;
};

}  // namespace

std::vector<GltfCamera> read_gltf_cameras(const GltfLoadResult& loaded) {
    if (!loaded.model)
        throw Error("read_gltf_cameras: the glTF model was not kept (load with keep_model)");
    return CameraReader(*loaded.model).read(loaded.report.scene_id);
}

}  // namespace rebraid
