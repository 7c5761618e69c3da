// An instanced-scene renderer written against Embree 3's API, switched to re-braiding.
// Everything is ordinary Embree code except the lines marked "rebraid:":
//
//   #include <rebraid/embree.h>                        // rebraid: the drop-in
//   rebraid::EmbreeAccel accel(scene);                 // rebraid: after rtcCommitScene(scene)
//   accel.intersect1(rayhit);                          // rebraid: was rtcIntersect1(scene, ...)
//
// or, leaving every rtcIntersect1 call as it is:
//
//   rebraid::EmbreeUserGeometryScene rebraided(accel); // rebraid: a scene answering with accel
//   scene = rebraided.get();                           // rebraid: trace this one instead
//
// and in CMake, target_link_libraries(app PRIVATE rebraid::embree_dropin) instead of embree.
//
// Usage (also --help): dropin_example [--mode embree|rebraid|user-geometry] [-o image.ppm]
//        dropin_example --check   (all three modes must agree; exit code 1 if not)
//        dropin_example --bench   (Mrays/s of each mode, instanced and flattened scene)
// A bad command line exits with 2.

#include <embree3/rtcore.h>
#include <rebraid/embree.h>  // rebraid: the drop-in

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <exception>
#include <fstream>
#include <string>
#include <vector>

