// The audit report as one self-contained HTML page: a 3D view of the scene (every object in a
// clash drawn with its real mesh, thinned for size; the others as boxes; a marker at every clash,
// sized to the clash; a selected clash framed with both its objects; three.js embedded, no network
// needed) and a clash table to sort and click (with each clash's review status), with the clashes
// grouped by category pair, floor cell and object.
#pragma once

#include "gatekeeper/v1/gatekeeper.pb.h"
#include "server/engine_names.h"

#include "kernel/mesh/display_decimation.h"

#include <map>
#include <string>
#include <vector>

namespace gk::server {

// How an object is drawn with its mesh: the part (a key of the meshes) and the pose.
struct PlacedMesh {
  std::string part_id;
  RigidTransform pose;
};

// `meshes`: thinned meshes by part id; `placed`: by object id, the objects drawn with theirs (the
// others are drawn as their boxes).
std::string audit_report_page(const ::gatekeeper::v1::AuditReport& report, const std::string& scene_name,
                              const std::vector<AuditedObject>& objects, const std::map<std::string, DisplayMesh>& meshes = {},
                              const std::map<std::string, PlacedMesh>& placed = {});

}  // namespace gk::server
