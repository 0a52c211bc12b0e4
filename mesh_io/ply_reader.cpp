// PLY, ASCII or binary (either byte order): the header's elements and properties, then the data.
// The vertex element's x, y, z (any numeric type: float32 and float64 values are taken exactly)
// and the face element's index list are read; every other element or property is skipped by
// its declared size.
#include "mesh_io/format_readers.h"
#include "mesh_io/polygon_triangulation.h"
#include "mesh_io/text_scanner.h"

#include <cstring>
#include <optional>

namespace gk::mesh_io {
namespace {

enum class Type { kInt8, kUInt8, kInt16, kUInt16, kInt32, kUInt32, kFloat32, kFloat64 };

std::optional<Type> type_named(std::string_view name) {
  if (name == "char" || name == "int8") return Type::kInt8;
  if (name == "uchar" || name == "uint8") return Type::kUInt8;
  if (name == "short" || name == "int16") return Type::kInt16;
  if (name == "ushort" || name == "uint16") return Type::kUInt16;
  if (name == "int" || name == "int32") return Type::kInt32;
  if (name == "uint" || name == "uint32") return Type::kUInt32;
  if (name == "float" || name == "float32") return Type::kFloat32;
  if (name == "double" || name == "float64") return Type::kFloat64;
  return std::nullopt;
}

std::size_t size_of(Type t) {
  switch (t) {
    case Type::kInt8:
    case Type::kUInt8: return 1;
    case Type::kInt16:
    case Type::kUInt16: return 2;
    case Type::kInt32:
    case Type::kUInt32:
    case Type::kFloat32: return 4;
    case Type::kFloat64: return 8;
  }
  return 0;
}

struct Property {
  std::string name;
  Type type = Type::kFloat32;
  bool is_list = false;
  Type count_type = Type::kUInt8;
};

struct Element {
  std::string name;
  long long count = 0;
  std::vector<Property> properties;
};

// Binary values: raw bytes in the file's order, widened to double exactly.
class BinaryCursor {
 public:
  BinaryCursor(std::string_view data, bool big_endian) : data_(data), big_endian_(big_endian) {}
  bool read(Type t, double& out) {
    const std::size_t n = size_of(t);
    if (pos_ + n > data_.size()) return false;
    unsigned char raw[8];
    std::memcpy(raw, data_.data() + pos_, n);
    pos_ += n;
    const bool host_big = false;  // the project targets little-endian machines (x86-64, arm64)
    if (big_endian_ != host_big)
      for (std::size_t i = 0; i < n / 2; ++i) std::swap(raw[i], raw[n - 1 - i]);
    switch (t) {
      case Type::kInt8: out = static_cast<std::int8_t>(raw[0]); break;
      case Type::kUInt8: out = raw[0]; break;
      case Type::kInt16: out = load<std::int16_t>(raw); break;
      case Type::kUInt16: out = load<std::uint16_t>(raw); break;
      case Type::kInt32: out = load<std::int32_t>(raw); break;
      case Type::kUInt32: out = load<std::uint32_t>(raw); break;
      case Type::kFloat32: out = static_cast<double>(load<float>(raw)); break;
      case Type::kFloat64: out = load<double>(raw); break;
    }
    return true;
  }

