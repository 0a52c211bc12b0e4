// An approximate convex decomposition of a triangle surface: the surface is split into patches
// until each patch is nearly convex, and each patch is replaced by its convex hull. (V-HACD is not
// packaged; this is the simple top-down form of the same idea.) A patch's concavity is the farthest
// any of its vertices lies inside its hull: 0 for a convex patch, whose vertices are all on it.
#pragma once

#include "kernel/core/aabb.h"
#include "kernel/mesh/convex_hull.h"
#include "kernel/core/rigid_transform.h"
#include "kernel/core/status.h"
#include "kernel/core/stop_token.h"
#include "kernel/mesh/triangle_mesh.h"

#include <vector>

namespace gk {

// A convex polytope as the separating-axis test needs it: corners (for support values), face
// normals and edges (for candidate axes). A flat patch is a polygon: one normal, its edges.
struct ConvexPiece {
  std::vector<Vec3> corners;  // in the mesh's frame
  std::vector<Vec3> face_normals;
  std::vector<std::array<std::uint32_t, 2>> edges;  // indices into corners
  Aabb bounds;                // of the corners
  double concavity_mm = 0.0;  // the farthest patch vertex inside the hull
};

struct DecompositionOptions {
  double max_concavity_mm = 1.0;  // split patches deeper than this ...
  int max_pieces = 64;            // ... until there are this many
  // Only triangles whose box meets this region take part (the rest cannot matter to a query
  // confined to it); an empty region means the whole mesh.
  Aabb region;
  // Asked between splits; when it says stop, the pieces so far are returned (coarser, still a
  // cover of the mesh).
  const StopToken* stop = nullptr;
};

struct ConvexDecomposition {
  std::vector<ConvexPiece> pieces;
  double max_concavity_mm = 0.0;  // over all pieces
};

// Every triangle in the region belongs to one patch, so the pieces' union covers that part of the
// surface. A flat patch becomes a flat piece (its hull in the plane).
Result<ConvexDecomposition> approximate_convex_decomposition(const TriangleMesh& mesh,
                                                             const DecompositionOptions& options = {});

// Two convex polytopes (corners in world coordinates once posed): the smallest translation of B
// that separates them, found by the separating-axis theorem over every face normal of both and
// every cross product of an edge of each. For convex polytopes that minimum is the exact
// penetration depth (it is the Minkowski difference's nearest facet, which EPA approaches
// iteratively). depth_mm <= 0 means they are apart along `direction` already.
struct ConvexSeparation {
  Vec3 direction = Vec3::Zero();  // unit; move B by depth_mm along it
  double depth_mm = 0.0;
  bool edge_axes_tested = false;  // false when the edge pairs were too many to test (then an upper bound)
};
ConvexSeparation convex_penetration(const ConvexPiece& a, const RigidTransform& pose_a, const ConvexPiece& b,
                                    const RigidTransform& pose_b, std::size_t max_edge_pairs = 200000);

// The piece of a convex hull (corners, face normals, edges); concavity 0.
ConvexPiece convex_piece_of(const HullPolytope& hull);

}  // namespace gk
