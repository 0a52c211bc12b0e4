// Reads triangle meshes from files with Assimp (a maintained reader, not a parser of our own).
#pragma once

#include "kernel/status.h"
#include "kernel/triangle_mesh.h"

#include <string>

namespace gk::mesh_io {

struct ReadOptions {
  MeshBuildOptions build;
  // Corners closer than this are merged into one vertex (STL stores a soup of triangles). [mm]
  bool merge_identical_vertices = true;
};

// Every mesh in the file, merged into one, in the file's units (taken as mm). Errors name the file
// and what was wrong (missing, unknown format, no triangles, invalid geometry).
Result<TriangleMesh> read_mesh_file(const std::string& path, const ReadOptions& options = {});

// The same from bytes already in memory; format_hint is the file extension ("stl", "obj", ...).
Result<TriangleMesh> read_mesh_bytes(const std::string& bytes, const std::string& format_hint,
                                     const ReadOptions& options = {});

}  // namespace gk::mesh_io
