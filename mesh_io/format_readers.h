// Our own readers for the simple mesh formats, so that coordinates arrive exactly as written:
// text numbers (OBJ, OFF, ASCII PLY, ASCII STL) are parsed straight to the nearest double, binary
// float32/float64 values (binary STL, binary PLY) are taken exactly. No file is opened beyond the
// bytes given (an OBJ's mtllib is ignored), every count and index is checked, and errors name the
// line or element. glTF positions are float32 by definition: taken exactly, placed by node
// transforms composed in double; its buffers must be inside the file (data: URIs or a .glb).
#pragma once

#include "kernel/core/status.h"
#include "kernel/mesh/triangle_mesh.h"

#include <string_view>
#include <vector>

namespace gk::mesh_io {

// A mesh as read: vertices and triangles (larger polygons cut into triangles that cover them as
// written: mesh_io/polygon_triangulation), indices checked against the vertices.
struct RawMesh {
  std::vector<Vec3> vertices;
  std::vector<TriangleMesh::Face> faces;
};

Result<RawMesh> read_obj(std::string_view bytes);
Result<RawMesh> read_off(std::string_view bytes);
Result<RawMesh> read_ply(std::string_view bytes);
Result<RawMesh> read_stl(std::string_view bytes);  // binary or ASCII, told apart by the byte count
Result<RawMesh> read_gltf(std::string_view bytes);  // .gltf (JSON) or .glb (binary container)

}  // namespace gk::mesh_io
