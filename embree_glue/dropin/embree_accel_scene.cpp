#include "embree_glue/dropin/embree_accel_scene.h"

#include <cmath>
#include <cstdint>
#include <cstdio>
#include <cstring>
#include <map>
#include <string>

#include "rebraid/core/error.h"

namespace rebraid::glue {
namespace {

/// Embree's FLT_LARGE: vertices beyond it make Embree skip the triangle.
constexpr float kEmbreeLargestVertexCoordinate = 1.844e18f;

std::string handle_text(const void* handle) {
    char text[32];
    std::snprintf(text, sizeof(text), "%p", handle);
    return text;
}

std::string scene_text(RTCScene scene) {
    return "scene " + handle_text(scene);
}

std::string geometry_text(RTCScene scene, unsigned int geom_id,
                          const RegisteredGeometry& geometry) {
    return "geometry " + std::to_string(geom_id) + " (" + embree_geometry_type_name(geometry.type) +
           ") of " + scene_text(scene);
}

const char* format_name(RTCFormat format) {
    switch (format) {
        case RTC_FORMAT_FLOAT3:
            return "RTC_FORMAT_FLOAT3";
        case RTC_FORMAT_UINT3:
            return "RTC_FORMAT_UINT3";
        default:
            return "another format";
    }
}

/// The buffer bound to (type, slot 0), checked against the one format Embree's triangle
/// meshes accept there.
const RegisteredBufferView& triangle_buffer(const RegisteredGeometry& geometry, RTCBufferType type,
                                            RTCFormat format, const std::string& where,
                                            const char* what) {
    const RegisteredBufferView* found = geometry.buffers.find(BufferSlot{type, 0});
    if (found == nullptr || found->data == nullptr)
        throw Error("EmbreeAccel: " + where + " has no " + what + " buffer in slot 0" +
                    (geometry.buffers.has_overflowed()
                         ? " the drop-in recorded (more than " +
                               std::to_string(RegisteredBuffers::kCapacity) + " buffers bound)"
                         : std::string()));
    const RegisteredBufferView& view = *found;
    if (view.format != format)
        throw Error("EmbreeAccel: " + where + ": " + what + " buffer has format " +
                    std::to_string(int(view.format)) + " (" + format_name(view.format) +
                    "), expected " + format_name(format));
    if (view.byte_stride < 12)
        throw Error("EmbreeAccel: " + where + ": " + what + " buffer stride " +
                    std::to_string(view.byte_stride) + " is smaller than one item (12 bytes)");
    return view;
}

bool is_valid_vertex(const Vec3f& p) {
    for (int axis = 0; axis < 3; ++axis)
        if (!(std::fabs(p[axis]) <= kEmbreeLargestVertexCoordinate)) return false;
    return true;
}

/// Copies a triangle geometry's buffers into a Mesh; see convert_embree_scene for what
/// happens to triangles Embree ignores.
Mesh read_triangle_mesh(const RegisteredGeometry& geometry, const std::string& where) {
    const RegisteredBufferView& vertices =
        triangle_buffer(geometry, RTC_BUFFER_TYPE_VERTEX, RTC_FORMAT_FLOAT3, where, "vertex");
    const RegisteredBufferView& indices =
        triangle_buffer(geometry, RTC_BUFFER_TYPE_INDEX, RTC_FORMAT_UINT3, where, "index");
    Mesh mesh;
    mesh.name = where;
    mesh.positions.resize(vertices.item_count);
    std::vector<char> is_valid(vertices.item_count);
    for (std::size_t i = 0; i < vertices.item_count; ++i) {
        Vec3f p;
        std::memcpy(&p, vertices.data + i * vertices.byte_stride, sizeof(Vec3f));
        is_valid[i] = is_valid_vertex(p);
        // The position of a vertex Embree ignores is never used (its triangles are made
        // degenerate below); zero keeps the scene valid.
        mesh.positions[i] = is_valid[i] ? p : Vec3f{};
    }
    mesh.triangles.resize(indices.item_count);
    for (std::size_t i = 0; i < indices.item_count; ++i) {
        Triangle triangle;
        std::memcpy(triangle.data(), indices.data + i * indices.byte_stride, sizeof(Triangle));
        bool is_valid_triangle = true;
        for (std::uint32_t index : triangle)
            is_valid_triangle = is_valid_triangle && index < vertices.item_count && is_valid[index];
        if (!is_valid_triangle) {
            // A point triangle is never hit, just as Embree never hits the triangle it skips.
            if (mesh.positions.empty()) mesh.positions.push_back({});
            triangle = {0, 0, 0};
        }
        mesh.triangles[i] = triangle;
    }
    return mesh;
}

AffineTransform to_affine(const std::array<float, 12>& m) {
    return {{m[0], m[1], m[2]}, {m[3], m[4], m[5]}, {m[6], m[7], m[8]}, {m[9], m[10], m[11]}};
}

/// Builds the converted scene; one object per conversion.
class SceneConverter {
public:
    SceneConverter(const RegisteredSceneSnapshot& snapshot, bool is_ray_mask_supported)
        : snapshot_(snapshot), is_ray_mask_supported_(is_ray_mask_supported) {}

