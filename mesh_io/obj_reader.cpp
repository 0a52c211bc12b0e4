// OBJ: "v x y z" vertices and "f a b c ..." polygons (a, a/t, a//n or a/t/n; negative indices count
// back from the last vertex); every other statement (normals, texture coordinates, groups,
// materials, mtllib) carries no geometry and is skipped without opening anything.
#include "mesh_io/format_readers.h"
#include "mesh_io/text_scanner.h"

#include <array>

namespace gk::mesh_io {

Result<RawMesh> read_obj(std::string_view bytes) {
  RawMesh mesh;
  TextScanner scanner(bytes);
  std::string_view line;
  std::vector<long long> polygon;
  // Faces are kept with their 1-based indices and checked once every vertex is known.
  std::vector<std::size_t> face_line;
  std::vector<std::array<long long, 3>> pending;
  while (scanner.next_line(line)) {
    const std::string_view keyword = next_word(line);
    if (keyword == "v") {
      double xyz[3];
      for (double& c : xyz)
        if (!parse_double(next_word(line), c))
          return line_error(scanner.line_number(), "a vertex needs three finite coordinates");
      mesh.vertices.emplace_back(xyz[0], xyz[1], xyz[2]);
    } else if (keyword == "f") {
      polygon.clear();
      for (std::string_view word = next_word(line); !word.empty(); word = next_word(line)) {
        long long index = 0;
        if (!parse_integer(word.substr(0, word.find('/')), index) || index == 0)
          return line_error(scanner.line_number(), "a face index must be a non-zero integer");
        // Relative indices count back from the vertices read so far.
        if (index < 0) index += static_cast<long long>(mesh.vertices.size()) + 1;
        polygon.push_back(index);
      }
      if (polygon.size() < 3) return line_error(scanner.line_number(), "a face needs at least three vertices");
      if (polygon.size() > 65536) return line_error(scanner.line_number(), "a face of more than 65,536 vertices");
      for (std::size_t k = 1; k + 1 < polygon.size(); ++k) {
        pending.push_back({polygon[0], polygon[k], polygon[k + 1]});
        face_line.push_back(scanner.line_number());
      }
    }
  }
  const auto count = static_cast<long long>(mesh.vertices.size());
  for (std::size_t f = 0; f < pending.size(); ++f) {
    TriangleMesh::Face face;
    for (int k = 0; k < 3; ++k) {
      if (pending[f][k] < 1 || pending[f][k] > count)
        return line_error(face_line[f], "face index " + std::to_string(pending[f][k]) + " is outside the " +
                                            std::to_string(count) + " vertices");
      face[k] = static_cast<std::uint32_t>(pending[f][k] - 1);
    }
    mesh.faces.push_back(face);
  }
  return mesh;
}

}  // namespace gk::mesh_io
