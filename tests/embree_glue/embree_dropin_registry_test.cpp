// The drop-in's interposer: every path by which an application hands Embree its buffers,
// instances and attachments reaches the registry, and released objects drop out of it. This
// executable links rebraid::embree_dropin, so its Embree calls go through the interposer, as
// an application's do.

#include <gtest/gtest.h>

#include <array>
#include <cstddef>
#include <optional>
#include <vector>

#include "support/embree_dropin_app.h"

namespace rebraid {
namespace {

using namespace rebraid::test;

TEST(EmbreeRegistry, InterposerIsActive) {
    Device app;
    const RTCScene scene = rtcNewScene(app.device);
    EXPECT_TRUE(glue::is_interposer_active());
    EXPECT_TRUE(glue::find_registered_scene(scene).has_value());
    rtcReleaseScene(scene);
    EXPECT_FALSE(glue::find_registered_scene(scene).has_value());
}

TEST(EmbreeRegistry, RecordsNewGeometryBuffers) {
    Device app;
    const RTCGeometry geometry = rtcNewGeometry(app.device, RTC_GEOMETRY_TYPE_TRIANGLE);
    void* vertices =
        rtcSetNewGeometryBuffer(geometry, RTC_BUFFER_TYPE_VERTEX, 0, RTC_FORMAT_FLOAT3, 16, 7);
    void* indices =
        rtcSetNewGeometryBuffer(geometry, RTC_BUFFER_TYPE_INDEX, 0, RTC_FORMAT_UINT3, 12, 5);
    const auto record = glue::find_registered_geometry(geometry);
    ASSERT_TRUE(record.has_value());
    EXPECT_EQ(record->type, RTC_GEOMETRY_TYPE_TRIANGLE);
    const auto& vertex_view = record->buffers.at({RTC_BUFFER_TYPE_VERTEX, 0});
    EXPECT_EQ(vertex_view.source, glue::BufferSource::new_geometry_buffer);
    EXPECT_EQ(vertex_view.format, RTC_FORMAT_FLOAT3);
    EXPECT_EQ(vertex_view.data, static_cast<const std::byte*>(vertices));
    EXPECT_EQ(vertex_view.byte_stride, 16u);
    EXPECT_EQ(vertex_view.item_count, 7u);
    const auto& index_view = record->buffers.at({RTC_BUFFER_TYPE_INDEX, 0});
    EXPECT_EQ(index_view.format, RTC_FORMAT_UINT3);
    EXPECT_EQ(index_view.data, static_cast<const std::byte*>(indices));
    EXPECT_EQ(index_view.item_count, 5u);
    rtcReleaseGeometry(geometry);
    EXPECT_FALSE(glue::find_registered_geometry(geometry).has_value());
}

TEST(EmbreeRegistry, RecordsSharedGeometryBufferWithOffsetAndStride) {
    Device app;
    std::vector<float> vertices(64, 0.0f);
    const RTCGeometry geometry = rtcNewGeometry(app.device, RTC_GEOMETRY_TYPE_TRIANGLE);
    rtcSetSharedGeometryBuffer(geometry, RTC_BUFFER_TYPE_VERTEX, 0, RTC_FORMAT_FLOAT3,
                               vertices.data(), 32, 20, 9);
    const auto record = glue::find_registered_geometry(geometry);
    ASSERT_TRUE(record.has_value());
    const auto& view = record->buffers.at({RTC_BUFFER_TYPE_VERTEX, 0});
    EXPECT_EQ(view.source, glue::BufferSource::shared_geometry_buffer);
    EXPECT_EQ(view.data, reinterpret_cast<const std::byte*>(vertices.data()) + 32);
    EXPECT_EQ(view.byte_offset, 32u);
    EXPECT_EQ(view.byte_stride, 20u);
    EXPECT_EQ(view.item_count, 9u);
    rtcReleaseGeometry(geometry);
}

TEST(EmbreeRegistry, RecordsNewBufferAndNewSharedBuffer) {
    Device app;
    const std::size_t before = glue::registry_counts().buffers;
    const RTCBuffer buffer = rtcNewBuffer(app.device, 256);
    std::vector<std::uint32_t> shared(30, 0u);
    const RTCBuffer shared_buffer = rtcNewSharedBuffer(app.device, shared.data(), 120);
    EXPECT_EQ(glue::registry_counts().buffers, before + 2);
    const auto record = glue::find_registered_buffer(buffer);
    ASSERT_TRUE(record.has_value());
    EXPECT_EQ(record->byte_size, 256u);
    EXPECT_FALSE(record->is_shared);
    EXPECT_EQ(record->data, static_cast<const std::byte*>(rtcGetBufferData(buffer)));
    const auto shared_record = glue::find_registered_buffer(shared_buffer);
    ASSERT_TRUE(shared_record.has_value());
    EXPECT_TRUE(shared_record->is_shared);
    EXPECT_EQ(shared_record->data, reinterpret_cast<const std::byte*>(shared.data()));

    const RTCGeometry geometry = rtcNewGeometry(app.device, RTC_GEOMETRY_TYPE_TRIANGLE);
    rtcSetGeometryBuffer(geometry, RTC_BUFFER_TYPE_VERTEX, 0, RTC_FORMAT_FLOAT3, buffer, 16, 12,
                         10);
    rtcSetGeometryBuffer(geometry, RTC_BUFFER_TYPE_INDEX, 0, RTC_FORMAT_UINT3, shared_buffer, 0, 12,
                         10);
    // Retained once, released twice: the application no longer holds the buffer, the
    // geometry still does (its view stays).
    rtcRetainBuffer(buffer);
    rtcReleaseBuffer(buffer);
    EXPECT_TRUE(glue::find_registered_buffer(buffer).has_value());
    rtcReleaseBuffer(buffer);
    rtcReleaseBuffer(shared_buffer);
    EXPECT_FALSE(glue::find_registered_buffer(buffer).has_value());
    EXPECT_EQ(glue::registry_counts().buffers, before);
    const auto geometry_record = glue::find_registered_geometry(geometry);
    ASSERT_TRUE(geometry_record.has_value());
    const auto& vertex_view = geometry_record->buffers.at({RTC_BUFFER_TYPE_VERTEX, 0});
    EXPECT_EQ(vertex_view.source, glue::BufferSource::embree_buffer);
    EXPECT_EQ(vertex_view.data, static_cast<const std::byte*>(
                                    rtcGetGeometryBufferData(geometry, RTC_BUFFER_TYPE_VERTEX, 0)));
    EXPECT_EQ(vertex_view.byte_offset, 16u);
    EXPECT_EQ(vertex_view.item_count, 10u);
    const auto& index_view = geometry_record->buffers.at({RTC_BUFFER_TYPE_INDEX, 0});
    EXPECT_EQ(index_view.data, reinterpret_cast<const std::byte*>(shared.data()));
    rtcReleaseGeometry(geometry);
}

TEST(EmbreeRegistry, RecordsInstancedSceneAndTransformInEveryFormat) {
    Device app;
    const RTCScene object = rtcNewScene(app.device);
    const RTCGeometry instance = rtcNewGeometry(app.device, RTC_GEOMETRY_TYPE_INSTANCE);
    rtcSetGeometryInstancedScene(instance, object);
    const AffineTransform expected = AffineTransform::translate({1, 2, 3}) *
                                     AffineTransform::rotate({0, 0, 1}, 0.5f) *
                                     AffineTransform::scale({2, 3, 4});
    const std::array<float, 12> expected_array = {
        expected.col_x.x, expected.col_x.y,       expected.col_x.z,       expected.col_y.x,
        expected.col_y.y, expected.col_y.z,       expected.col_z.x,       expected.col_z.y,
        expected.col_z.z, expected.translation.x, expected.translation.y, expected.translation.z};
    auto recorded = [&] { return glue::find_registered_geometry(instance)->transform; };

    rtcSetGeometryTransform(instance, 0, RTC_FORMAT_FLOAT3X4_COLUMN_MAJOR, &expected);
    EXPECT_EQ(recorded(), expected_array);
    EXPECT_EQ(glue::find_registered_geometry(instance)->instanced_scene, object);

    float row_major[12];
    for (int row = 0; row < 3; ++row)
        for (int column = 0; column < 4; ++column)
            row_major[row * 4 + column] = expected_array[std::size_t(column * 3 + row)];
    const AffineTransform identity;
    rtcSetGeometryTransform(instance, 0, RTC_FORMAT_FLOAT3X4_COLUMN_MAJOR, &identity);
    rtcSetGeometryTransform(instance, 0, RTC_FORMAT_FLOAT3X4_ROW_MAJOR, row_major);
    EXPECT_EQ(recorded(), expected_array);

    float column_major_4x4[16] = {};
    for (int column = 0; column < 4; ++column)
        for (int row = 0; row < 3; ++row)
            column_major_4x4[column * 4 + row] = expected_array[std::size_t(column * 3 + row)];
    column_major_4x4[15] = 1.0f;
    rtcSetGeometryTransform(instance, 0, RTC_FORMAT_FLOAT3X4_COLUMN_MAJOR, &identity);
    rtcSetGeometryTransform(instance, 0, RTC_FORMAT_FLOAT4X4_COLUMN_MAJOR, column_major_4x4);
    EXPECT_EQ(recorded(), expected_array);

    // A quaternion decomposition: the registry holds Embree's own matrix for it.
    RTCQuaternionDecomposition decomposition;
    rtcInitQuaternionDecomposition(&decomposition);
    rtcQuaternionDecompositionSetTranslation(&decomposition, 5, 6, 7);
    rtcQuaternionDecompositionSetScale(&decomposition, 2, 2, 2);
    rtcSetGeometryTransformQuaternion(instance, 0, &decomposition);
    std::array<float, 12> embree_matrix{};
    rtcGetGeometryTransform(instance, 0.0f, RTC_FORMAT_FLOAT3X4_COLUMN_MAJOR, embree_matrix.data());
    EXPECT_EQ(recorded(), embree_matrix);
    EXPECT_EQ(recorded()[9], 5.0f);

    // The instance keeps the scene alive after the application released it.
    rtcReleaseScene(object);
    EXPECT_TRUE(glue::find_registered_scene(object).has_value());
    rtcReleaseGeometry(instance);
    EXPECT_FALSE(glue::find_registered_scene(object).has_value());
}

TEST(EmbreeRegistry, AttachDetachAndReleaseById) {
    Device app;
    const glue::RegistryCounts before = glue::registry_counts();
    SharedMemory memory;
    const RTCScene scene = rtcNewScene(app.device);
    const RTCGeometry first =
        make_triangle_geometry(app.device, one_triangle(), BufferPath::new_geometry_buffer, memory);
    const RTCGeometry second =
        make_triangle_geometry(app.device, one_triangle(), BufferPath::new_geometry_buffer, memory);
    rtcAttachGeometryByID(scene, first, 5);
    const unsigned int second_id = rtcAttachGeometry(scene, second);
    auto record = glue::find_registered_scene(scene);
    ASSERT_TRUE(record.has_value());
    ASSERT_EQ(record->geometries.size(), 2u);
    EXPECT_EQ(record->geometries.at(5), first);
    EXPECT_EQ(record->geometries.at(second_id), second);
    EXPECT_TRUE(record->has_uncommitted_changes);
    rtcCommitScene(scene);
    EXPECT_FALSE(glue::find_registered_scene(scene)->has_uncommitted_changes);
    EXPECT_EQ(glue::find_registered_scene(scene)->commit_count, 1u);

    // Released by the application but attached: the scene holds the geometries.
    rtcReleaseGeometry(first);
    rtcReleaseGeometry(second);
    EXPECT_TRUE(glue::find_registered_geometry(first).has_value());
    rtcDetachGeometry(scene, 5);
    record = glue::find_registered_scene(scene);
    EXPECT_EQ(record->geometries.size(), 1u);
    EXPECT_FALSE(record->geometries.contains(5));
    EXPECT_FALSE(glue::find_registered_geometry(first).has_value());

    // A taken id: Embree refuses (and reports it to the application), so does the registry.
    const RTCGeometry third =
        make_triangle_geometry(app.device, one_triangle(), BufferPath::new_geometry_buffer, memory);
    rtcGetDeviceError(app.device);  // clear
    rtcAttachGeometryByID(scene, third, second_id);
    EXPECT_NE(rtcGetDeviceError(app.device), RTC_ERROR_NONE);
    EXPECT_EQ(glue::find_registered_scene(scene)->geometries.at(second_id), second);
    EXPECT_EQ(glue::find_registered_geometry(third)->scene_refs, 0u);
    rtcReleaseGeometry(third);

    // Retained once: it takes two releases to drop the scene and what it held.
    rtcRetainScene(scene);
    rtcReleaseScene(scene);
    EXPECT_TRUE(glue::find_registered_scene(scene).has_value());
    rtcReleaseScene(scene);
    const glue::RegistryCounts after = glue::registry_counts();
    EXPECT_EQ(after.scenes, before.scenes);
    EXPECT_EQ(after.geometries, before.geometries);
}

TEST(EmbreeRegistry, RecordsEnableMaskTimeStepsFiltersAndCommits) {
    Device app;
    SharedMemory memory;
    const RTCGeometry geometry =
        make_triangle_geometry(app.device, one_triangle(), BufferPath::new_geometry_buffer, memory);
    EXPECT_EQ(glue::find_registered_geometry(geometry)->commit_count, 1u);
    rtcDisableGeometry(geometry);
    EXPECT_FALSE(glue::find_registered_geometry(geometry)->is_enabled);
    rtcEnableGeometry(geometry);
    EXPECT_TRUE(glue::find_registered_geometry(geometry)->is_enabled);
    rtcSetGeometryMask(geometry, 6);
    EXPECT_EQ(glue::find_registered_geometry(geometry)->mask, 6u);
    rtcSetGeometryTimeStepCount(geometry, 3);
    EXPECT_EQ(glue::find_registered_geometry(geometry)->time_step_count, 3u);
    rtcSetGeometryIntersectFilterFunction(geometry, [](const RTCFilterFunctionNArguments*) {});
    EXPECT_TRUE(glue::find_registered_geometry(geometry)->has_filter_function);
    rtcReleaseGeometry(geometry);
}

}  // namespace
}  // namespace rebraid
