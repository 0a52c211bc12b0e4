// Seeded random meshes and poses for tests.
#pragma once

#include "kernel/core/rigid_transform.h"
#include "kernel/mesh/triangle_mesh.h"

#include <array>
#include <memory>
#include <random>
#include <string>
#include <vector>

namespace gk::testing {

using Rng = std::mt19937_64;

// A closed, outward-oriented, star-shaped blob: a subdivided octahedron whose vertices are pushed
// to random radii in [radius * (1 - roughness), radius]. subdivisions 0 gives 8 triangles, each
// level multiplies by 4.
TriangleMesh random_closed_blob(Rng& rng, int subdivisions, double radius, double roughness, const Vec3& center);

// An axis-aligned box as a closed, outward-oriented 12-triangle mesh.
TriangleMesh box_mesh(const Vec3& min, const Vec3& max);

// A closed, outward-oriented prism over a regular n-gon about z, z in [0, length]: a polyhedral
// cylinder.
TriangleMesh cylinder_mesh(double radius, double length, int sides);

// A closed, outward-oriented prism over a counter-clockwise profile in (x, y), z in [0, length];
// the cap triangles index the profile (counter-clockwise seen from +z).
TriangleMesh prism_mesh(const std::vector<Vec2>& profile, const std::vector<std::array<std::uint32_t, 3>>& cap, double length);

// A U-channel: the 10 x 10 square less the slot [2, 8] x [2, 10], 20 long in z — the union of
// the boxes [0,10]x[0,2], [0,2]x[2,10] and [8,10]x[2,10].
TriangleMesh u_channel_mesh();

// A soup of n random triangles of edge length up to size inside a cube of half side extent.
TriangleMesh random_soup(Rng& rng, int n, double extent, double size);

// A uniformly random rotation with a translation uniform in [-range, range]^3.
RigidTransform random_pose(Rng& rng, double range);

std::shared_ptr<const TriangleMesh> share(TriangleMesh mesh);

// Path of a file in ../shared/data.
std::string shared_data(const std::string& relative);

}  // namespace gk::testing