    ConvertedEmbreeScene convert() {
        const RegisteredScene& root = scene_record(snapshot_.root, scene_text(snapshot_.root));
        if (root.commit_count == 0)
            throw Error("EmbreeAccel: " + scene_text(snapshot_.root) +
                        " was never committed; call rtcCommitScene before building");
        if (root.has_uncommitted_changes)
            throw Error("EmbreeAccel: " + scene_text(snapshot_.root) +
                        " has geometries attached or detached since its last rtcCommitScene");
        result_.is_robust = asks_for_robust_mode(snapshot_.root);
        for (const auto& [geom_id, handle] : root.geometries) {
            const RegisteredGeometry& geometry = geometry_record(handle);
            const std::string where = geometry_text(snapshot_.root, geom_id, geometry);
            if (!geometry.is_enabled) continue;
            check_common(geometry, where);
            if (geometry.type == RTC_GEOMETRY_TYPE_TRIANGLE) {
                add_instance(handle, geometry, where, AffineTransform::identity(),
                             {geom_id, RTC_INVALID_GEOMETRY_ID}, nullptr, snapshot_.root);
            } else if (geometry.type == RTC_GEOMETRY_TYPE_INSTANCE) {
                add_instance_geometry(handle, geometry, geom_id, where);
            } else {
                throw unsupported(where);
            }
        }
        return std::move(result_);
    }

private:
    static Error unsupported(const std::string& where) {
        return Error("EmbreeAccel: " + where +
                     " is not supported: only triangle meshes and instances of scenes of "
                     "triangle meshes are");
    }

    const RegisteredScene& scene_record(RTCScene scene, const std::string& where) const {
        const auto found = snapshot_.scenes.find(scene);
        if (found == snapshot_.scenes.end())
            throw Error("EmbreeAccel: " + where +
                        " is unknown to the drop-in's registry (created before the interposer "
                        "saw it, or released)");
        return found->second;
    }

    const RegisteredGeometry& geometry_record(RTCGeometry geometry) const {
        const auto found = snapshot_.geometries.find(geometry);
        if (found == snapshot_.geometries.end())
            throw Error("EmbreeAccel: geometry " + handle_text(geometry) +
                        " is unknown to the drop-in's registry");
        return found->second;
    }

    void check_common(const RegisteredGeometry& geometry, const std::string& where) const {
        if (geometry.time_step_count != 1)
            throw Error("EmbreeAccel: " + where + " has " +
                        std::to_string(geometry.time_step_count) +
                        " time steps; motion blur is not supported");
        if (geometry.has_filter_function)
            throw Error("EmbreeAccel: " + where +
                        " has a filter function; filter functions are not supported");
        if (is_ray_mask_supported_ && geometry.mask != 0xffffffffu)
            throw Error("EmbreeAccel: " + where + " has mask " + std::to_string(geometry.mask) +
                        "; only the default mask (all bits set) is supported");
    }

