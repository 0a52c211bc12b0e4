// Reads triangle meshes from files: STL, OBJ, OFF and PLY by our own small readers, so that
// coordinates arrive exactly as written (Assimp reads them in single precision: at 5e4 mm that
// rounds to 0.004 mm), nothing outside the bytes is opened, and every count and index is checked;
// glTF with Assimp (its data are float32 by definition: put a factory offset in the pose).
#pragma once

#include "kernel/core/status.h"
#include "kernel/mesh/triangle_mesh.h"

#include <string>

namespace gk::mesh_io {

struct ReadOptions {
  MeshBuildOptions build;
  // Exactly equal corners are merged into one vertex (STL stores a soup of triangles).
  bool merge_identical_vertices = true;
};

// Every mesh in the file, merged into one, in the file's units (taken as mm). Errors name the file
// and what was wrong (missing, unknown format, no triangles, invalid geometry).
Result<TriangleMesh> read_mesh_file(const std::string& path, const ReadOptions& options = {});

// The same from bytes already in memory; format_hint is the file extension ("stl", "obj", ...).
Result<TriangleMesh> read_mesh_bytes(const std::string& bytes, const std::string& format_hint,
                                     const ReadOptions& options = {});

}  // namespace gk::mesh_io
