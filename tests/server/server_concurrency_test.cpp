// The server's shared structures under concurrent use, in process. ThreadSanitizer cannot look
// through Debian's gRPC (it is not instrumented: a TSan build of the daemon reports thousands of
// races inside gRPC's own call machinery), so this suite is what scripts/sanitizers.sh runs under
// TSan for the server; in the Release suite it checks that every answer is still right.
#include "server/answer_cache.h"
#include "server/part_registry.h"
#include "server/part_store.h"
#include "server/work_pool.h"

#include <gtest/gtest.h>
#include <openssl/sha.h>

#include <atomic>
#include <cstdio>
#include <filesystem>
#include <map>
#include <thread>
#include <vector>

namespace gk::server {
namespace {

std::string temp_dir(const std::string& tag) {
  const auto dir = std::filesystem::temp_directory_path() / ("gk-concurrency-" + tag + "-" + std::to_string(::getpid()));
  std::filesystem::remove_all(dir);
  std::filesystem::create_directories(dir);
  return dir.string();
}

std::string sha256_hex(const std::string& bytes) {
  unsigned char digest[SHA256_DIGEST_LENGTH];
  SHA256(reinterpret_cast<const unsigned char*>(bytes.data()), bytes.size(), digest);
  std::string hex;
  char two[3];
  for (unsigned char b : digest) {
    std::snprintf(two, sizeof two, "%02x", b);
    hex += two;
  }
  return hex;
}

// A flat grid of n x n squares (2 n^2 triangles) as OBJ text: parts of different sizes.
std::string grid_obj(int n) {
  std::string obj;
  for (int j = 0; j <= n; ++j)
    for (int i = 0; i <= n; ++i) obj += "v " + std::to_string(i) + " " + std::to_string(j) + " 0\n";
  auto at = [&](int i, int j) { return std::to_string(j * (n + 1) + i + 1); };
  for (int j = 0; j < n; ++j)
    for (int i = 0; i < n; ++i) {
      obj += "f " + at(i, j) + " " + at(i + 1, j) + " " + at(i + 1, j + 1) + "\n";
      obj += "f " + at(i, j) + " " + at(i + 1, j + 1) + " " + at(i, j + 1) + "\n";
    }
  return obj;
}

TEST(ServerConcurrency, PartLoadsRacingEvictionEachAnswerTheirOwnPart) {
  const std::string dir = temp_dir("parts");
  auto store = PartStore::open(dir).value();
  // About two of the four parts fit: loads keep evicting each other.
  PartRegistry registry(*store, dir + "/bvh-cache", 2 * 2 * 20 * 20 * PartRegistry::kBytesPerTriangle);
  std::map<std::string, std::uint32_t> triangles;
  for (int n : {10, 20, 30, 40}) {
    const std::string bytes = grid_obj(n);
    auto upload = store->begin("grid" + std::to_string(n), "obj", bytes.size(), sha256_hex(bytes)).value();
    ASSERT_TRUE(upload->append(bytes).ok());
    auto record = store->finish(std::move(upload), [](const std::string& path, PartRecord r) -> Result<PartRecord> {
      auto mesh = PartRegistry::read_any(path, "obj", 0.05);
      if (!mesh.ok()) return mesh.error();
      r.triangles = static_cast<std::uint32_t>(mesh.value().triangle_count());
      return r;
    });
    ASSERT_TRUE(record.ok()) << record.error().to_string();
    triangles[record.value().id] = static_cast<std::uint32_t>(2 * n * n);
  }
  std::vector<std::string> ids;
  for (const auto& [id, count] : triangles) ids.push_back(id);
  std::atomic<int> wrong{0}, failed{0};
  std::vector<std::thread> threads;
  for (int t = 0; t < 8; ++t)
    threads.emplace_back([&, t] {
      for (int i = 0; i < 150; ++i) {
        const std::string& id = ids[static_cast<std::size_t>(t * 7 + i) % ids.size()];
        auto part = registry.load(id, 0.05);
        if (!part.ok()) {
          ++failed;
          continue;
        }
        if (part.value()->mesh->triangle_count() != triangles[id] || part.value()->bvh->mesh().triangle_count() != triangles[id])
          ++wrong;
      }
    });
  for (auto& t : threads) t.join();
  EXPECT_EQ(failed.load(), 0);
  EXPECT_EQ(wrong.load(), 0);
  const auto memory = registry.memory_stats();
  EXPECT_GT(memory.evicted, 0u);
  EXPECT_TRUE(memory.parts == 1 || memory.bytes <= 2 * 2 * 20 * 20 * PartRegistry::kBytesPerTriangle) << memory.parts << " " << memory.bytes;
  std::filesystem::remove_all(dir);
}

TEST(ServerConcurrency, AWorkPoolRunsEveryAcceptedJobOnceEvenWhileStopping) {
  WorkPool pool(3, 50);
  std::atomic<int> accepted{0}, ran{0};
  std::vector<std::thread> submitters;
  for (int t = 0; t < 4; ++t)
    submitters.emplace_back([&] {
      for (int i = 0; i < 2000; ++i)
        if (pool.try_submit([&] { ++ran; })) ++accepted;
    });
  std::thread stopper([&] {
    std::this_thread::sleep_for(std::chrono::milliseconds(2));
    pool.stop();
  });
  for (auto& t : submitters) t.join();
  stopper.join();
  pool.stop();
  EXPECT_EQ(ran.load(), accepted.load());
  EXPECT_FALSE(pool.try_submit([] {})) << "a stopped pool accepts nothing";
}

TEST(ServerConcurrency, AnswerCacheReadersSeeOnlyWhatWasStoredUnderTheirKey) {
  AnswerCache cache(64);  // small: writers keep clearing it under the readers
  std::atomic<int> wrong{0};
  std::vector<std::thread> threads;
  for (int t = 0; t < 4; ++t)
    threads.emplace_back([&, t] {
      for (int i = 0; i < 3000; ++i) {
        const int k = (i * 7 + t) % 200;
        if (t % 2 == 0) {
          ::gatekeeper::v1::ValidateStepResponse r;
          r.set_min_clearance_mm(k);
          cache.store("key" + std::to_string(k), r);
        } else if (auto hit = cache.find("key" + std::to_string(k))) {
          if (hit->min_clearance_mm() != k) ++wrong;
        }
      }
    });
  for (auto& t : threads) t.join();
  EXPECT_EQ(wrong.load(), 0);
}

}  // namespace
}  // namespace gk::server
