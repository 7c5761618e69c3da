// An Embree 3 application that knows nothing of rebraid, for the preload library's tests
// (embree_preload_test.cpp runs it with and without LD_PRELOAD and compares what it prints).
//
//   embree_preload_client trace    builds scenes rebraid serves (triangles, instances of a
//                                  scene of triangles, masks, a re-commit after moving an
//                                  instance) and scenes it must leave to Embree (a quad mesh,
//                                  a filter function, nested instancing, motion blur), traces
//                                  the same rays through every ray-query call and prints each
//                                  answer bit for bit
//   embree_preload_client cycles N creates, commits, traces and releases a scene N times and
//                                  prints the resident memory (kB) after N/10 and after N
//
// It links libembree3 only: never rebraid.

#include <embree3/rtcore.h>

#include <array>
#include <cinttypes>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <fstream>
#include <string>
#include <vector>

namespace {

/// A fixed pseudo-random sequence (the same numbers on every run and machine).
class Random {
public:
    float next(float low, float high) {
        state_ = state_ * 6364136223846793005ull + 1442695040888963407ull;
        const float unit = float(state_ >> 40) / float(1ull << 24);
        return low + (high - low) * unit;
    }

private:
    std::uint64_t state_ = 0x9e3779b97f4a7c15ull;
};

std::uint32_t bits(float value) {
    std::uint32_t out;
    std::memcpy(&out, &value, sizeof out);
    return out;
}

/// A committed triangle mesh of `count` random triangles in [-1, 1]^3 (shared buffers when
/// `shared` is given, else Embree's).
RTCGeometry random_triangles(RTCDevice device, Random& random, unsigned int count) {
    const RTCGeometry geometry = rtcNewGeometry(device, RTC_GEOMETRY_TYPE_TRIANGLE);
    auto* vertices = static_cast<float*>(rtcSetNewGeometryBuffer(
        geometry, RTC_BUFFER_TYPE_VERTEX, 0, RTC_FORMAT_FLOAT3, 3 * sizeof(float), 3 * count));
    auto* indices = static_cast<unsigned int*>(rtcSetNewGeometryBuffer(
        geometry, RTC_BUFFER_TYPE_INDEX, 0, RTC_FORMAT_UINT3, 3 * sizeof(unsigned int), count));
    for (unsigned int t = 0; t < count; ++t) {
        const float cx = random.next(-1, 1), cy = random.next(-1, 1), cz = random.next(-1, 1);
        for (unsigned int corner = 0; corner < 3; ++corner) {
            float* v = vertices + 9 * t + 3 * corner;
            v[0] = cx + random.next(-0.3f, 0.3f);
            v[1] = cy + random.next(-0.3f, 0.3f);
            v[2] = cz + random.next(-0.3f, 0.3f);
            indices[3 * t + corner] = 3 * t + corner;
        }
    }
    rtcCommitGeometry(geometry);
    return geometry;
}

RTCGeometry instance_of(RTCDevice device, RTCScene scene, float angle, float dx, float dy) {
    const RTCGeometry instance = rtcNewGeometry(device, RTC_GEOMETRY_TYPE_INSTANCE);
    rtcSetGeometryInstancedScene(instance, scene);
    const float c = std::cos(angle), s = std::sin(angle);
    const float column_major[12] = {c, s, 0, -s, c, 0, 0, 0, 1.2f, dx, dy, 0.1f};
    rtcSetGeometryTransform(instance, 0, RTC_FORMAT_FLOAT3X4_COLUMN_MAJOR, column_major);
    rtcCommitGeometry(instance);
    return instance;
}

void attach_and_release(RTCScene scene, RTCGeometry geometry) {
    rtcAttachGeometry(scene, geometry);
    rtcReleaseGeometry(geometry);
}

/// Random rays towards [-2, 2]^3, some inactive (tnear > tfar), some with mask 0.
std::vector<RTCRayHit> make_rays(unsigned int count) {
    Random random;
    std::vector<RTCRayHit> rays(count);
    for (unsigned int i = 0; i < count; ++i) {
        RTCRayHit& rayhit = rays[i];
        rayhit = {};
        RTCRay& ray = rayhit.ray;
        ray.org_x = random.next(-4, 4);
        ray.org_y = random.next(-4, 4);
        ray.org_z = -5.0f;
        ray.dir_x = random.next(-2, 2) - ray.org_x;
        ray.dir_y = random.next(-2, 2) - ray.org_y;
        ray.dir_z = random.next(-2, 2) - ray.org_z;
        ray.tnear = i % 17 == 3 ? 2.0f : 0.0f;
        ray.tfar = i % 17 == 3 ? 1.0f : (i % 5 == 0 ? 0.9f : INFINITY);
        ray.mask = i % 23 == 7 ? 0u : 0xffffffffu;
        ray.id = i;
        rayhit.hit.geomID = RTC_INVALID_GEOMETRY_ID;
        rayhit.hit.instID[0] = RTC_INVALID_GEOMETRY_ID;
    }
    return rays;
}

void print_hit(const char* call, unsigned int i, const RTCRayHit& rayhit) {
    const RTCHit& hit = rayhit.hit;
    std::printf("%s %u: tfar %08x", call, i, bits(rayhit.ray.tfar));
    if (hit.geomID != RTC_INVALID_GEOMETRY_ID)
        std::printf(" geom %u prim %u inst %u u %08x v %08x Ng %08x %08x %08x", hit.geomID,
                    hit.primID, hit.instID[0], bits(hit.u), bits(hit.v), bits(hit.Ng_x),
                    bits(hit.Ng_y), bits(hit.Ng_z));
    std::printf("\n");
}

void print_occlusion(const char* call, unsigned int i, const RTCRay& ray) {
    std::printf("%s %u: tfar %08x\n", call, i, bits(ray.tfar));
}

/// Copies ray `i` of `rays` into lane `lane` of a packet or stream in SOA layout of width n.
void to_lane(RTCRayHitN* packet, unsigned int n, unsigned int lane, const RTCRayHit& rayhit) {
    RTCRayN* ray = RTCRayHitN_RayN(packet, n);
    RTCRayN_org_x(ray, n, lane) = rayhit.ray.org_x;
    RTCRayN_org_y(ray, n, lane) = rayhit.ray.org_y;
    RTCRayN_org_z(ray, n, lane) = rayhit.ray.org_z;
    RTCRayN_tnear(ray, n, lane) = rayhit.ray.tnear;
    RTCRayN_dir_x(ray, n, lane) = rayhit.ray.dir_x;
    RTCRayN_dir_y(ray, n, lane) = rayhit.ray.dir_y;
    RTCRayN_dir_z(ray, n, lane) = rayhit.ray.dir_z;
    RTCRayN_time(ray, n, lane) = rayhit.ray.time;
    RTCRayN_tfar(ray, n, lane) = rayhit.ray.tfar;
    RTCRayN_mask(ray, n, lane) = rayhit.ray.mask;
    RTCRayN_id(ray, n, lane) = rayhit.ray.id;
    RTCRayN_flags(ray, n, lane) = rayhit.ray.flags;
    rtcCopyHitToHitN(RTCRayHitN_HitN(packet, n), &rayhit.hit, n, lane);
}

RTCIntersectContext plain_context() {
    RTCIntersectContext context;
    rtcInitIntersectContext(&context);
    return context;
}

/// Every ray-query call on `scene`, each answer printed. Lanes of packets whose index is
/// 1 mod 3 are marked invalid.
void trace_everything(RTCScene scene, const std::vector<RTCRayHit>& rays) {
    RTCIntersectContext context = plain_context();
    const unsigned int count = unsigned(rays.size());
    for (unsigned int i = 0; i < count; ++i) {
        RTCRayHit rayhit = rays[i];
        rtcIntersect1(scene, &context, &rayhit);
        print_hit("rtcIntersect1", i, rayhit);
        RTCRay ray = rays[i].ray;
        rtcOccluded1(scene, &context, &ray);
        print_occlusion("rtcOccluded1", i, ray);
    }
    // Packets of 4, 8 and 16 (one buffer, aligned for the widest).
    alignas(64) std::array<std::byte, sizeof(RTCRayHit16)> packet{};
    alignas(64) std::array<int, 16> valid{};
    for (unsigned int width : {4u, 8u, 16u}) {
        for (unsigned int first = 0; first + width <= count; first += width) {
            auto* rayhit_n = reinterpret_cast<RTCRayHitN*>(packet.data());
            for (unsigned int lane = 0; lane < width; ++lane) {
                to_lane(rayhit_n, width, lane, rays[first + lane]);
                valid[lane] = lane % 3 == 1 ? 0 : -1;
            }
            if (width == 4) rtcIntersect4(valid.data(), scene, &context, (RTCRayHit4*)rayhit_n);
            if (width == 8) rtcIntersect8(valid.data(), scene, &context, (RTCRayHit8*)rayhit_n);
            if (width == 16) rtcIntersect16(valid.data(), scene, &context, (RTCRayHit16*)rayhit_n);
            for (unsigned int lane = 0; lane < width; ++lane)
                print_hit("rtcIntersectK", first + lane,
                          rtcGetRayHitFromRayHitN(rayhit_n, width, lane));
            for (unsigned int lane = 0; lane < width; ++lane)
                to_lane(rayhit_n, width, lane, rays[first + lane]);
            auto* ray_n = reinterpret_cast<RTCRayN*>(packet.data());
            if (width == 4) rtcOccluded4(valid.data(), scene, &context, (RTCRay4*)ray_n);
            if (width == 8) rtcOccluded8(valid.data(), scene, &context, (RTCRay8*)ray_n);
            if (width == 16) rtcOccluded16(valid.data(), scene, &context, (RTCRay16*)ray_n);
            for (unsigned int lane = 0; lane < width; ++lane)
                std::printf("rtcOccludedK %u: tfar %08x\n", first + lane,
                            bits(RTCRayN_tfar(ray_n, width, lane)));
        }
    }
    // Streams: 1M (with a stride larger than the struct), 1Mp, NM (N = 4), Np.
    struct Padded {
        RTCRayHit rayhit;
        float padding[3];
    };
    std::vector<Padded> padded(count);
    for (unsigned int i = 0; i < count; ++i) padded[i].rayhit = rays[i];
    rtcIntersect1M(scene, &context, &padded[0].rayhit, count, sizeof(Padded));
    for (unsigned int i = 0; i < count; ++i) print_hit("rtcIntersect1M", i, padded[i].rayhit);
    std::vector<RTCRay> plain(count);
    for (unsigned int i = 0; i < count; ++i) plain[i] = rays[i].ray;
    rtcOccluded1M(scene, &context, plain.data(), count, sizeof(RTCRay));
    for (unsigned int i = 0; i < count; ++i) print_occlusion("rtcOccluded1M", i, plain[i]);

    std::vector<RTCRayHit> copies = rays;
    std::vector<RTCRayHit*> pointers;
    std::vector<RTCRay*> ray_pointers;
    for (RTCRayHit& copy : copies) pointers.push_back(&copy);
    rtcIntersect1Mp(scene, &context, pointers.data(), count);
    for (unsigned int i = 0; i < count; ++i) print_hit("rtcIntersect1Mp", i, copies[i]);
    copies = rays;
    for (RTCRayHit& copy : copies) ray_pointers.push_back(&copy.ray);
    rtcOccluded1Mp(scene, &context, ray_pointers.data(), count);
    for (unsigned int i = 0; i < count; ++i) print_occlusion("rtcOccluded1Mp", i, copies[i].ray);

    const unsigned int packets = count / 4;
    std::vector<RTCRayHit4> soa(packets);
    for (unsigned int i = 0; i < 4 * packets; ++i)
        to_lane(reinterpret_cast<RTCRayHitN*>(&soa[i / 4]), 4, i % 4, rays[i]);
    rtcIntersectNM(scene, &context, reinterpret_cast<RTCRayHitN*>(soa.data()), 4, packets,
                   sizeof(RTCRayHit4));
    for (unsigned int i = 0; i < 4 * packets; ++i)
        print_hit("rtcIntersectNM", i,
                  rtcGetRayHitFromRayHitN(reinterpret_cast<RTCRayHitN*>(&soa[i / 4]), 4, i % 4));
    for (unsigned int i = 0; i < 4 * packets; ++i)
        to_lane(reinterpret_cast<RTCRayHitN*>(&soa[i / 4]), 4, i % 4, rays[i]);
    rtcOccludedNM(scene, &context, reinterpret_cast<RTCRayN*>(soa.data()), 4, packets,
                  sizeof(RTCRayHit4));
    for (unsigned int i = 0; i < 4 * packets; ++i)
        std::printf("rtcOccludedNM %u: tfar %08x\n", i, bits(soa[i / 4].ray.tfar[i % 4]));

    // Pointer SOA: one array per field.
    std::vector<float> ox(count), oy(count), oz(count), tn(count), dx(count), dy(count), dz(count),
        time(count), tf(count), ngx(count), ngy(count), ngz(count), u(count), v(count);
    std::vector<unsigned int> mask(count), id(count), flags(count), prim(count), geom(count),
        inst(count);
    auto fill = [&] {
        for (unsigned int i = 0; i < count; ++i) {
            const RTCRay& ray = rays[i].ray;
            ox[i] = ray.org_x, oy[i] = ray.org_y, oz[i] = ray.org_z, tn[i] = ray.tnear;
            dx[i] = ray.dir_x, dy[i] = ray.dir_y, dz[i] = ray.dir_z, time[i] = ray.time;
            tf[i] = ray.tfar, mask[i] = ray.mask, id[i] = ray.id, flags[i] = ray.flags;
            geom[i] = RTC_INVALID_GEOMETRY_ID, inst[i] = RTC_INVALID_GEOMETRY_ID;
        }
    };
    fill();
    RTCRayHitNp np{};
    np.ray = {ox.data(), oy.data(),   oz.data(), tn.data(),   dx.data(), dy.data(),
              dz.data(), time.data(), tf.data(), mask.data(), id.data(), flags.data()};
    np.hit.Ng_x = ngx.data(), np.hit.Ng_y = ngy.data(), np.hit.Ng_z = ngz.data();
    np.hit.u = u.data(), np.hit.v = v.data(), np.hit.primID = prim.data();
    np.hit.geomID = geom.data(), np.hit.instID[0] = inst.data();
    rtcIntersectNp(scene, &context, &np, count);
    for (unsigned int i = 0; i < count; ++i) {
        RTCRayHit rayhit = rays[i];
        rayhit.ray.tfar = tf[i];
        rayhit.hit = {ngx[i], ngy[i], ngz[i], u[i], v[i], prim[i], geom[i], {inst[i]}};
        print_hit("rtcIntersectNp", i, rayhit);
    }
    fill();
    rtcOccludedNp(scene, &context, &np.ray, count);
    for (unsigned int i = 0; i < count; ++i)
        std::printf("rtcOccludedNp %u: tfar %08x\n", i, bits(tf[i]));
}

/// Keeps hits on even primitives only (an application's filter: only Embree can call it).
void even_primitives_only(const RTCFilterFunctionNArguments* arguments) {
    for (unsigned int i = 0; i < arguments->N; ++i)
        if (RTCHitN_primID(arguments->hit, arguments->N, i) % 2 == 1) arguments->valid[i] = 0;
}

int trace() {
    const RTCDevice device = rtcNewDevice(nullptr);
    Random random;
    const std::vector<RTCRayHit> rays = make_rays(400);

    // Served: a mesh of its own and overlapping instances of a scene of triangles.
    const RTCScene object = rtcNewScene(device);
    rtcSetSceneFlags(object, RTC_SCENE_FLAG_CONTEXT_FILTER_FUNCTION);
    attach_and_release(object, random_triangles(device, random, 60));
    attach_and_release(object, random_triangles(device, random, 40));
    rtcCommitScene(object);
    const RTCScene served = rtcNewScene(device);
    // Allow the context filter below (in both scenes); change nothing for calls without one.
    rtcSetSceneFlags(served, RTC_SCENE_FLAG_CONTEXT_FILTER_FUNCTION);
    attach_and_release(served, random_triangles(device, random, 50));
    RTCGeometry moved = nullptr;
    for (int i = 0; i < 5; ++i) {
        const RTCGeometry instance =
            instance_of(device, object, 0.7f * float(i), 0.3f * float(i), -0.2f * float(i));
        if (i == 2) moved = instance;
        rtcAttachGeometry(served, instance);
        if (i != 2) rtcReleaseGeometry(instance);
    }
    rtcCommitScene(served);
    std::printf("scene: served\n");
    trace_everything(served, rays);

    // The same scene after moving an instance (an update).
    const float column_major[12] = {1, 0, 0, 0, 1, 0, 0, 0, 1, -1.0f, 0.5f, 0.0f};
    rtcSetGeometryTransform(moved, 0, RTC_FORMAT_FLOAT3X4_COLUMN_MAJOR, column_major);
    rtcCommitGeometry(moved);
    rtcReleaseGeometry(moved);
    rtcCommitScene(served);
    std::printf("scene: served, moved\n");
    trace_everything(served, rays);

    // The context's filter: that call goes to Embree.
    {
        RTCIntersectContext context = plain_context();
        context.filter = even_primitives_only;
        for (unsigned int i = 0; i < rays.size(); ++i) {
            RTCRayHit rayhit = rays[i];
            rtcIntersect1(served, &context, &rayhit);
            print_hit("context filter", i, rayhit);
        }
    }

    // Left to Embree: a quad mesh.
    const RTCScene quads = rtcNewScene(device);
    {
        const RTCGeometry quad = rtcNewGeometry(device, RTC_GEOMETRY_TYPE_QUAD);
        const float vertices[] = {-2, -2, 0, 2, -2, 0, 2, 2, 0.5f, -2, 2, 0};
        const unsigned int indices[] = {0, 1, 2, 3};
        std::memcpy(rtcSetNewGeometryBuffer(quad, RTC_BUFFER_TYPE_VERTEX, 0, RTC_FORMAT_FLOAT3,
                                            3 * sizeof(float), 4),
                    vertices, sizeof vertices);
        std::memcpy(rtcSetNewGeometryBuffer(quad, RTC_BUFFER_TYPE_INDEX, 0, RTC_FORMAT_UINT4,
                                            4 * sizeof(unsigned int), 1),
                    indices, sizeof indices);
        rtcCommitGeometry(quad);
        attach_and_release(quads, quad);
        attach_and_release(quads, random_triangles(device, random, 20));
    }
    rtcCommitScene(quads);
    std::printf("scene: quads\n");
    trace_everything(quads, rays);

    // Left to Embree: a filter function on a geometry.
    const RTCScene filtered = rtcNewScene(device);
    {
        const RTCGeometry geometry = random_triangles(device, random, 80);
        rtcSetGeometryIntersectFilterFunction(geometry, even_primitives_only);
        rtcSetGeometryOccludedFilterFunction(geometry, even_primitives_only);
        rtcCommitGeometry(geometry);
        attach_and_release(filtered, geometry);
    }
    rtcCommitScene(filtered);
    std::printf("scene: filtered\n");
    trace_everything(filtered, rays);

    // Left to Embree: motion blur (two time steps).
    const RTCScene blurred = rtcNewScene(device);
    {
        const RTCGeometry geometry = rtcNewGeometry(device, RTC_GEOMETRY_TYPE_TRIANGLE);
        rtcSetGeometryTimeStepCount(geometry, 2);
        for (unsigned int step = 0; step < 2; ++step) {
            const float vertices[] = {-1, -1, 0.5f * float(step), 1, -1, 0, 0, 1, 0};
            std::memcpy(rtcSetNewGeometryBuffer(geometry, RTC_BUFFER_TYPE_VERTEX, step,
                                                RTC_FORMAT_FLOAT3, 3 * sizeof(float), 3),
                        vertices, sizeof vertices);
        }
        const unsigned int indices[] = {0, 1, 2};
        std::memcpy(rtcSetNewGeometryBuffer(geometry, RTC_BUFFER_TYPE_INDEX, 0, RTC_FORMAT_UINT3,
                                            3 * sizeof(unsigned int), 1),
                    indices, sizeof indices);
        rtcCommitGeometry(geometry);
        attach_and_release(blurred, geometry);
    }
    rtcCommitScene(blurred);
    std::printf("scene: motion blur\n");
    trace_everything(blurred, rays);

    rtcReleaseScene(blurred);
    rtcReleaseScene(filtered);
    rtcReleaseScene(quads);
    rtcReleaseScene(served);
    rtcReleaseScene(object);
    rtcReleaseDevice(device);
    return 0;
}

long resident_kb() {
    std::ifstream status("/proc/self/status");
    std::string line;
    while (std::getline(status, line))
        if (line.rfind("VmRSS:", 0) == 0) return std::strtol(line.c_str() + 6, nullptr, 10);
    return -1;
}

int cycles(unsigned int count) {
    const RTCDevice device = rtcNewDevice(nullptr);
    const std::vector<RTCRayHit> rays = make_rays(64);
    unsigned int hits = 0;
    for (unsigned int cycle = 1; cycle <= count; ++cycle) {
        Random random;
        const RTCScene object = rtcNewScene(device);
        attach_and_release(object, random_triangles(device, random, 200));
        rtcCommitScene(object);
        const RTCScene scene = rtcNewScene(device);
        for (int i = 0; i < 4; ++i)
            attach_and_release(scene, instance_of(device, object, float(i), 0.2f * float(i), 0));
        rtcCommitScene(scene);
        RTCIntersectContext context = plain_context();
        for (const RTCRayHit& ray : rays) {
            RTCRayHit rayhit = ray;
            rtcIntersect1(scene, &context, &rayhit);
            hits += rayhit.hit.geomID != RTC_INVALID_GEOMETRY_ID;
        }
        rtcReleaseScene(scene);
        rtcReleaseScene(object);
        if (cycle == count / 10 || cycle == count)
            std::printf("cycle %u: resident %ld kB\n", cycle, resident_kb());
    }
    std::printf("hits %u\n", hits);
    rtcReleaseDevice(device);
    return 0;
}

}  // namespace

int main(int argc, char** argv) {
    const std::string mode = argc > 1 ? argv[1] : "";
    if (mode == "trace" && argc == 2) return trace();
    if (mode == "cycles" && argc == 3) return cycles(unsigned(std::strtoul(argv[2], nullptr, 10)));
    std::fprintf(stderr, "usage: embree_preload_client trace | cycles N\n");
    return 2;
}