namespace {

struct Vertex {
    float x, y, z;
};
struct Mesh {
    std::vector<Vertex> vertices;
    std::vector<unsigned int> indices;  // three per triangle
};

Mesh make_torus(float major, float minor, int segments, int sides, float bumps) {
    Mesh mesh;
    for (int i = 0; i < segments; ++i)
        for (int j = 0; j < sides; ++j) {
            const float a = 6.2831853f * float(i) / float(segments);
            const float b = 6.2831853f * float(j) / float(sides);
            const float r = minor * (1.0f + bumps * std::sin(5.0f * a) * std::sin(3.0f * b));
            mesh.vertices.push_back({(major + r * std::cos(b)) * std::cos(a), r * std::sin(b),
                                     (major + r * std::cos(b)) * std::sin(a)});
        }
    for (int i = 0; i < segments; ++i)
        for (int j = 0; j < sides; ++j) {
            const auto at = [&](int u, int v) {
                return unsigned(((u % segments) * sides) + (v % sides));
            };
            const unsigned int q[4] = {at(i, j), at(i + 1, j), at(i + 1, j + 1), at(i, j + 1)};
            mesh.indices.insert(mesh.indices.end(), {q[0], q[1], q[2], q[0], q[2], q[3]});
        }
    return mesh;
}

/// A triangle geometry with the mesh's vertices mapped by the column-major 3x4 `xfm`.
RTCGeometry new_triangle_geometry(RTCDevice device, const Mesh& mesh, const float* xfm) {
    RTCGeometry geometry = rtcNewGeometry(device, RTC_GEOMETRY_TYPE_TRIANGLE);
    auto* vertices = static_cast<Vertex*>(
        rtcSetNewGeometryBuffer(geometry, RTC_BUFFER_TYPE_VERTEX, 0, RTC_FORMAT_FLOAT3,
                                sizeof(Vertex), mesh.vertices.size()));
    for (std::size_t i = 0; i < mesh.vertices.size(); ++i) {
        const Vertex p = mesh.vertices[i];
        vertices[i] = {xfm[0] * p.x + xfm[3] * p.y + xfm[6] * p.z + xfm[9],
                       xfm[1] * p.x + xfm[4] * p.y + xfm[7] * p.z + xfm[10],
                       xfm[2] * p.x + xfm[5] * p.y + xfm[8] * p.z + xfm[11]};
    }
    auto* indices = static_cast<unsigned int*>(
        rtcSetNewGeometryBuffer(geometry, RTC_BUFFER_TYPE_INDEX, 0, RTC_FORMAT_UINT3,
                                3 * sizeof(unsigned int), mesh.indices.size() / 3));
    std::copy(mesh.indices.begin(), mesh.indices.end(), indices);
    rtcCommitGeometry(geometry);
    return geometry;
}

/// The application's scene: a ground quad and a grid x grid field of rotated, scaled
/// instances of three tori. `flattened`: every instance copied into world space instead.
RTCScene build_scene(RTCDevice device, int grid, bool flattened) {
    const Mesh meshes[3] = {make_torus(1.0f, 0.35f, 96, 32, 0.2f),
                            make_torus(0.8f, 0.2f, 64, 24, 0.5f),
                            make_torus(0.6f, 0.45f, 48, 48, 0.1f)};
    const float identity[12] = {1, 0, 0, 0, 1, 0, 0, 0, 1, 0, 0, 0};
    RTCScene scene = rtcNewScene(device);

    Mesh ground;
    const float extent = 2.0f * float(grid);
    ground.vertices = {{-extent, -0.6f, -extent},
                       {extent, -0.6f, -extent},
                       {extent, -0.6f, extent},
                       {-extent, -0.6f, extent}};
    ground.indices = {0, 2, 1, 0, 3, 2};
    RTCGeometry ground_geometry = new_triangle_geometry(device, ground, identity);
    rtcAttachGeometry(scene, ground_geometry);
    rtcReleaseGeometry(ground_geometry);

    RTCScene objects[3];
    for (int m = 0; m < 3; ++m) {
        objects[m] = rtcNewScene(device);
        RTCGeometry geometry = new_triangle_geometry(device, meshes[m], identity);
        rtcAttachGeometry(objects[m], geometry);
        rtcReleaseGeometry(geometry);
        rtcCommitScene(objects[m]);
    }
    for (int i = 0; i < grid; ++i)
        for (int j = 0; j < grid; ++j) {
            const int m = (i * 7 + j * 3) % 3;
            const float angle = 0.37f * float(i * grid + j);
            const float s = 0.8f + 0.4f * float((i + 2 * j) % 5) / 4.0f;
            const float c = std::cos(angle) * s, n = std::sin(angle) * s;
            const float xfm[12] = {c,    0,
                                   -n,   0,
                                   s,    0,
                                   n,    0,
                                   c,    4.0f * float(i - grid / 2),
                                   0.0f, 4.0f * float(j - grid / 2)};
            RTCGeometry geometry;
            if (flattened) {
                geometry = new_triangle_geometry(device, meshes[m], xfm);
            } else {
                geometry = rtcNewGeometry(device, RTC_GEOMETRY_TYPE_INSTANCE);
                rtcSetGeometryInstancedScene(geometry, objects[m]);
                rtcSetGeometryTransform(geometry, 0, RTC_FORMAT_FLOAT3X4_COLUMN_MAJOR, xfm);
                rtcCommitGeometry(geometry);
            }
            rtcAttachGeometry(scene, geometry);
            rtcReleaseGeometry(geometry);
        }
    for (RTCScene object : objects) rtcReleaseScene(object);
    rtcCommitScene(scene);
    return scene;
}

/// Primary rays of a pinhole camera looking down at the field.
std::vector<RTCRayHit> camera_rays(int width, int height, int grid) {
    std::vector<RTCRayHit> rays;
    const float distance = 2.2f * float(grid);
    for (int y = 0; y < height; ++y)
        for (int x = 0; x < width; ++x) {
            RTCRayHit rayhit{};
            rayhit.ray.org_x = 0.3f * distance;
            rayhit.ray.org_y = 0.6f * distance;
            rayhit.ray.org_z = -distance;
            const float px = (2.0f * (float(x) + 0.5f) / float(width) - 1.0f) * 0.8f;
            const float py = (1.0f - 2.0f * (float(y) + 0.5f) / float(height)) * 0.6f;
            float d[3] = {px - 0.25f, py - 0.55f, 1.0f};
            const float len = std::sqrt(d[0] * d[0] + d[1] * d[1] + d[2] * d[2]);
            rayhit.ray.dir_x = d[0] / len;
            rayhit.ray.dir_y = d[1] / len;
            rayhit.ray.dir_z = d[2] / len;
            rayhit.ray.tfar = INFINITY;
            rayhit.ray.mask = ~0u;
            rayhit.hit.geomID = RTC_INVALID_GEOMETRY_ID;
            rayhit.hit.instID[0] = RTC_INVALID_GEOMETRY_ID;
            rays.push_back(rayhit);
        }
    return rays;
}

enum class Mode { embree, rebraid, user_geometry };

/// Traces every ray in `mode`; returns the seconds it took.
double trace(Mode mode, RTCScene scene, const rebraid::EmbreeAccel& accel,
             const rebraid::EmbreeUserGeometryScene& rebraided, std::vector<RTCRayHit>& rays) {
    RTCIntersectContext context;
    rtcInitIntersectContext(&context);
    const auto start = std::chrono::steady_clock::now();
    for (RTCRayHit& rayhit : rays) {
        if (mode == Mode::embree) rtcIntersect1(scene, &context, &rayhit);
        if (mode == Mode::rebraid) accel.intersect1(rayhit);  // rebraid: was rtcIntersect1
        if (mode == Mode::user_geometry) rtcIntersect1(rebraided.get(), &context, &rayhit);
    }
    return std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
}

/// Rays whose answers differ between `a` and `b` (ids, or t beyond 1e-4 relative).
std::size_t count_differences(const std::vector<RTCRayHit>& a, const std::vector<RTCRayHit>& b) {
    std::size_t differences = 0;
    for (std::size_t i = 0; i < a.size(); ++i) {
        const bool same_ids = a[i].hit.geomID == b[i].hit.geomID &&
                              a[i].hit.instID[0] == b[i].hit.instID[0] &&
                              a[i].hit.primID == b[i].hit.primID;
        const float ta = a[i].ray.tfar, tb = b[i].ray.tfar;
        const bool same_t = ta == tb || std::fabs(ta - tb) <= 1e-4f * std::max(ta, tb);
        differences += !(same_ids && same_t);
    }
    return differences;
}

int check(RTCDevice device) {
    const int grid = 8;
    RTCScene scene = build_scene(device, grid, false);
    rebraid::EmbreeAccel accel(scene);                  // rebraid: after rtcCommitScene(scene)
    rebraid::EmbreeUserGeometryScene rebraided(accel);  // rebraid: for unchanged call sites
    int failures = 0;
    for (int round = 0; round < 2; ++round) {
        std::vector<RTCRayHit> expected = camera_rays(320, 240, grid);
        std::vector<RTCRayHit> direct = expected, through = expected;
        trace(Mode::embree, scene, accel, rebraided, expected);
        trace(Mode::rebraid, scene, accel, rebraided, direct);
        trace(Mode::user_geometry, scene, accel, rebraided, through);
        const std::size_t direct_differences = count_differences(expected, direct);
        const std::size_t through_differences = count_differences(expected, through);
        std::printf(
            "%s: %zu rays, %zu differ from rtcIntersect1 (intersect1), %zu (user geometry)\n",
            round == 0 ? "built" : "updated", expected.size(), direct_differences,
            through_differences);
        // Rays through shared edges may pick either triangle: allow one in a thousand.
        if (direct_differences > expected.size() / 1000 ||
            through_differences > expected.size() / 1000)
            ++failures;
        // Move instance 5 (geomID 5: the ground is geometry 0) and let the accel follow.
        const float moved[12] = {0, 0, 1, 0, 1, 0, -1, 0, 0, 1.0f, 0.5f, 2.0f};
        RTCGeometry instance = rtcGetGeometry(scene, 5);
        rtcSetGeometryTransform(instance, 0, RTC_FORMAT_FLOAT3X4_COLUMN_MAJOR, moved);
        rtcCommitGeometry(instance);
        rtcCommitScene(scene);
        accel.update();      // rebraid: after the application's commit
        rebraided.update();  // rebraid: the user geometry's bounds follow
    }
    rtcReleaseScene(scene);
    std::printf(failures == 0 ? "check passed\n" : "check FAILED\n");
    return failures == 0 ? 0 : 1;
}

int bench(RTCDevice device, int grid) {
    std::printf("scene,mode,build_ms,mrays_per_s\n");
    for (bool flattened : {false, true}) {
        RTCScene scene = build_scene(device, grid, flattened);
        const auto start = std::chrono::steady_clock::now();
        rebraid::EmbreeAccel accel(scene);
        const double build_ms =
            std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - start)
                .count();
        rebraid::EmbreeUserGeometryScene rebraided(accel);
        const std::vector<RTCRayHit> rays = camera_rays(640, 480, grid);
        const char* names[3] = {"rtcIntersect1", "EmbreeAccel::intersect1",
                                "rtcIntersect1 on EmbreeUserGeometryScene"};
        // Modes take turns, so that a change in machine load hits all of them alike: a
        // warm-up round, then the median of seven.
        std::vector<double> seconds[3];
        for (int round = 0; round < 8; ++round)
            for (Mode mode : {Mode::embree, Mode::rebraid, Mode::user_geometry}) {
                std::vector<RTCRayHit> work = rays;
                const double s = trace(mode, scene, accel, rebraided, work);
                if (round > 0) seconds[int(mode)].push_back(s);
            }
        for (Mode mode : {Mode::embree, Mode::rebraid, Mode::user_geometry}) {
            std::vector<double>& times = seconds[int(mode)];
            std::sort(times.begin(), times.end());
            std::printf("%s,%s,%.1f,%.2f\n", flattened ? "flattened" : "instanced",
                        names[int(mode)], mode == Mode::embree ? 0.0 : build_ms,
                        double(rays.size()) / times[times.size() / 2] * 1e-6);
        }
        rtcReleaseScene(scene);
    }
    return 0;
}

