// OFF (and COFF, NOFF, ... variants): a header word, the vertex, face and edge counts, then the
// vertices (their first three numbers; colours or normals after them are skipped) and the faces
// ("n i1 ... in", 0-based). The counts must match what follows.
#include "mesh_io/format_readers.h"
#include "mesh_io/polygon_triangulation.h"
#include "mesh_io/text_scanner.h"

namespace gk::mesh_io {
namespace {

// The next line holding something, with comments removed.
bool next_content(TextScanner& scanner, std::string_view& line) {
  while (scanner.next_line(line)) {
    if (const std::size_t hash = line.find('#'); hash != std::string_view::npos) line = line.substr(0, hash);
    std::string_view probe = line;
    if (!next_word(probe).empty()) return true;
  }
  return false;
}

}  // namespace

Result<RawMesh> read_off(std::string_view bytes) {
  TextScanner scanner(bytes);
  std::string_view line;
  if (!next_content(scanner, line)) return invalid_argument("header", "empty OFF file");
  const std::string_view magic = next_word(line);
  // OFF, or with per-vertex colours (C), normals (N) or both: still three coordinates first.
  if (magic != "OFF" && magic != "COFF" && magic != "NOFF" && magic != "CNOFF")
    return line_error(scanner.line_number(), "an OFF file starts with OFF, COFF, NOFF or CNOFF");
  // The counts may follow the header word on its line, or stand on the next.
  std::string_view counts = line;
  {
    std::string_view probe = counts;
    if (next_word(probe).empty()) {
      if (!next_content(scanner, counts)) return invalid_argument("header", "no vertex and face counts");
    }
  }
  long long nv = 0, nf = 0;
  if (!parse_integer(next_word(counts), nv) || !parse_integer(next_word(counts), nf) || nv < 0 || nf < 0)
    return line_error(scanner.line_number(), "expected the vertex and face counts");
  // Each vertex or face needs at least a few bytes: a count beyond that cannot be honest.
  if (static_cast<double>(nv) * 6.0 > static_cast<double>(bytes.size()) ||
      static_cast<double>(nf) * 8.0 > static_cast<double>(bytes.size()))
    return line_error(scanner.line_number(), "declares " + std::to_string(nv) + " vertices and " + std::to_string(nf) +
                                                 " faces, more than the file can hold");
  RawMesh mesh;
  mesh.vertices.reserve(static_cast<std::size_t>(nv));
  for (long long v = 0; v < nv; ++v) {
    if (!next_content(scanner, line))
      return invalid_argument("vertices", "declares " + std::to_string(nv) + " vertices, gives " + std::to_string(v));
    double xyz[3];
    for (double& c : xyz)
      if (!parse_double(next_word(line), c)) return line_error(scanner.line_number(), "a vertex needs three finite coordinates");
    mesh.vertices.emplace_back(xyz[0], xyz[1], xyz[2]);
  }
  TriangulationBudget budget;
  for (long long f = 0; f < nf; ++f) {
    if (!next_content(scanner, line))
      return invalid_argument("faces", "declares " + std::to_string(nf) + " faces, gives " + std::to_string(f));
    long long n = 0;
    if (!parse_integer(next_word(line), n) || n < 3 || n > nv)
      return line_error(scanner.line_number(), "a face needs a vertex count of at least 3");
    std::vector<std::uint32_t> polygon;
    for (long long k = 0; k < n; ++k) {
      long long index = 0;
      if (!parse_integer(next_word(line), index) || index < 0 || index >= nv)
        return line_error(scanner.line_number(), "face index outside the " + std::to_string(nv) + " vertices");
      polygon.push_back(static_cast<std::uint32_t>(index));
    }
    auto cut = append_polygon_triangles(mesh.vertices, polygon, mesh.faces, budget);
    if (!cut.ok()) return line_error(scanner.line_number(), cut.error().message);
  }
  return mesh;
}

}  // namespace gk::mesh_io
