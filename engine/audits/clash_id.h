// A clash's stable id: the same for the same pair of objects in every audit of a scene (a
// re-audit, a resumed or a distributed one), whichever object is named first; another scene's
// pair of objects with the same ids gets another (clients may choose object ids, and two scenes'
// BCF files imported into one project must not merge their topics). Written as a UUID
// (RFC 9562 version 8: hash-derived), so that a BCF topic, whose Guid must be one, and a user's
// status for the clash follow the pair from audit to audit.
#pragma once

#include <string>

namespace gk::engine {

std::string clash_id(const std::string& scene_id, const std::string& object_a, const std::string& object_b);

}  // namespace gk::engine
