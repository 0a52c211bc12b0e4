#include "tests/support/file_text.h"

#include <openssl/sha.h>

#include <cstdio>

namespace gk::testing {

std::string obj_text(const TriangleMesh& mesh) {
  std::string out;
  char line[128];
  for (const Vec3& v : mesh.vertices()) {
    std::snprintf(line, sizeof line, "v %.17g %.17g %.17g\n", v.x(), v.y(), v.z());
    out += line;
  }
  for (const auto& f : mesh.faces()) {
    std::snprintf(line, sizeof line, "f %u %u %u\n", f[0] + 1, f[1] + 1, f[2] + 1);
    out += line;
  }
  return out;
}

std::string sha256_hex(const std::string& bytes) {
  unsigned char digest[SHA256_DIGEST_LENGTH];
  SHA256(reinterpret_cast<const unsigned char*>(bytes.data()), bytes.size(), digest);
  std::string hex;
  char two[3];
  for (unsigned char b : digest) {
    std::snprintf(two, sizeof two, "%02x", b);
    hex += two;
  }
  return hex;
}

}  // namespace gk::testing
