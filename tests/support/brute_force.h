// All-pairs oracles: every triangle of A against every triangle of B, no tree involved.
// B's triangles are moved into A's frame with the same relative transform the queries use.
#pragma once

#include "kernel/core/rigid_transform.h"
#include "kernel/mesh/triangle_mesh.h"

#include <set>
#include <utility>

namespace gk::testing {

using PairSet = std::set<std::pair<std::uint32_t, std::uint32_t>>;

PairSet brute_force_contacts(const TriangleMesh& a, const RigidTransform& pose_a, const TriangleMesh& b,
                             const RigidTransform& pose_b);

double brute_force_distance(const TriangleMesh& a, const RigidTransform& pose_a, const TriangleMesh& b,
                            const RigidTransform& pose_b);

PairSet brute_force_pairs_within(const TriangleMesh& a, const RigidTransform& pose_a, const TriangleMesh& b,
                                 const RigidTransform& pose_b, double delta_mm);

// Is some triangle pair of the two within delta_mm (an intersecting pair is at 0)? All pairs,
// except those whose triangles' boxes are farther apart than delta_mm along an axis (exactly
// dropped: such triangles cannot be within delta_mm) - fast enough for every frame of a path.
bool brute_force_any_within(const TriangleMesh& a, const RigidTransform& pose_a, const TriangleMesh& b,
                            const RigidTransform& pose_b, double delta_mm);

// The same answers as brute_force_distance and brute_force_pairs_within for meshes of thousands of
// triangles: every pair, except those whose triangles' boxes are apart along an axis by more than
// the best distance so far (or delta_mm), with a relative margin of 1e-12 for the subtraction's
// rounding - such a pair cannot be nearer. No tree involved.
double brute_force_distance_pruned(const TriangleMesh& a, const RigidTransform& pose_a, const TriangleMesh& b,
                                   const RigidTransform& pose_b);
// The same set as brute_force_contacts: pairs whose triangles' boxes do not overlap (compared
// exactly on the same doubles) cannot meet and are skipped.
PairSet brute_force_contacts_pruned(const TriangleMesh& a, const RigidTransform& pose_a, const TriangleMesh& b,
                                    const RigidTransform& pose_b);
PairSet brute_force_pairs_within_pruned(const TriangleMesh& a, const RigidTransform& pose_a, const TriangleMesh& b,
                                        const RigidTransform& pose_b, double delta_mm);

}  // namespace gk::testing
