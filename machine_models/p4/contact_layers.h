// Intended contact, made exact: a part rests on a support's top face and is pressed by an engaged
// ABA segment on its upper face. Rather than exempting those organs, the part is checked against
// them without the thin layer that is the contact itself: what hangs below a support's top face
// (less the contact tolerance), and what stands above the pressing plane (plus the tolerance). A
// body that crosses the face deeper than the tolerance, or reaches another face, meets the organ.
#pragma once

#include "kernel/core/status.h"
#include "kernel/mesh/triangle_mesh.h"

#include <optional>

namespace gk::p4 {

// The part of the mesh strictly below z (keep_below) or strictly above it, as an open triangle
// soup; nothing when no triangle reaches there.
Result<std::optional<TriangleMesh>> clip_mesh_at_z(const TriangleMesh& mesh, double z, bool keep_below);

}  // namespace gk::p4
