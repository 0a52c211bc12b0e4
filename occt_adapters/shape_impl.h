// Private to occt_adapters/: the OCCT shape behind gk::occt::Shape.
#pragma once

#include "occt_adapters/shape.h"

#include <TopoDS_Shape.hxx>

namespace gk::occt {

struct Shape::Impl {
  TopoDS_Shape shape;
};

inline Shape wrap(const TopoDS_Shape& s) { return Shape(std::make_shared<const Shape::Impl>(Shape::Impl{s})); }

}  // namespace gk::occt
