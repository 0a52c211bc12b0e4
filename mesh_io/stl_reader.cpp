// STL, binary or ASCII. Binary when the byte count is exactly 84 + 50 n for the n its header
// declares (its float32 coordinates are taken exactly); otherwise ASCII "solid ... facet ... outer
// loop, vertex x y z (three times), endloop, endfacet ... endsolid", numbers parsed as written.
#include "mesh_io/format_readers.h"
#include "mesh_io/text_scanner.h"

#include <cstring>

namespace gk::mesh_io {
namespace {

Result<RawMesh> read_binary(std::string_view bytes, std::uint32_t count) {
  RawMesh mesh;
  mesh.vertices.reserve(3u * count);
  mesh.faces.reserve(count);
  for (std::uint32_t f = 0; f < count; ++f) {
    const char* facet = bytes.data() + 84 + 50u * f;
    for (int k = 0; k < 3; ++k) {
      float xyz[3];
      std::memcpy(xyz, facet + 12 + 12 * k, sizeof xyz);
      const Vec3 v(static_cast<double>(xyz[0]), static_cast<double>(xyz[1]), static_cast<double>(xyz[2]));
      if (!v.allFinite()) return invalid_argument("facets[" + std::to_string(f) + "].vertices[" + std::to_string(k) + "]",
                                                  "coordinate is not finite");
      mesh.vertices.push_back(v);
    }
    const auto base = static_cast<std::uint32_t>(3u * f);
    mesh.faces.push_back({base, base + 1, base + 2});
  }
  return mesh;
}

Result<RawMesh> read_ascii(std::string_view bytes) {
  RawMesh mesh;
  TextScanner scanner(bytes);
  std::string_view line;
  int in_facet = -1;  // vertices read in the current facet; -1 outside one
  bool solid = false;
  while (scanner.next_line(line)) {
    const std::string_view keyword = next_word(line);
    if (keyword == "solid") {
      solid = true;
    } else if (keyword == "facet") {
      if (in_facet >= 0) return line_error(scanner.line_number(), "facet inside a facet");
      in_facet = 0;
    } else if (keyword == "vertex") {
      if (in_facet < 0 || in_facet >= 3) return line_error(scanner.line_number(), "a facet has exactly three vertices");
      double xyz[3];
      for (double& c : xyz)
        if (!parse_double(next_word(line), c)) return line_error(scanner.line_number(), "a vertex needs three finite coordinates");
      if (!at_end(line)) return line_error(scanner.line_number(), "a vertex has exactly three coordinates");
      mesh.vertices.emplace_back(xyz[0], xyz[1], xyz[2]);
      ++in_facet;
    } else if (keyword == "endfacet") {
      if (in_facet != 3) return line_error(scanner.line_number(), "a facet has exactly three vertices");
      const auto base = static_cast<std::uint32_t>(mesh.vertices.size() - 3);
      mesh.faces.push_back({base, base + 1, base + 2});
      in_facet = -1;
    } else if (keyword == "outer" || keyword == "endloop" || keyword == "endsolid" || keyword.empty()) {
      continue;
    } else {
      return line_error(scanner.line_number(), "unexpected '" + std::string(keyword) + "' in an ASCII STL");
    }
  }
  if (!solid) return invalid_argument("header", "neither a binary STL (84 + 50 n bytes) nor an ASCII one ('solid')");
  if (in_facet >= 0) return invalid_argument("facets", "the file ends inside a facet");
  return mesh;
}

}  // namespace

Result<RawMesh> read_stl(std::string_view bytes) {
  if (bytes.size() >= 84) {
    std::uint32_t count = 0;
    std::memcpy(&count, bytes.data() + 80, sizeof count);
    if (bytes.size() == 84 + 50ull * count) return read_binary(bytes, count);
  }
  std::string_view head = bytes.substr(0, 512);
  if (next_word(head) == "solid") return read_ascii(bytes);
  if (bytes.size() >= 84) {
    std::uint32_t count = 0;
    std::memcpy(&count, bytes.data() + 80, sizeof count);
    return invalid_argument("header", "binary STL declares " + std::to_string(count) + " facets (" +
                                          std::to_string(84 + 50ull * count) + " bytes) but the file has " +
                                          std::to_string(bytes.size()));
  }
  return invalid_argument("header", "too short for an STL file");
}

}  // namespace gk::mesh_io
