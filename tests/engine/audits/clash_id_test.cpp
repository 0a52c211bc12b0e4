// A clash's id: one per pair of objects in a scene, whichever object comes first; another scene's
// pair with the same object ids gets another; the text is a UUID (a BCF topic's Guid).
#include "engine/audits/clash_id.h"

#include <gtest/gtest.h>

#include <regex>
#include <set>
#include <string>

namespace gk::engine {
namespace {

TEST(ClashId, OnePerPairOfObjectsInAScene) {
  EXPECT_EQ(clash_id("scene-1", "robot-1", "conveyor-2"), clash_id("scene-1", "conveyor-2", "robot-1"));
  EXPECT_NE(clash_id("scene-1", "robot-1", "conveyor-2"), clash_id("scene-2", "robot-1", "conveyor-2"));
  // Joined texts that read the same must not give the same id.
  EXPECT_NE(clash_id("s", "ab", "c"), clash_id("s", "a", "bc"));
  EXPECT_NE(clash_id("sa", "b", "c"), clash_id("s", "ab", "c"));
  const std::regex uuid("[0-9a-f]{8}-[0-9a-f]{4}-8[0-9a-f]{3}-[89ab][0-9a-f]{3}-[0-9a-f]{12}");
  std::set<std::string> ids;
  for (int a = 0; a < 60; ++a)
    for (int b = a + 1; b < 60; ++b) {
      const std::string id = clash_id("scene", "obj-" + std::to_string(a), "obj-" + std::to_string(b));
      EXPECT_TRUE(std::regex_match(id, uuid)) << id;
      ids.insert(id);
    }
  EXPECT_EQ(ids.size(), 60u * 59u / 2u);
}

}  // namespace
}  // namespace gk::engine
