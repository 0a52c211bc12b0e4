#include "server/audit_report_page.h"

#include <nlohmann/json.hpp>

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

void replace_all(std::string& text, const std::string& what, const std::string& with) {
  for (std::size_t at = text.find(what); at != std::string::npos; at = text.find(what, at + with.size())) text.replace(at, what.size(), with);
}

}  // namespace

std::string audit_report_page(const pb::AuditReport& report, const std::string& scene_name, const std::vector<AuditedObject>& objects) {
  json data;
  const pb::AuditProgress& p = report.progress();
  data["summary"] = {{"state", pb::AuditState_Name(p.state())}, {"objects", report.objects()}, {"triangles", report.triangles()},
                     {"candidate_pairs", report.candidate_pairs()}, {"excluded_by_rules", report.excluded_by_rules()},
                     {"broad_s", report.broad_s()}, {"narrow_s", report.narrow_s()}};
  std::map<std::string, std::size_t> index_of;
  json objs = json::array();
  for (const AuditedObject& o : objects) {
    index_of[o.id] = objs.size();
    objs.push_back({{"id", o.id}, {"name", o.name}, {"category", o.category}, {"min", vec(o.box.min)}, {"max", vec(o.box.max)}});
  }
  data["objects"] = objs;
  json clashes = json::array();
  for (const pb::Clash& c : report.clashes()) {
    clashes.push_back({{"a", c.object_a()}, {"b", c.object_b()}, {"a_index", index_of[c.object_a()]}, {"b_index", index_of[c.object_b()]},
                       {"name_a", c.name_a()}, {"name_b", c.name_b()}, {"category_a", c.category_a()}, {"category_b", c.category_b()},
                       {"verdict", pb::Verdict_Name(c.verdict())}, {"clearance_violation", c.clearance_violation()},
                       {"distance_mm", c.distance_mm()}, {"depth_mm", c.depth_mm()}, {"contacts", c.contact_pairs()},
                       {"point", vec(c.point())}});
  }
  data["clashes"] = clashes;
  data["by_category"] = groups(report.by_category());
  data["by_region"] = groups(report.by_region());
  data["by_object"] = groups(report.by_object());
  std::string payload = data.dump();
  replace_all(payload, "</", "<\\/");  // never close the script element early
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
