// What tests hand to an upload: a mesh as OBJ text at full precision, and the SHA-256 an upload
// declares.
#pragma once

#include "kernel/mesh/triangle_mesh.h"

#include <string>

namespace gk::testing {

// Every coordinate to 17 significant digits: a reader in double gets exactly this mesh.
std::string obj_text(const TriangleMesh& mesh);

// Lower-case hex of the SHA-256 of bytes.
std::string sha256_hex(const std::string& bytes);

}  // namespace gk::testing