 private:
  template <class T>
  static T load(const unsigned char* raw) {
    T v;
    std::memcpy(&v, raw, sizeof(T));
    return v;
  }
  std::string_view data_;
  bool big_endian_;
  std::size_t pos_ = 0;
};

}  // namespace

Result<RawMesh> read_ply(std::string_view bytes) {
  TextScanner scanner(bytes);
  std::string_view line;
  if (!scanner.next_line(line) || line != "ply") return invalid_argument("header", "a PLY file starts with 'ply'");
  std::string format;
  std::vector<Element> elements;
  bool ended = false;
  while (!ended && scanner.next_line(line)) {
    const std::string_view keyword = next_word(line);
    if (keyword == "format") {
      format = std::string(next_word(line));
    } else if (keyword == "element") {
      Element e;
      e.name = std::string(next_word(line));
      for (const Element& other : elements)
        if (other.name == e.name) return line_error(scanner.line_number(), "element '" + e.name + "' declared twice");
      if (!parse_integer(next_word(line), e.count) || e.count < 0)
        return line_error(scanner.line_number(), "an element needs a count");
      elements.push_back(std::move(e));
    } else if (keyword == "property") {
      if (elements.empty()) return line_error(scanner.line_number(), "a property before any element");
      Property p;
      std::string_view type = next_word(line);
      if (type == "list") {
        p.is_list = true;
        const auto count_type = type_named(next_word(line));
        if (!count_type) return line_error(scanner.line_number(), "unknown list count type");
        p.count_type = *count_type;
        type = next_word(line);
      }
      const auto t = type_named(type);
      if (!t) return line_error(scanner.line_number(), "unknown property type '" + std::string(type) + "'");
      p.type = *t;
      p.name = std::string(next_word(line));
      elements.back().properties.push_back(std::move(p));
    } else if (keyword == "end_header") {
      if (!at_end(line)) return line_error(scanner.line_number(), "end_header stands alone on its line");
      ended = true;
    } else if (keyword != "comment" && keyword != "obj_info" && !keyword.empty()) {
      return line_error(scanner.line_number(), "unknown header line '" + std::string(keyword) + "'");
    }
  }
  if (!ended) return invalid_argument("header", "no end_header");
  const bool ascii = format == "ascii";
  if (!ascii && format != "binary_little_endian" && format != "binary_big_endian")
    return invalid_argument("header.format", "must be ascii, binary_little_endian or binary_big_endian");
  for (const Element& e : elements) {
    // Every item takes at least one byte (binary) or two (text): a count beyond that cannot be honest.
    const double least = static_cast<double>(e.count) * static_cast<double>(std::max<std::size_t>(1, e.properties.size()));
    if (least > static_cast<double>(bytes.size())) return invalid_argument("element " + e.name, "count larger than the file");
  }

  RawMesh mesh;
  long long vertex_count = -1;
  std::vector<std::pair<std::string, std::vector<std::uint32_t>>> polygons;  // faces of more than 3 vertices
  BinaryCursor binary(bytes.substr(scanner.offset()), format == "binary_big_endian");
  std::vector<double> values;
  std::vector<std::vector<double>> lists;
  // PLY allows any element order: faces may come before the vertices they index.
  for (const Element& e : elements)
    if (e.name == "vertex") vertex_count = e.count;
  for (const Element& e : elements) {
    const bool is_vertex = e.name == "vertex", is_face = e.name == "face";
    int ix = -1, iy = -1, iz = -1, iface = -1;
    for (std::size_t k = 0; k < e.properties.size(); ++k) {
      const std::string& n = e.properties[k].name;
      if (is_vertex && !e.properties[k].is_list) {
        if (n == "x") ix = static_cast<int>(k);
        if (n == "y") iy = static_cast<int>(k);
        if (n == "z") iz = static_cast<int>(k);
      }
      if (is_face && e.properties[k].is_list && (n == "vertex_indices" || n == "vertex_index")) iface = static_cast<int>(k);
    }
    if (is_vertex && (ix < 0 || iy < 0 || iz < 0)) return invalid_argument("element vertex", "needs x, y and z properties");
    if (is_face && iface < 0) return invalid_argument("element face", "needs a vertex_indices list");
    const std::string where = "element " + e.name + "[";
    for (long long item = 0; item < e.count; ++item) {
      values.assign(e.properties.size(), 0.0);
      lists.assign(e.properties.size(), {});
      if (ascii) {
        if (!scanner.next_line(line)) return invalid_argument(where + std::to_string(item) + "]", "missing: the file ends early");
        for (std::size_t k = 0; k < e.properties.size(); ++k) {
          const Property& p = e.properties[k];
          long long n = 1;
          if (p.is_list && (!parse_integer(next_word(line), n) || n < 0 || n > 1000000))
            return line_error(scanner.line_number(), "a list needs a count");
          for (long long j = 0; j < n; ++j) {
            double v = 0.0;
            if (!parse_double(next_word(line), v)) return line_error(scanner.line_number(), "expected a finite number");
            if (p.is_list) lists[k].push_back(v);
            else values[k] = v;
          }
        }
        if (!at_end(line)) return line_error(scanner.line_number(), "more values than the element's properties");
      } else {
        for (std::size_t k = 0; k < e.properties.size(); ++k) {
          const Property& p = e.properties[k];
          double n = 1.0;
          if (p.is_list && (!binary.read(p.count_type, n) || !(n >= 0.0 && n <= 1000000.0 && n == std::floor(n))))
            return invalid_argument(where + std::to_string(item) + "]", "list count missing or absurd");
          for (long long j = 0; j < static_cast<long long>(n); ++j) {
            double v = 0.0;
            if (!binary.read(p.type, v)) return invalid_argument(where + std::to_string(item) + "]", "missing: the file ends early");
            if (p.is_list) lists[k].push_back(v);
            else values[k] = v;
          }
        }
      }
      if (is_vertex) {
        const Vec3 v(values[ix], values[iy], values[iz]);
        if (!v.allFinite()) return invalid_argument(where + std::to_string(item) + "]", "coordinate is not finite");
        mesh.vertices.push_back(v);
      }
      if (is_face) {
        const std::vector<double>& idx = lists[iface];
        if (idx.size() < 3) return invalid_argument(where + std::to_string(item) + "]", "a face needs at least three vertices");
        std::vector<std::uint32_t> polygon;
        for (double d : idx) {
          if (!(d >= 0.0) || d != std::floor(d) || vertex_count < 0 || d >= static_cast<double>(vertex_count))
            return invalid_argument(where + std::to_string(item) + "]", "index outside the " +
                                                                           std::to_string(std::max(0LL, vertex_count)) + " vertices");
          polygon.push_back(static_cast<std::uint32_t>(d));
        }
        // Larger polygons are cut once every vertex is known (the vertices may follow the faces).
        if (polygon.size() == 3) mesh.faces.push_back({polygon[0], polygon[1], polygon[2]});
        else polygons.push_back({where + std::to_string(item) + "]", std::move(polygon)});
      }
    }
  }
  if (static_cast<long long>(mesh.vertices.size()) != std::max(0LL, vertex_count) && !polygons.empty())
    return invalid_argument("element vertex", "fewer vertices than declared");
  TriangulationBudget budget;
  for (const auto& [name, polygon] : polygons) {
    auto cut = append_polygon_triangles(mesh.vertices, polygon, mesh.faces, budget);
    if (!cut.ok()) return invalid_argument(name, cut.error().message);
  }
  return mesh;
}

}  // namespace gk::mesh_io
