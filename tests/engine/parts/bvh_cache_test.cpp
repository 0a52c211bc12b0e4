// BVHs kept on disk by their mesh's content hash: met again, a tree is loaded, never misread.
#include "engine/parts/bvh_cache.h"
#include "tests/support/random_meshes.h"

#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <unistd.h>

namespace gk::engine {
namespace {

TEST(BvhCache, ASecondMeetingLoadsTheTreeAndABadFileIsRebuilt) {
  const std::string dir = ::testing::TempDir() + "/bvh-cache-" + std::to_string(::getpid());
  std::filesystem::remove_all(dir);
  testing::Rng rng(4);
  auto mesh = testing::share(testing::random_closed_blob(rng, 4, 40.0, 0.3, Vec3::Zero()));
  BvhCache cache(dir);
  const auto first = cache.get_or_build(mesh).value();
  const auto again = cache.get_or_build(mesh).value();
  EXPECT_EQ(cache.stats().built, 1u);
  EXPECT_EQ(cache.stats().loaded, 1u);
  EXPECT_EQ(again->serialize(), first->serialize());
  // The same content in another mesh object hits the same file; different content does not.
  auto copy = testing::share(TriangleMesh(*mesh));
  (void)cache.get_or_build(copy).value();
  EXPECT_EQ(cache.stats().loaded, 2u);
  auto other = testing::share(testing::random_closed_blob(rng, 4, 40.0, 0.3, Vec3::Zero()));
  EXPECT_NE(mesh_content_hash(*other), mesh_content_hash(*mesh));
  (void)cache.get_or_build(other).value();
  EXPECT_EQ(cache.stats().built, 2u);
  // Overwrite every file with garbage: refused, rebuilt, rewritten.
  for (const auto& entry : std::filesystem::directory_iterator(dir)) std::ofstream(entry.path()) << "garbage";
  const auto rebuilt = cache.get_or_build(mesh).value();
  EXPECT_EQ(cache.stats().rejected, 1u);
  EXPECT_EQ(rebuilt->serialize(), first->serialize());
  (void)cache.get_or_build(mesh).value();
  EXPECT_EQ(cache.stats().loaded, 3u);
  std::filesystem::remove_all(dir);
}


// A file of an earlier format (GKBVH002 held OCCT's double node arrays, GKBVH001 trees of one
// triangle per leaf) is never read as the current layout: it is rebuilt.
TEST(BvhCache, AFileOfTheEarlierFormatIsRebuiltInTheCurrentOne) {
  const std::string dir = ::testing::TempDir() + "/bvh-cache-v1-" + std::to_string(::getpid());
  std::filesystem::remove_all(dir);
  testing::Rng rng(5);
  auto mesh = testing::share(testing::random_closed_blob(rng, 4, 40.0, 0.3, Vec3::Zero()));
  BvhCache cache(dir);
  const std::string current = cache.get_or_build(mesh).value()->serialize();
  ASSERT_EQ(current.compare(0, 8, "GKBVH003"), 0);
  // The same mesh's tree of one triangle per leaf, labelled with the earlier format, where the
  // cache looks.
  BvhBuildOptions one_per_leaf;
  one_per_leaf.leaf_size = 1;
  std::string old = MeshBvh::build(mesh, one_per_leaf).value()->serialize();
  old.replace(0, 8, "GKBVH002");
  for (const auto& entry : std::filesystem::directory_iterator(dir)) std::ofstream(entry.path(), std::ios::binary) << old;
  const auto again = cache.get_or_build(mesh).value();
  EXPECT_EQ(cache.stats().rejected, 1u);
  EXPECT_EQ(cache.stats().built, 2u);
  EXPECT_EQ(again->serialize(), current);
  std::filesystem::remove_all(dir);
}

}  // namespace
}  // namespace gk::engine
