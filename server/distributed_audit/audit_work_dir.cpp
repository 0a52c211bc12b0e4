#include "server/distributed_audit/audit_work_dir.h"

#include "kernel/core/content_hash.h"
#include "server/audit_checkpoint_store.h"

#include <nlohmann/json.hpp>

#include <fcntl.h>
#include <unistd.h>

#include <cmath>
#include <cstdio>
#include <fstream>
#include <sstream>

namespace gk::server {
namespace {

std::string tile_header(const std::string& print, std::size_t tile, std::size_t bytes) {
  return "GKTILE1 " + print + " " + std::to_string(tile) + " " + std::to_string(bytes) + "\n";
}

Error bad_job(const std::string& path, const std::string& why) { return invalid_argument("--job " + path, why); }

}  // namespace

bool write_whole(const std::string& path, const std::string& bytes) {
  const std::string tmp = path + ".tmp." + std::to_string(::getpid());
  const int fd = ::open(tmp.c_str(), O_WRONLY | O_CREAT | O_TRUNC | O_CLOEXEC, 0644);
  if (fd < 0) return false;
  std::size_t done = 0;
  while (done < bytes.size()) {
    const ssize_t n = ::write(fd, bytes.data() + done, bytes.size() - done);
    if (n <= 0) {
      ::close(fd);
      return false;
    }
    done += static_cast<std::size_t>(n);
  }
  const bool synced = ::fsync(fd) == 0;
  ::close(fd);
  return synced && std::rename(tmp.c_str(), path.c_str()) == 0;
}

std::string read_whole(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  std::ostringstream s;
  s << in.rdbuf();
  return s.str();
}

std::string audit_fingerprint(const engine::SceneRecord& scene, const engine::AuditOptions& o) {
  ContentHash h;
  auto text = [&](const std::string& t) {
    h.add(static_cast<std::uint64_t>(t.size()));
    h.add_bytes(t.data(), t.size());
  };
  text(scene.id);
  for (const auto& [id, object] : scene.objects) {
    text(id);
    text(object.part_id);
    text(object.category);
    text(object.group);
    const engine::StoredPose& p = object.pose;
    h.add({p.translation.x(), p.translation.y(), p.translation.z(), p.axis.x(), p.axis.y(), p.axis.z(), p.angle_deg});
  }
  h.add({o.clearance_mm, o.tile_mm, o.region_merge_mm, o.compute_depth ? 1.0 : 0.0, o.compute_volume ? 1.0 : 0.0});
  h.add(static_cast<std::uint64_t>(o.max_contacts_per_pair));
  for (const engine::ContactRule& r : o.rules) {
    text(r.name);
    text(r.category_a);
    text(r.category_b);
    h.add(static_cast<std::uint64_t>(r.same_group_only));
  }
  return h.value().hex();
}

std::string tile_path(const std::string& work_dir, std::size_t tile) { return work_dir + "/tile-" + std::to_string(tile) + ".bin"; }

std::string tile_file_bytes(const std::string& fingerprint, std::size_t tile, const std::vector<engine::PairClash>& clashes) {
  const std::string bytes = encode_tile(clashes);
  return tile_header(fingerprint, tile, bytes.size()) + bytes;
}

Result<std::vector<engine::PairClash>> read_tile_file(const std::string& path, const std::string& fingerprint, std::size_t tile) {
  const std::string text = read_whole(path);
  const std::size_t eol = text.find('\n');
  const std::string bytes = eol == std::string::npos ? "" : text.substr(eol + 1);
  if (eol == std::string::npos || text.substr(0, eol + 1) != tile_header(fingerprint, tile, bytes.size()))
    return Error{ErrorCode::kInternal, path, "not this audit's tile, or cut short"};
  auto clashes = decode_tile(bytes);
  if (!clashes.ok()) return Error{ErrorCode::kInternal, path, clashes.error().message};
  return clashes;
}

std::string job_file_text(const engine::SceneRecord& scene, const engine::AuditOptions& o) {
  nlohmann::json objects = nlohmann::json::array();
  for (const auto& [id, object] : scene.objects) {
    const engine::StoredPose& p = object.pose;
    objects.push_back({{"id", id},
                       {"name", object.name},
                       {"category", object.category},
                       {"group", object.group},
                       {"part_id", object.part_id},
                       {"translation_mm", {p.translation.x(), p.translation.y(), p.translation.z()}},
                       {"axis", {p.axis.x(), p.axis.y(), p.axis.z()}},
                       {"angle_deg", p.angle_deg}});
  }
  nlohmann::json rules = nlohmann::json::array();
  for (const engine::ContactRule& r : o.rules)
    rules.push_back({{"name", r.name}, {"category_a", r.category_a}, {"category_b", r.category_b}, {"same_group_only", r.same_group_only}});
  const nlohmann::json job{{"scene_id", scene.id},
                           {"scene_name", scene.name},
                           {"objects", std::move(objects)},
                           {"clearance_mm", o.clearance_mm},
                           {"tile_mm", o.tile_mm},
                           {"threads", o.threads},
                           {"compute_depth", o.compute_depth},
                           {"compute_volume", o.compute_volume},
                           {"region_merge_mm", o.region_merge_mm},
                           {"max_contacts_per_pair", o.max_contacts_per_pair},
                           {"rules", std::move(rules)}};
  // Doubles are written to round-trip (nlohmann's shortest form that reads back the same).
  return job.dump(1) + "\n";
}

Result<AuditJobFile> read_job_file(const std::string& path) {
  const nlohmann::json job = nlohmann::json::parse(read_whole(path), nullptr, false);
  if (job.is_discarded() || !job.is_object()) return bad_job(path, "is not a JSON job file");
  try {
    AuditJobFile out;
    out.scene.id = job.at("scene_id").get<std::string>();
    out.scene.name = job.value("scene_name", "");
    for (const auto& o : job.at("objects")) {
      engine::SceneObjectRecord r;
      r.id = o.at("id").get<std::string>();
      r.name = o.at("name").get<std::string>();
      r.category = o.at("category").get<std::string>();
      r.group = o.at("group").get<std::string>();
      r.part_id = o.at("part_id").get<std::string>();
      for (int k = 0; k < 3; ++k) {
        r.pose.translation[k] = o.at("translation_mm").at(static_cast<std::size_t>(k)).get<double>();
        r.pose.axis[k] = o.at("axis").at(static_cast<std::size_t>(k)).get<double>();
      }
      r.pose.angle_deg = o.at("angle_deg").get<double>();
      out.scene.objects[r.id] = std::move(r);
    }
    engine::AuditOptions& a = out.options;
    a.clearance_mm = job.at("clearance_mm").get<double>();
    a.tile_mm = job.at("tile_mm").get<double>();
    a.threads = job.at("threads").get<int>();
    a.compute_depth = job.at("compute_depth").get<bool>();
    a.compute_volume = job.at("compute_volume").get<bool>();
    a.region_merge_mm = job.at("region_merge_mm").get<double>();
    a.max_contacts_per_pair = job.at("max_contacts_per_pair").get<std::size_t>();
    for (const auto& r : job.at("rules"))
      a.rules.push_back({r.at("name").get<std::string>(), r.at("category_a").get<std::string>(), r.at("category_b").get<std::string>(),
                         r.at("same_group_only").get<bool>()});
    return out;
  } catch (const nlohmann::json::exception& e) {
    return bad_job(path, std::string("lacks a field or has one of the wrong type: ") + e.what());
  }
}

}  // namespace gk::server
