// OBJ: "v x y z" vertices and "f a b c ..." polygons (a, a/t, a//n or a/t/n; negative indices count
// back from the last vertex); every other statement (normals, texture coordinates, groups,
// materials, mtllib) carries no geometry and is skipped without opening anything.
#include "mesh_io/format_readers.h"
#include "mesh_io/polygon_triangulation.h"
#include "mesh_io/text_scanner.h"

#include <cstdint>

namespace gk::mesh_io {

Result<RawMesh> read_obj(std::string_view bytes) {
  RawMesh mesh;
  TextScanner scanner(bytes);
  std::string_view line;
  std::vector<long long> polygon;
  // Faces are kept with their 1-based indices (one flat list) and checked once every vertex is known.
  std::vector<long long> indices;
  std::vector<std::size_t> face_start, face_line;
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
      face_start.push_back(indices.size());
      face_line.push_back(scanner.line_number());
      indices.insert(indices.end(), polygon.begin(), polygon.end());
    }
  }
  face_start.push_back(indices.size());
  const auto count = static_cast<long long>(mesh.vertices.size());
  TriangulationBudget budget;
  std::vector<std::uint32_t> face;
  for (std::size_t f = 0; f + 1 < face_start.size(); ++f) {
    face.clear();
    for (std::size_t k = face_start[f]; k < face_start[f + 1]; ++k) {
      if (indices[k] < 1 || indices[k] > count)
        return line_error(face_line[f], "face index " + std::to_string(indices[k]) + " is outside the " +
                                            std::to_string(count) + " vertices");
      face.push_back(static_cast<std::uint32_t>(indices[k] - 1));
    }
    auto cut = append_polygon_triangles(mesh.vertices, face, mesh.faces, budget);
    if (!cut.ok()) return line_error(face_line[f], cut.error().message);
  }
  return mesh;
}

}  // namespace gk::mesh_io