int render(RTCDevice device, Mode mode, const std::string& path) {
    const int grid = 8, width = 640, height = 480;
    RTCScene scene = build_scene(device, grid, false);
    rebraid::EmbreeAccel accel(scene);
    rebraid::EmbreeUserGeometryScene rebraided(accel);
    std::vector<RTCRayHit> rays = camera_rays(width, height, grid);
    trace(mode, scene, accel, rebraided, rays);
    std::ofstream out(path, std::ios::binary);
    out << "P6\n" << width << " " << height << "\n255\n";
    for (const RTCRayHit& rayhit : rays) {
        unsigned char rgb[3] = {40, 40, 60};
        if (rayhit.hit.geomID != RTC_INVALID_GEOMETRY_ID) {
            // Facing ratio with the (object-space, as Embree gives it) geometry normal.
            const float n =
                std::sqrt(rayhit.hit.Ng_x * rayhit.hit.Ng_x + rayhit.hit.Ng_y * rayhit.hit.Ng_y +
                          rayhit.hit.Ng_z * rayhit.hit.Ng_z);
            const float shade = n > 0.0f ? 0.3f + 0.7f * std::fabs(rayhit.hit.Ng_y) / n : 0.3f;
            const unsigned id =
                rayhit.hit.instID[0] == RTC_INVALID_GEOMETRY_ID ? 0u : rayhit.hit.instID[0];
            rgb[0] = (unsigned char)(shade * float(120 + (id * 53) % 135));
            rgb[1] = (unsigned char)(shade * float(120 + (id * 97) % 135));
            rgb[2] = (unsigned char)(shade * float(120 + (id * 31) % 135));
        }
        out.write(reinterpret_cast<const char*>(rgb), 3);
    }
    rtcReleaseScene(scene);
    std::printf("wrote %s\n", path.c_str());
    return out ? 0 : 1;
}

}  // namespace

