// TriangleMesh as bytes (see append_bytes / read_bytes in triangle_mesh.h). Native byte order: the
// files are a cache of this machine kind, named and checked by kernel/bvh/mesh_pack. Every array
// starts, and the whole ends, at a multiple of 8 bytes from the start, so a reader whose bytes
// start 8-aligned (a mapped file) copies the arrays element by element without zeroing them first.
#include "kernel/mesh/triangle_mesh.h"

#include "kernel/core/tolerances.h"

#include <cmath>
#include <cstring>

namespace gk {
namespace {

template <typename T>
void put(std::string& out, const T& value) {
  out.append(reinterpret_cast<const char*>(&value), sizeof(T));
}

void pad_to_8(std::string& out, std::size_t start) { out.append((8 - (out.size() - start) % 8) % 8, '\0'); }

template <typename T>
void put_array(std::string& out, std::size_t start, const std::vector<T>& values) {
  out.append(reinterpret_cast<const char*>(values.data()), values.size() * sizeof(T));
  pad_to_8(out, start);
}

template <typename T>
bool take(std::string_view& in, T& value) {
  if (in.size() < sizeof(T)) return false;
  std::memcpy(&value, in.data(), sizeof(T));
  in.remove_prefix(sizeof(T));
  return true;
}

// The array and its padding. Aligned input is copied as T (no zeroing pass); other input through memcpy.
template <typename T>
bool take_array(std::string_view& in, std::uint64_t count, std::vector<T>& values) {
  if (count > in.size() / sizeof(T)) return false;
  const std::size_t n = static_cast<std::size_t>(count), size = n * sizeof(T), padded = (size + 7) / 8 * 8;
  if (padded > in.size()) return false;
  if (reinterpret_cast<std::uintptr_t>(in.data()) % alignof(T) == 0) {
    const T* first = reinterpret_cast<const T*>(in.data());
    values.assign(first, first + n);
  } else {
    values.resize(n);
    // Vec3 is three packed doubles (geometry_types.h); copied as bytes, as they were written.
    std::memcpy(static_cast<void*>(values.data()), in.data(), size);
  }
  in.remove_prefix(padded);
  return true;
}

}  // namespace

TriangleMesh TriangleMesh::in_face_order(const std::vector<std::uint32_t>& order) const {
  constexpr std::uint32_t kUnset = 0xffffffffu;
  std::vector<std::uint32_t> renumbered(vertices_.size(), kUnset);
  TriangleMesh out;
  out.vertices_.reserve(vertices_.size());
  out.faces_.reserve(order.size());
  out.degenerate_.reserve(order.size());
  for (std::uint32_t t : order) {
    Face f = faces_[t];
    for (std::uint32_t& v : f) {
      if (renumbered[v] == kUnset) {
        renumbered[v] = static_cast<std::uint32_t>(out.vertices_.size());
        out.vertices_.push_back(vertices_[v]);
      }
      v = renumbered[v];
    }
    out.faces_.push_back(f);
    out.degenerate_.push_back(degenerate_[t]);
    if (degenerate_[t]) out.report_.zero_area_triangles.push_back(static_cast<std::uint32_t>(out.faces_.size() - 1));
  }
  out.degenerate_count_ = degenerate_count_;
  out.report_.closed = report_.closed;
  out.report_.consistently_oriented = report_.consistently_oriented;
  out.report_.boundary_edges = report_.boundary_edges;
  out.report_.non_manifold_edges = report_.non_manifold_edges;
  for (std::uint32_t seed : body_seeds_) out.body_seeds_.push_back(renumbered[seed]);  // a seed is a used corner
  out.bounds_ = bounds_;
  return out;
}

void TriangleMesh::append_bytes(std::string& out) const {
  const std::size_t start = out.size();
  put(out, static_cast<std::uint64_t>(vertices_.size()));
  put(out, static_cast<std::uint64_t>(faces_.size()));
  put(out, static_cast<std::uint64_t>(report_.zero_area_triangles.size()));
  put(out, static_cast<std::uint64_t>(body_seeds_.size()));
  put(out, static_cast<std::uint64_t>(report_.dropped_triangles));
  put(out, static_cast<std::uint64_t>(report_.boundary_edges));
  put(out, static_cast<std::uint64_t>(report_.non_manifold_edges));
  put(out, static_cast<std::uint8_t>(report_.closed ? 1 : 0));
  put(out, static_cast<std::uint8_t>(report_.consistently_oriented ? 1 : 0));
  pad_to_8(out, start);
  put_array(out, start, vertices_);
  put_array(out, start, faces_);
  put_array(out, start, degenerate_);
  put_array(out, start, report_.zero_area_triangles);
  put_array(out, start, body_seeds_);
}

Result<TriangleMesh> TriangleMesh::read_bytes(std::string_view& in) {
  auto bad = [](const std::string& why) { return invalid_argument("mesh bytes", why); };
  std::uint64_t n_vertices = 0, n_faces = 0, n_zero = 0, n_seeds = 0, dropped = 0, boundary = 0, non_manifold = 0;
  std::uint8_t closed = 0, oriented = 0;
  if (!take(in, n_vertices) || !take(in, n_faces) || !take(in, n_zero) || !take(in, n_seeds) || !take(in, dropped) ||
      !take(in, boundary) || !take(in, non_manifold) || !take(in, closed) || !take(in, oriented) || in.size() < 6)
    return bad("truncated header");
  in.remove_prefix(6);  // the header's padding to 8 bytes
  if (n_vertices == 0 || n_faces == 0 || n_vertices > 0xffffffffull || n_seeds == 0 || n_seeds > n_faces || closed > 1 ||
      oriented > 1)
    return bad("impossible counts");
  TriangleMesh mesh;
  if (!take_array(in, n_vertices, mesh.vertices_) || !take_array(in, n_faces, mesh.faces_) ||
      !take_array(in, n_faces, mesh.degenerate_) || !take_array(in, n_zero, mesh.report_.zero_area_triangles) ||
      !take_array(in, n_seeds, mesh.body_seeds_))
    return bad("truncated arrays");
  for (const Vec3& v : mesh.vertices_)
    for (int a = 0; a < 3; ++a)
      if (!(std::fabs(v[a]) <= tolerances::kMaxCoordinateMm)) return bad("a coordinate is not finite or out of range");
  for (const Face& f : mesh.faces_)
    for (std::uint32_t v : f) {
      if (v >= n_vertices) return bad("a vertex index is out of range");
      mesh.bounds_.extend(mesh.vertices_[v]);
    }
  for (std::uint8_t d : mesh.degenerate_) {
    if (d > 1) return bad("a degeneracy flag is neither 0 nor 1");
    mesh.degenerate_count_ += d;
  }
  for (std::uint32_t s : mesh.body_seeds_)
    if (s >= n_vertices) return bad("a body seed is out of range");
  mesh.report_.dropped_triangles = static_cast<std::size_t>(dropped);
  mesh.report_.boundary_edges = static_cast<std::size_t>(boundary);
  mesh.report_.non_manifold_edges = static_cast<std::size_t>(non_manifold);
  mesh.report_.closed = closed != 0;
  mesh.report_.consistently_oriented = oriented != 0;
  return mesh;
}

}  // namespace gk
