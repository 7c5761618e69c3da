// The smallest program using rebraid: a scene built in code (one mesh, three instances), the
// re-braided structure over it, and a few rays traced through it.
#include <cstdio>
#include <numbers>

#include "rebraid/rebraid.h"

int main() {
    using rebraid::AffineTransform;
    using rebraid::Vec3f;

    // One object: a unit square in the z = 0 plane, two triangles (primIDs 0 and 1).
    rebraid::Mesh square;
    square.positions = {{0, 0, 0}, {1, 0, 0}, {1, 1, 0}, {0, 1, 0}};
    square.triangles = {{0, 1, 2}, {0, 2, 3}};

    // Three placements of it (instances 0, 1, 2): as is, moved back, moved back and turned.
    rebraid::Scene scene;
    scene.meshes.push_back(square);
    const float quarter_turn = std::numbers::pi_v<float> / 2;
    scene.instances = {
        {0, AffineTransform::identity()},
        {0, AffineTransform::translate({0.5f, 0, -1})},
        {0,
         AffineTransform::translate({0, 0, -2}) * AffineTransform::rotate({0, 0, 1}, quarter_turn)},
    };

    const rebraid::InstancedAccel accel = rebraid::build_rebraid_accel(scene);

    // Rays along -z: t is in units of the direction, tfar defaults to infinity.
    for (Vec3f origin :
         {Vec3f{0.25f, 0.75f, 1}, Vec3f{1.25f, 0.5f, 1}, Vec3f{-0.25f, 0.5f, 1}, Vec3f{3, 3, 1}}) {
        const rebraid::Ray ray{.org = origin, .dir = {0, 0, -1}};
        const rebraid::Hit hit = accel.intersect(ray);
        if (hit.is_hit())
            std::printf("ray from (%g, %g): t %g, instance %u, primitive %u\n", origin.x, origin.y,
                        hit.t, hit.instance_id, hit.prim_id);
        else
            std::printf("ray from (%g, %g): miss\n", origin.x, origin.y);
    }
    return 0;
}