constexpr const char* kUsage =
    "usage: dropin_example [--mode embree|rebraid|user-geometry] [--grid N] [-o image.ppm]\n"
    "       dropin_example --check   all three modes must agree (exit code 1 if not)\n"
    "       dropin_example --bench   Mrays/s of each mode, instanced and flattened scene\n"
    "--grid N: N x N instances (default 24); -o: the image of --mode (default dropin.ppm)\n";

/// Prints `message` and the usage on stderr; the exit code of a bad command line.
int usage_error(const std::string& message) {
    std::fprintf(stderr, "dropin_example: %s\n%s", message.c_str(), kUsage);
    return 2;
}

int main(int argc, char** argv) {
    try {
        Mode mode = Mode::rebraid;
        std::string output = "dropin.ppm";
        bool is_check = false, is_bench = false;
        int grid = 24;
        for (int i = 1; i < argc; ++i) {
            const std::string arg = argv[i];
            const bool takes_value = arg == "--grid" || arg == "-o" || arg == "--mode";
            if (takes_value && i + 1 >= argc) return usage_error(arg + " needs a value");
            if (arg == "-h" || arg == "--help") {
                std::fputs(kUsage, stdout);
                return 0;
            } else if (arg == "--check") {
                is_check = true;
            } else if (arg == "--bench") {
                is_bench = true;
            } else if (arg == "--grid") {
                const std::string value = argv[++i];
                char* end = nullptr;
                const long parsed = std::strtol(value.c_str(), &end, 10);
                if (value.empty() || *end != '\0' || parsed < 1 || parsed > 1000)
                    return usage_error("--grid " + value +
                                       ": expected a whole number from 1 to 1000");
                grid = static_cast<int>(parsed);
            } else if (arg == "-o") {
                output = argv[++i];
            } else if (arg == "--mode") {
                const std::string name = argv[++i];
                if (name == "embree")
                    mode = Mode::embree;
                else if (name == "rebraid")
                    mode = Mode::rebraid;
                else if (name == "user-geometry")
                    mode = Mode::user_geometry;
                else
                    return usage_error("--mode " + name +
                                       ": expected embree, rebraid or user-geometry");
            } else {
                return usage_error("unknown argument " + arg);
            }
        }
        RTCDevice device = rtcNewDevice(nullptr);
        const int result = is_check   ? check(device)
                           : is_bench ? bench(device, grid)
                                      : render(device, mode, output);
        rtcReleaseDevice(device);
        return result;
    } catch (const std::exception& error) {
        std::fprintf(stderr, "dropin_example: %s\n", error.what());
        return 1;
    }
}
