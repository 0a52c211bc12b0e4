// The audit report as one self-contained HTML page: a 3D view of the scene (objects as boxes, the
// clashing ones highlighted, a marker at every clash; three.js embedded, no network needed) and a
// clash table to sort and click, with the clashes grouped by category pair, floor cell and object.
#pragma once

#include "gatekeeper/v1/gatekeeper.pb.h"
#include "server/engine_names.h"

#include <string>
#include <vector>

namespace gk::server {

std::string audit_report_page(const ::gatekeeper::v1::AuditReport& report, const std::string& scene_name,
                              const std::vector<AuditedObject>& objects);

}  // namespace gk::server
