// An opaque handle to an OCCT B-Rep shape: no OCCT type crosses this header.
#pragma once

#include "kernel/core/aabb.h"

#include <memory>

namespace gk::occt {

class Shape {
 public:
  struct Impl;  // holds the TopoDS_Shape; defined in occt_adapters/shape_impl.h

  Shape();
  explicit Shape(std::shared_ptr<const Impl> impl);
  bool is_null() const;
  int face_count() const;
  int solid_count() const;
  Aabb bounds() const;  // of the exact geometry, slightly enlarged by OCCT's tolerances
  double volume() const;  // 0 for shapes without solids
  // Every face a plane and every edge a straight line: a tessellation of it is the shape itself
  // (up to rounding), whatever its deflection.
  bool is_polyhedral() const;
  const Impl& impl() const { return *impl_; }

 private:
  std::shared_ptr<const Impl> impl_;
};

}  // namespace gk::occt