    void add_instance_geometry(RTCGeometry handle, const RegisteredGeometry& instance,
                               unsigned int inst_id, const std::string& where) {
        if (instance.instanced_scene == nullptr)
            throw Error("EmbreeAccel: " + where + " has no instanced scene");
        const std::string scene_where = "the scene instanced by " + where;
        const RegisteredScene& scene = scene_record(instance.instanced_scene, scene_where);
        if (scene.commit_count == 0)
            throw Error("EmbreeAccel: " + scene_where + " (" +
                        scene_text(instance.instanced_scene) + ") was never committed");
        const AffineTransform object_to_world = to_affine(instance.transform);
        const float det = object_to_world.determinant();
        if (!object_to_world.is_finite() || !std::isfinite(det) || std::fabs(det) < 1e-30f)
            throw Error("EmbreeAccel: " + where +
                        " has a singular or non-finite transform (determinant " +
                        std::to_string(det) + ")");
        for (const auto& [geom_id, inner_handle] : scene.geometries) {
            const RegisteredGeometry& geometry = geometry_record(inner_handle);
            const std::string inner_where =
                geometry_text(instance.instanced_scene, geom_id, geometry) + ", instanced by " +
                where;
            if (!geometry.is_enabled) continue;
            check_common(geometry, inner_where);
            if (geometry.type == RTC_GEOMETRY_TYPE_INSTANCE)
                throw Error("EmbreeAccel: " + inner_where +
                            " is an instance inside an instanced scene; only one level of "
                            "instancing is supported");
            if (geometry.type != RTC_GEOMETRY_TYPE_TRIANGLE) throw unsupported(inner_where);
            add_instance(inner_handle, geometry, inner_where, object_to_world, {geom_id, inst_id},
                         handle, instance.instanced_scene);
        }
    }

    void add_instance(RTCGeometry mesh_handle, const RegisteredGeometry& geometry,
                      const std::string& where, const AffineTransform& object_to_world,
                      EmbreeHitIds ids, RTCGeometry instance_handle, RTCScene triangle_scene) {
        auto [found, is_new] =
            mesh_ids_.try_emplace(mesh_handle, MeshId(result_.scene.meshes.size()));
        if (is_new) {
            result_.scene.meshes.push_back(read_triangle_mesh(geometry, where));
            result_.mesh_geometries.push_back(mesh_handle);
        }
        result_.scene.instances.push_back({found->second, object_to_world});
        result_.instance_ids.push_back(ids);
        result_.instance_geometries.push_back(instance_handle);
        result_.triangle_scenes.push_back(triangle_scene);
        result_.is_robust = result_.is_robust || asks_for_robust_mode(triangle_scene);
    }

    static bool asks_for_robust_mode(RTCScene scene) {
        return (rtcGetSceneFlags(scene) & RTC_SCENE_FLAG_ROBUST) != 0;
    }

    const RegisteredSceneSnapshot& snapshot_;
    bool is_ray_mask_supported_;
    std::map<RTCGeometry, MeshId> mesh_ids_;
    ConvertedEmbreeScene result_;
};

}  // namespace

ConvertedEmbreeScene convert_embree_scene(const RegisteredSceneSnapshot& snapshot,
                                          bool is_ray_mask_supported) {
    return SceneConverter(snapshot, is_ray_mask_supported).convert();
}

const char* embree_geometry_type_name(RTCGeometryType type) {
    switch (type) {
        case RTC_GEOMETRY_TYPE_TRIANGLE:
            return "RTC_GEOMETRY_TYPE_TRIANGLE";
        case RTC_GEOMETRY_TYPE_QUAD:
            return "RTC_GEOMETRY_TYPE_QUAD";
        case RTC_GEOMETRY_TYPE_GRID:
            return "RTC_GEOMETRY_TYPE_GRID";
        case RTC_GEOMETRY_TYPE_SUBDIVISION:
            return "RTC_GEOMETRY_TYPE_SUBDIVISION";
        case RTC_GEOMETRY_TYPE_USER:
            return "RTC_GEOMETRY_TYPE_USER";
        case RTC_GEOMETRY_TYPE_INSTANCE:
            return "RTC_GEOMETRY_TYPE_INSTANCE";
        case RTC_GEOMETRY_TYPE_SPHERE_POINT:
        case RTC_GEOMETRY_TYPE_DISC_POINT:
        case RTC_GEOMETRY_TYPE_ORIENTED_DISC_POINT:
            return "point geometry";
        default:
            return "curve geometry";
    }
}

}  // namespace rebraid::glue
