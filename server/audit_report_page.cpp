#include "server/audit_report_page.h"

#include <nlohmann/json.hpp>

#include <cstdint>
#include <map>

namespace gk::server {

// Generated at build time from server/report_page (the template and npm's three.min.js).
const char* audit_report_template();
const std::string& embedded_three_js();  // joined once

namespace {

namespace pb = ::gatekeeper::v1;
using nlohmann::json;

json vec(const pb::Vec3& v) { return json::array({v.x_mm(), v.y_mm(), v.z_mm()}); }
json vec(const Vec3& v) { return json::array({v.x(), v.y(), v.z()}); }

json groups(const google::protobuf::RepeatedPtrField<pb::ClashGroup>& in) {
  json out = json::array();
  for (const pb::ClashGroup& g : in) out.push_back({{"key", g.key()}, {"clashes", g.clashes()}, {"collisions", g.collisions()}});
  return out;
}

std::string html_escape(const std::string& s) {
  std::string out;
  for (char c : s) {
    switch (c) {
      case '<': out += "&lt;"; break;
      case '>': out += "&gt;"; break;
      case '&': out += "&amp;"; break;
      case '"': out += "&quot;"; break;
      default: out += c;
    }
  }
  return out;
}

// Little-endian bytes (what the page's typed arrays read) as base64.
template <typename T>
std::string base64_of(const std::vector<T>& values) {
  static const char kAlphabet[] = "ABCDEFGHIJKLMNOPQRSTUVWXYZabcdefghijklmnopqrstuvwxyz0123456789+/";
  const auto* bytes = reinterpret_cast<const unsigned char*>(values.data());
  const std::size_t n = values.size() * sizeof(T);
  std::string out;
  out.reserve((n + 2) / 3 * 4);
  for (std::size_t i = 0; i < n; i += 3) {
    const std::uint32_t chunk = (static_cast<std::uint32_t>(bytes[i]) << 16) | (i + 1 < n ? static_cast<std::uint32_t>(bytes[i + 1]) << 8 : 0u) |
                                (i + 2 < n ? static_cast<std::uint32_t>(bytes[i + 2]) : 0u);
    out += kAlphabet[(chunk >> 18) & 63];
    out += kAlphabet[(chunk >> 12) & 63];
    out += i + 1 < n ? kAlphabet[(chunk >> 6) & 63] : '=';
    out += i + 2 < n ? kAlphabet[chunk & 63] : '=';
  }
  return out;
}

// A clash's own size: half the extent of its witnesses and contact regions [mm].
double clash_extent(const pb::Clash& c) {
  Aabb box;
  box.extend(Vec3(c.point().x_mm(), c.point().y_mm(), c.point().z_mm()));
  box.extend(Vec3(c.point_b().x_mm(), c.point_b().y_mm(), c.point_b().z_mm()));
  for (const pb::ContactRegion& r : c.contact_regions()) {
    box.extend(Vec3(r.bounds_min().x_mm(), r.bounds_min().y_mm(), r.bounds_min().z_mm()));
    box.extend(Vec3(r.bounds_max().x_mm(), r.bounds_max().y_mm(), r.bounds_max().z_mm()));
  }
  return 0.5 * (box.max - box.min).norm();
}

void replace_all(std::string& text, const std::string& what, const std::string& with) {
  for (std::size_t at = text.find(what); at != std::string::npos; at = text.find(what, at + with.size())) text.replace(at, what.size(), with);
}

}  // namespace

std::string audit_report_page(const pb::AuditReport& report, const std::string& scene_name, const std::vector<AuditedObject>& objects,
                              const std::map<std::string, DisplayMesh>& meshes, const std::map<std::string, PlacedMesh>& placed) {
  json data;
  const pb::AuditProgress& p = report.progress();
  data["summary"] = {{"state", pb::AuditState_Name(p.state())}, {"objects", report.objects()}, {"triangles", report.triangles()},
                     {"candidate_pairs", report.candidate_pairs()}, {"excluded_by_rules", report.excluded_by_rules()},
                     {"broad_s", report.broad_s()}, {"narrow_s", report.narrow_s()}};
  std::map<std::string, std::size_t> part_index;
  json parts = json::array();
  for (const auto& [part_id, mesh] : meshes) {
    std::vector<float> positions;
    positions.reserve(mesh.vertices.size() * 3);
    for (const Vec3& v : mesh.vertices)
      for (int k = 0; k < 3; ++k) positions.push_back(static_cast<float>(v[k]));
    std::vector<std::uint32_t> indices;
    indices.reserve(mesh.triangles.size() * 3);
    for (const auto& t : mesh.triangles) indices.insert(indices.end(), t.begin(), t.end());
    part_index[part_id] = parts.size();
    parts.push_back({{"positions", base64_of(positions)}, {"indices", base64_of(indices)}, {"triangles", mesh.triangles.size()}});
  }
  data["parts"] = parts;
  std::map<std::string, std::size_t> index_of;
  json objs = json::array();
  for (const AuditedObject& o : objects) {
    index_of[o.id] = objs.size();
    json obj = {{"id", o.id}, {"name", o.name}, {"category", o.category}, {"min", vec(o.box.min)}, {"max", vec(o.box.max)}};
    const auto at = placed.find(o.id);
    if (at != placed.end() && part_index.count(at->second.part_id)) {
      // Column-major 4x4, as three.js's Matrix4.fromArray reads it.
      const RigidTransform& pose = at->second.pose;
      json matrix = json::array();
      for (int col = 0; col < 4; ++col)
        for (int row = 0; row < 4; ++row)
          matrix.push_back(col < 3 ? (row < 3 ? pose.rotation(row, col) : 0.0) : (row < 3 ? pose.translation[row] : 1.0));
      obj["part"] = part_index[at->second.part_id];
      obj["matrix"] = matrix;
    }
    objs.push_back(obj);
  }
  data["objects"] = objs;
  json clashes = json::array();
  for (const pb::Clash& c : report.clashes()) {
    clashes.push_back({{"a", c.object_a()}, {"b", c.object_b()}, {"a_index", index_of[c.object_a()]}, {"b_index", index_of[c.object_b()]},
                       {"name_a", c.name_a()}, {"name_b", c.name_b()}, {"category_a", c.category_a()}, {"category_b", c.category_b()},
                       {"verdict", pb::Verdict_Name(c.verdict())}, {"clearance_violation", c.clearance_violation()},
                       {"distance_mm", c.distance_mm()}, {"depth_mm", c.depth_mm()}, {"contacts", c.contact_pairs()},
                       {"point", vec(c.point())}, {"extent_mm", clash_extent(c)}, {"clash_id", c.clash_id()},
                       {"status", pb::ClashStatus_Name(c.status())}});
  }
  data["clashes"] = clashes;
  data["by_category"] = groups(report.by_category());
  data["by_region"] = groups(report.by_region());
  data["by_object"] = groups(report.by_object());
  std::string payload = data.dump();
  // No '<' at all inside the data block: "</script" would close it early and "<!--" would put
  // the HTML parser into a state that swallows the scripts after it.
  replace_all(payload, "<", "\\u003c");
  std::string page = audit_report_template();
  replace_all(page, "@SCENE_NAME@", html_escape(scene_name.empty() ? "(unnamed scene)" : scene_name));
  // three.js last: its text must not be searched for placeholders.
  const std::size_t json_at = page.find("@REPORT_JSON@");
  page.replace(json_at, std::string("@REPORT_JSON@").size(), payload);
  const std::size_t three_at = page.find("@THREE_JS@", json_at + payload.size());
  page.replace(three_at, std::string("@THREE_JS@").size(), embedded_three_js());
  return page;
}

}  // namespace gk::server
