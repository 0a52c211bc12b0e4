#include "occt_adapters/shape_mesher.h"

#include "occt_adapters/occt_errors.h"
#include "occt_adapters/shape_impl.h"
#include "kernel/core/tolerances.h"

#include <BRepBuilderAPI_Copy.hxx>
#include <BRepMesh_IncrementalMesh.hxx>
#include <BRepAdaptor_Surface.hxx>
#include <BRep_Tool.hxx>
#include <Poly_Triangulation.hxx>
#include <TopExp.hxx>
#include <TopExp_Explorer.hxx>
#include <TopLoc_Location.hxx>
#include <TopTools_IndexedMapOfShape.hxx>
#include <TopoDS.hxx>
#include <TopoDS_Face.hxx>

#include <array>
#include <cmath>
#include <map>
#include <string>

namespace gk::occt {

namespace {

// How far a face's triangles stray from its surface, measured: at each triangle's edge midpoints
// and centroid, the surface at the interpolated (u, v) against the triangle's point there, along
// the triangle's normal (across it the parametrisation's own stretch, large near a sphere's poles,
// is no gap). Where the surface is its second-order expansion over a triangle, that gap is a
// quadratic in the barycentric b vanishing at the corners, sum over edges ij of c_ij b_i b_j,
// whose value at edge ij's midpoint is c_ij / 4; its largest size anywhere is then at most
// (max |c_ij|) / 3, 4/3 of the largest midpoint gap. OCCT's own control leaves a sphere's
// triangles up to about twice the asked deflection from it (0.1 mm at 0.05 mm, measured).
double tessellation_deviation(const TopoDS_Face& face, const Poly_Triangulation& tri) {
  if (!tri.HasUVNodes()) return 0.0;
  const BRepAdaptor_Surface surface(face, false);
  if (surface.GetType() == GeomAbs_Plane) return 0.0;
  double largest_mid = 0.0, largest_centroid = 0.0;
  for (int t = 1; t <= tri.NbTriangles(); ++t) {
    int n[3];
    tri.Triangle(t).Get(n[0], n[1], n[2]);
    gp_Pnt2d uv[3];
    gp_XYZ p[3];
    for (int k = 0; k < 3; ++k) {
      uv[k] = tri.UVNode(n[k]);
      p[k] = tri.Node(n[k]).XYZ();
    }
    gp_XYZ normal = (p[1] - p[0]).Crossed(p[2] - p[0]);
    if (!(normal.Modulus() > 0.0)) continue;  // no plane: dropped from the mesh (shape_mesher)
    normal /= normal.Modulus();
    const auto gap = [&](double b0, double b1, double b2) {
      const gp_Pnt on_surface = surface.Value(b0 * uv[0].X() + b1 * uv[1].X() + b2 * uv[2].X(), b0 * uv[0].Y() + b1 * uv[1].Y() + b2 * uv[2].Y());
      return std::abs(normal.Dot(on_surface.XYZ() - (b0 * p[0] + b1 * p[1] + b2 * p[2])));
    };
    largest_mid = std::max({largest_mid, gap(0.5, 0.5, 0.0), gap(0.0, 0.5, 0.5), gap(0.5, 0.0, 0.5)});
    largest_centroid = std::max(largest_centroid, gap(1.0 / 3.0, 1.0 / 3.0, 1.0 / 3.0));
  }
  return std::max(4.0 / 3.0 * largest_mid, largest_centroid);
}

}  // namespace

Result<MeshedShape> mesh_shape(const Shape& shape, double deflection_mm, double angular_deg) {
  if (shape.is_null()) return invalid_argument("shape", "is empty");
  if (!(deflection_mm > 0.0) || !std::isfinite(deflection_mm))
    return invalid_argument("deflection_mm", "must be a positive length");
  if (!(angular_deg > 0.0 && angular_deg <= 90.0)) return invalid_argument("angular_deg", "must be in (0, 90]");
  std::vector<Vec3> vertices;
  std::vector<TriangleMesh::Face> faces;
  std::vector<int> face_ids;
  double deviation = 0.0;
  auto ran = guarded("shape", "meshing", [&] {
    const TopoDS_Shape copy = BRepBuilderAPI_Copy(shape.impl().shape, true, false).Shape();
    BRepMesh_IncrementalMesh mesher(copy, deflection_mm, false, angular_deg * M_PI / 180.0, false);
    TopTools_IndexedMapOfShape face_map;
    TopExp::MapShapes(copy, TopAbs_FACE, face_map);
    // Vertices are merged within one solid only: solids of an assembly that share an edge or a face
    // stay separate closed bodies (merged, their shared edges would have four triangles and no
    // body would be closed, so nothing could be found inside them). Faces outside any solid come
    // last, merged among themselves.
    std::vector<std::vector<std::pair<int, TopoDS_Face>>> groups;
    std::vector<char> in_solid(face_map.Extent() + 1, 0);
    for (TopExp_Explorer solid(copy, TopAbs_SOLID); solid.More(); solid.Next()) {
      TopTools_IndexedMapOfShape solid_faces;
      TopExp::MapShapes(solid.Current(), TopAbs_FACE, solid_faces);
      std::vector<std::pair<int, TopoDS_Face>> group;
      for (int i = 1; i <= solid_faces.Extent(); ++i) {
        const int f = face_map.FindIndex(solid_faces(i));
        if (f < 1) continue;
        group.emplace_back(f, TopoDS::Face(solid_faces(i)));  // oriented as its solid uses it
        in_solid[f] = 1;
      }
      groups.push_back(std::move(group));
    }
    std::vector<std::pair<int, TopoDS_Face>> loose;
    for (int f = 1; f <= face_map.Extent(); ++f)
      if (!in_solid[f]) loose.emplace_back(f, TopoDS::Face(face_map(f)));
    groups.push_back(std::move(loose));
    for (const auto& group : groups) {
      std::map<std::array<double, 3>, std::uint32_t> vertex_of_point;
      for (const auto& [f, face] : group) {
        TopLoc_Location location;
        const Handle(Poly_Triangulation) tri = BRep_Tool::Triangulation(face, location);
        if (tri.IsNull()) continue;
        const gp_Trsf trsf = location.Transformation();
        // Faces share the nodes of their common edges: the same point gets one vertex, so a closed
        // solid gives a closed body.
        std::vector<std::uint32_t> index(tri->NbNodes() + 1);
        for (int n = 1; n <= tri->NbNodes(); ++n) {
          const gp_Pnt p = tri->Node(n).Transformed(trsf);
          const std::array<double, 3> key = {p.X(), p.Y(), p.Z()};
          auto [it, fresh] = vertex_of_point.emplace(key, static_cast<std::uint32_t>(vertices.size()));
          if (fresh) vertices.emplace_back(p.X(), p.Y(), p.Z());
          index[n] = it->second;
        }
        deviation = std::max(deviation, tessellation_deviation(face, *tri));
        const bool reversed = face.Orientation() == TopAbs_REVERSED;
        for (int t = 1; t <= tri->NbTriangles(); ++t) {
          int a, b, c;
          tri->Triangle(t).Get(a, b, c);
          if (reversed) std::swap(b, c);
          // At a pole or an apex two nodes of a triangle are one point: the triangle is a segment
          // that covers nothing, and kept it would leave the mesh open.
          if (index[a] == index[b] || index[b] == index[c] || index[c] == index[a]) continue;
          faces.push_back({index[a], index[b], index[c]});
          face_ids.push_back(f);
        }
      }
    }
  });
  if (!ran.ok()) return ran.error();
  if (faces.empty()) return invalid_argument("shape", "meshing produced no triangles");
  auto mesh = TriangleMesh::create(std::move(vertices), std::move(faces));
  if (!mesh.ok()) return mesh.error();
  // The window the engine decides in: the asked deflection, or what was measured when larger,
  // with a margin for the expansion's remainder (tolerances::kTessellationDeviationMargin).
  return MeshedShape{std::move(mesh).value(), std::move(face_ids), std::max(deflection_mm, tolerances::kTessellationDeviationMargin * deviation)};
}

}  // namespace gk::occt
