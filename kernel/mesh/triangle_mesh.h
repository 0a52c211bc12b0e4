// An indexed triangle mesh in double precision, validated on construction.
#pragma once

#include "kernel/core/aabb.h"
#include "kernel/core/geometry_types.h"
#include "kernel/core/status.h"

#include <cstdint>
#include <string>
#include <string_view>
#include <vector>

namespace gk {

struct MeshBuildOptions {
  // Drop the zero-area triangles whose edges are all edges of triangles with area (seam slivers);
  // otherwise (and those with an edge of their own, needles) they are kept and reported.
  bool drop_zero_area_triangles = false;
};

// What validation found that is not an error.
struct MeshReport {
  std::vector<std::uint32_t> zero_area_triangles;  // indices in the input (kept or dropped)
  std::size_t dropped_triangles = 0;
  bool closed = false;         // every edge has exactly two incident triangles
  bool consistently_oriented = false;  // ... traversed in opposite directions
  std::size_t boundary_edges = 0;       // edges with one incident triangle
  std::size_t non_manifold_edges = 0;   // edges with three or more
};

class TriangleMesh {
 public:
  using Face = std::array<std::uint32_t, 3>;

  // Validates and builds: no vertices or no triangles, NaN/inf or huge coordinates, and indices
  // out of range are errors naming the offending element.
  static Result<TriangleMesh> create(std::vector<Vec3> vertices, std::vector<Face> faces,
                                     const MeshBuildOptions& options = {});

  const std::vector<Vec3>& vertices() const { return vertices_; }
  const std::vector<Face>& faces() const { return faces_; }
  std::size_t triangle_count() const { return faces_.size(); }
  Triangle triangle(std::size_t i) const {
    const Face& f = faces_[i];
    return {vertices_[f[0]], vertices_[f[1]], vertices_[f[2]]};
  }
  // Exactly degenerate (collinear corners): such triangles need special care in exact tests.
  bool is_degenerate(std::size_t i) const { return degenerate_[i] != 0; }
  bool has_degenerate_triangles() const { return degenerate_count_ > 0; }

  const MeshReport& report() const { return report_; }
  // One vertex of every connected body (triangles joined through shared vertices), in order of
  // first appearance: containment tests need a point of each body, not of the first only.
  const std::vector<std::uint32_t>& body_seeds() const { return body_seeds_; }
  bool is_closed_oriented() const { return report_.closed && report_.consistently_oriented; }

  Aabb bounds() const { return bounds_; }
  double area() const;
  // Enclosed volume by the divergence theorem; meaningful only when is_closed_oriented().
  // Positive when the triangles wind counter-clockwise seen from outside.
  double signed_volume() const;

  // The same mesh with its triangles in `order` (a permutation of the triangle indices) and its
  // vertices renumbered in order of first use (unused ones dropped); the analysis is carried over,
  // not redone (zero-area triangles listed by their new indices).
  TriangleMesh in_face_order(const std::vector<std::uint32_t>& order) const;

  // The mesh with what validation found, appended as bytes, and read back without analysing it
  // again: for checksummed files of our own (kernel/bvh/mesh_pack). Reading checks the counts, the
  // coordinates and every index, so no bytes make a mesh that reads outside its arrays; the stored
  // topology report and degeneracy flags are taken as written. `in` is advanced past the mesh.
  void append_bytes(std::string& out) const;
  static Result<TriangleMesh> read_bytes(std::string_view& in);

  // Moves the vertices (same count) keeping the topology, for refit after deformation.
  Result<bool> set_vertices(std::vector<Vec3> vertices);

 private:
  TriangleMesh() = default;
  void analyse_topology();
  void compute_bounds_and_degeneracy();

  std::vector<Vec3> vertices_;
  std::vector<Face> faces_;
  std::vector<std::uint8_t> degenerate_;
  std::size_t degenerate_count_ = 0;
  MeshReport report_;
  std::vector<std::uint32_t> body_seeds_;
  Aabb bounds_;
};

}  // namespace gk
