#include "rebraid/io/ray_file.h"

#include <gtest/gtest.h>

#include <bit>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <limits>
#include <sstream>
#include <string>
#include <vector>

#include "rebraid/core/error.h"
#include "rebraid/core/random.h"

namespace rebraid {
namespace {

constexpr float kInf = std::numeric_limits<float>::infinity();

std::vector<Ray> read_string(const std::string& text) {
    std::istringstream in(text);
    return read_rays(in, "test.rays");
}

/// Bit-exact comparison: -0 and +0 differ, which a round trip must preserve too.
void expect_same_bits(float a, float b) {
    EXPECT_EQ(std::bit_cast<std::uint32_t>(a), std::bit_cast<std::uint32_t>(b)) << a << " " << b;
}

void expect_same_ray(const Ray& a, const Ray& b) {
    for (int axis = 0; axis < 3; ++axis) {
        expect_same_bits(a.org[axis], b.org[axis]);
        expect_same_bits(a.dir[axis], b.dir[axis]);
    }
    expect_same_bits(a.tnear, b.tnear);
    expect_same_bits(a.tfar, b.tfar);
}

/// A finite float from random bits (any exponent, subnormals included).
float random_finite_float(Random& random) {
    for (;;) {
        const float f = std::bit_cast<float>(random.next_u32());
        if (std::isfinite(f)) return f;
    }
}

TEST(RayFile, WriteThenReadGivesIdenticalRays) {
    Random random(11);
    std::vector<Ray> rays;
    for (int i = 0; i < 2000; ++i) {
        Ray ray;
        ray.org = {random_finite_float(random), random_finite_float(random),
                   random_finite_float(random)};
        do {
            ray.dir = {random_finite_float(random), random_finite_float(random),
                       random_finite_float(random)};
        } while (ray.dir == Vec3f{});
        ray.tnear = std::fabs(random_finite_float(random));
        ray.tfar = (i % 3 == 0) ? kInf : random_finite_float(random);
        rays.push_back(ray);
    }
    // Hand-picked extremes: largest, smallest subnormal, negative zero, ordinary values.
    rays.push_back({{std::numeric_limits<float>::max(), -std::numeric_limits<float>::max(),
                     std::numeric_limits<float>::denorm_min()},
                    0.0f,
                    {-0.0f, 0.1f, 1.0f / 3.0f},
                    kInf});
    std::ostringstream out;
    write_rays(out, rays);
    const std::vector<Ray> back = read_string(out.str());
    ASSERT_EQ(back.size(), rays.size());
    for (std::size_t i = 0; i < rays.size(); ++i) expect_same_ray(back[i], rays[i]);
}

TEST(RayFile, ParsesInfinitySignsAndExponents) {
    const std::vector<Ray> rays = read_string(
        "1 -2.5 +3 0 0 1 0 inf\n"
        "0 0 0 1e-3 -2E2 +0.5 1.25 +inf\n"
        "0 0 0 1 0 0 0 INF\n"
        "0 0 0 1 0 0 0 Infinity\n"
        "0 0 0 1 0 0 2 100\n");
    ASSERT_EQ(rays.size(), 5u);
    EXPECT_EQ(rays[0].org, (Vec3f{1.0f, -2.5f, 3.0f}));
    EXPECT_EQ(rays[0].dir, (Vec3f{0.0f, 0.0f, 1.0f}));
    EXPECT_EQ(rays[0].tnear, 0.0f);
    EXPECT_EQ(rays[0].tfar, kInf);
    EXPECT_EQ(rays[1].dir, (Vec3f{1e-3f, -200.0f, 0.5f}));
    EXPECT_EQ(rays[1].tnear, 1.25f);
    EXPECT_EQ(rays[1].tfar, kInf);
    EXPECT_EQ(rays[2].tfar, kInf);
    EXPECT_EQ(rays[3].tfar, kInf);
    EXPECT_EQ(rays[4].tnear, 2.0f);
    EXPECT_EQ(rays[4].tfar, 100.0f);
}

TEST(RayFile, SkipsCommentsBlankLinesAndExtraWhitespace) {
    const std::vector<Ray> rays = read_string(
        "# header comment\n"
        "\n"
        "   \t \n"
        "  # indented comment 1 2 3\n"
        "\t1  2\t3 4 5 6   7 8  \r\n"
        "\n"
        "9 8 7 6 5 4 3 2");  // no final newline
    ASSERT_EQ(rays.size(), 2u);
    EXPECT_EQ(rays[0].org, (Vec3f{1, 2, 3}));
    EXPECT_EQ(rays[0].dir, (Vec3f{4, 5, 6}));
    EXPECT_EQ(rays[0].tnear, 7.0f);
    EXPECT_EQ(rays[0].tfar, 8.0f);
    EXPECT_EQ(rays[1].org, (Vec3f{9, 8, 7}));
    EXPECT_EQ(rays[1].tfar, 2.0f);
}

TEST(RayFile, EmptyInputGivesNoRays) {
    EXPECT_TRUE(read_string("").empty());
}

TEST(RayFile, TnearBeyondTfarIsAcceptedAsIs) {
    const std::vector<Ray> rays = read_string("0 0 0 1 0 0 5 1\n");
    ASSERT_EQ(rays.size(), 1u);
    EXPECT_EQ(rays[0].tnear, 5.0f);
    EXPECT_EQ(rays[0].tfar, 1.0f);
}

TEST(RayFile, EveryBadLineNamesSourceAndLineNumber) {
    const std::vector<std::string> bad_lines = {
        "0 0 0 1 0 0 0",             // 7 fields
        "0 0 0 1 0 0 0 inf 1",       // 9 fields
        "0 0 0 1 0 0 0 inf # note",  // trailing comment counts as fields
        "0 0 zero 1 0 0 0 inf",      // not a number
        "0 0 0 1.0x 0 0 0 inf",      // trailing junk
        "0 0 0 1 0 0 0 0x10",        // hex is not accepted
        "0 0 0 1 0 0 0 --1",         // double sign
        "nan 0 0 1 0 0 0 inf",       // NaN origin
        "0 0 0 0 NaN 1 0 inf",       // NaN direction
        "0 0 0 1 0 0 nan inf",       // NaN tnear
        "0 0 0 1 0 0 0 nan",         // NaN tfar
        "inf 0 0 1 0 0 0 inf",       // infinite origin
        "0 0 0 1 -inf 0 0 inf",      // infinite direction
        "0 0 0 1 0 0 inf inf",       // infinite tnear
        "0 0 0 1 0 0 0 -inf",        // tfar -inf
        "0 0 0 0 0 0 0 inf",         // zero direction
        "0 0 0 -0 0 -0 0 inf",       // zero direction with signs
        "0 0 0 1 0 0 -1 inf",        // negative tnear
        "1e39 0 0 1 0 0 0 inf",      // beyond float range
        "0 0 0 1 0 0 0 -1e300",      // beyond float range
    };
    for (const std::string& bad : bad_lines) {
        const std::string text = "# rays\n0 0 0 1 0 0 0 inf\n" + bad + "\n0 0 0 1 0 0 0 inf\n";
        try {
            read_string(text);
            ADD_FAILURE() << "accepted bad line: " << bad;
        } catch (const Error& e) {
            const std::string message = e.what();
            EXPECT_NE(message.find("line 3"), std::string::npos) << message;
            EXPECT_NE(message.find("test.rays"), std::string::npos) << message;
        }
    }
}

TEST(RayFile, TinyValuesReadAsNearestFloat) {
    const std::vector<Ray> rays = read_string("1e-60 -1e-50 0 1 0 0 0 inf\n");
    ASSERT_EQ(rays.size(), 1u);
    EXPECT_EQ(rays[0].org.x, 0.0f);
    EXPECT_EQ(rays[0].org.y, 0.0f);
}

TEST(RayFile, ReadRayFileReadsWhatWasWritten) {
    const std::filesystem::path path =
        std::filesystem::path(REBRAID_TEST_TMP) / "ray_file_test_roundtrip.rays";
    const std::vector<Ray> rays = {{{1, 2, 3}, 0.5f, {0, -1, 0}, kInf},
                                   {{-4, 5.25f, 6}, 0.0f, {0.25f, 0, 1}, 10.0f}};
    {
        std::ofstream out(path);
        write_rays(out, rays);
    }
    const std::vector<Ray> back = read_ray_file(path.string());
    ASSERT_EQ(back.size(), rays.size());
    for (std::size_t i = 0; i < rays.size(); ++i) expect_same_ray(back[i], rays[i]);
    std::filesystem::remove(path);
}

TEST(RayFile, MissingFileErrorNamesThePath) {
    const std::string path = std::string(REBRAID_TEST_TMP) + "/no_such_dir/missing.rays";
    try {
        read_ray_file(path);
        ADD_FAILURE() << "no error for a missing file";
    } catch (const Error& e) {
        EXPECT_NE(std::string(e.what()).find(path), std::string::npos) << e.what();
    }
}

TEST(RayFile, BadLineInFileNamesThePath) {
    const std::filesystem::path path =
        std::filesystem::path(REBRAID_TEST_TMP) / "ray_file_test_bad.rays";
    {
        std::ofstream out(path);
        out << "0 0 0 1 0 0 0 inf\n0 0 0 1 0 0\n";
    }
    try {
        read_ray_file(path.string());
        ADD_FAILURE() << "accepted a 6-field line";
    } catch (const Error& e) {
        const std::string message = e.what();
        EXPECT_NE(message.find(path.string()), std::string::npos) << message;
        EXPECT_NE(message.find("line 2"), std::string::npos) << message;
    }
    std::filesystem::remove(path);
}

TEST(HitFile, WritesHitsAndMissesInTheDocumentedFormat) {
    std::vector<Hit> hits(4);
    hits[0].t = 1.5f;
    hits[0].instance_id = 3;
    hits[0].prim_id = 42;
    // hits[1] stays a miss.
    hits[2].t = 1.0f / 3.0f;  // float nearest 1/3 is 0.3333333432674407958984375
    hits[2].instance_id = 0;
    hits[2].prim_id = 4000000000u;
    hits[3].t = 123456789.0f;  // float 123456792: 9 digits, no exponent
    hits[3].instance_id = 7;
    hits[3].prim_id = 0;
    std::ostringstream out;
    write_hits(out, hits);
    EXPECT_EQ(out.str(),
              "1.5 3 42\n"
              "inf -1 -1\n"
              "0.333333343 0 4000000000\n"
              "123456792 7 0\n");
}

TEST(HitFile, TimesMatchPrintfNineSignificantDigits) {
    Random random(5);
    std::vector<Hit> hits;
    for (int i = 0; i < 500; ++i) {
        Hit hit;
        hit.t = std::fabs(random_finite_float(random));
        hit.instance_id = static_cast<InstanceId>(i);
        hit.prim_id = static_cast<PrimId>(2 * i);
        hits.push_back(hit);
    }
    std::ostringstream out;
    write_hits(out, hits);
    std::istringstream lines(out.str());
    std::string line;
    for (const Hit& hit : hits) {
        ASSERT_TRUE(std::getline(lines, line));
        char expected[96];
        std::snprintf(expected, sizeof expected, "%.9g %u %u", static_cast<double>(hit.t),
                      hit.instance_id, hit.prim_id);
        EXPECT_EQ(line, expected);
    }
}

}  // namespace
}  // namespace rebraid
