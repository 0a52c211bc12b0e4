// Plates as OCCT B-Rep boxes, for the exact phase and for the swept-solid cross-check.
#pragma once

#include "kernel/core/rigid_transform.h"
#include "kernel/core/status.h"
#include "machine_models/p4/sheet_part.h"
#include "occt_adapters/shape.h"

#include <vector>

namespace gk::p4 {

// The plates, each moved by `pose`, as one compound of boxes.
Result<occt::Shape> plates_shape(const std::vector<Plate>& plates, const RigidTransform& pose = {});

}  // namespace gk::p4
