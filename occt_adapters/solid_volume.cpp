#include "occt_adapters/solid_volume.h"

#include "kernel/core/tolerances.h"

#include <BRepBndLib.hxx>
#include <BRepBuilderAPI_Copy.hxx>
#include <BRepGProp.hxx>
#include <BRepMesh_IncrementalMesh.hxx>
#include <BRep_Tool.hxx>
#include <Bnd_Box.hxx>
#include <GProp_GProps.hxx>
#include <Poly_Triangulation.hxx>
#include <TopExp_Explorer.hxx>
#include <TopLoc_Location.hxx>
#include <TopoDS.hxx>

#include <algorithm>
#include <cmath>
#include <limits>

namespace gk::occt {

SolidVolume solid_volume(const TopoDS_Shape& solid) {
  SolidVolume out;
  out.error_bound_mm3 = std::numeric_limits<double>::infinity();
  GProp_GProps props;
  BRepGProp::VolumeProperties(solid, props, 1e-9);
  out.volume_mm3 = std::fabs(props.Mass());
  GProp_GProps surface;
  BRepGProp::SurfaceProperties(solid, surface);
  out.area_mm2 = surface.Mass();
  return out;
}

SolidVolume solid_volume_with_bound(const TopoDS_Shape& solid) {
  SolidVolume out = solid_volume(solid);
  Bnd_Box box;
  BRepBndLib::Add(solid, box);
  if (box.IsVoid() || !(out.area_mm2 > 0.0)) return out;
  const double diagonal = std::sqrt(box.SquareExtent());
  const double thickness = 2.0 * out.volume_mm3 / out.area_mm2;
  // Fine relative to how thick the solid is, so that the band stays a small part of the volume
  // (about 4 * deflection / thickness of it: 1 %), and no finer than the solid's size allows.
  const double deflection = std::max({tolerances::kVolumeCheckDeflectionRelative * thickness, 1e-6 * diagonal, tolerances::kVolumeCheckFinestDeflectionMm});
  // Meshed as a copy: the caller's shape keeps whatever triangulation it had.
  const TopoDS_Shape copy = BRepBuilderAPI_Copy(solid, Standard_True, Standard_False).Shape();
  BRepMesh_IncrementalMesh mesher(copy, deflection, Standard_False, 0.5, Standard_False);
  if (!mesher.IsDone()) return out;
  double xmin, ymin, zmin, xmax, ymax, zmax;
  box.Get(xmin, ymin, zmin, xmax, ymax, zmax);
  const gp_XYZ origin(0.5 * (xmin + xmax), 0.5 * (ymin + ymax), 0.5 * (zmin + zmax));  // small coordinates
  double mesh_volume = 0.0, band = 0.0;
  for (TopExp_Explorer e(copy, TopAbs_FACE); e.More(); e.Next()) {
    const TopoDS_Face& face = TopoDS::Face(e.Current());
    TopLoc_Location where;
    const Handle(Poly_Triangulation) tri = BRep_Tool::Triangulation(face, where);
    if (tri.IsNull()) return out;  // a face left unmeshed: no bound
    const gp_Trsf placement = where.Transformation();
    const bool reversed = face.Orientation() == TopAbs_REVERSED;
    double mesh_area = 0.0;
    for (Standard_Integer i = 1; i <= tri->NbTriangles(); ++i) {
      Standard_Integer n1, n2, n3;
      tri->Triangle(i).Get(n1, n2, n3);
      if (reversed) std::swap(n2, n3);
      const gp_XYZ p1 = tri->Node(n1).Transformed(placement).XYZ() - origin;
      const gp_XYZ p2 = tri->Node(n2).Transformed(placement).XYZ() - origin;
      const gp_XYZ p3 = tri->Node(n3).Transformed(placement).XYZ() - origin;
      mesh_volume += p1.Dot(p2.Crossed(p3)) / 6.0;
      mesh_area += 0.5 * (p2 - p1).Crossed(p3 - p1).Modulus();
    }
    GProp_GProps face_props;
    BRepGProp::SurfaceProperties(face, face_props);
    // The true boundary and the triangles are within the deflection of each other: the region
    // between them lies within that distance on either side of the face.
    band += 2.0 * std::max(face_props.Mass(), mesh_area) * std::max(deflection, tri->Deflection());
  }
  out.error_bound_mm3 = std::fabs(out.volume_mm3 - std::fabs(mesh_volume)) + band;
  return out;
}

}  // namespace gk::occt
