#include "clients/gatekeeper_client/bcf_export.h"

#include "clients/gatekeeper_client/zip_writer.h"

#include <openssl/sha.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <ctime>
#include <regex>
#include <set>

namespace pb = ::gatekeeper::v1;

namespace gk::client {
namespace {

std::string xml_text(const std::string& in) {
  std::string out;
  for (std::size_t i = 0; i < in.size(); ++i) {
    const char c = in[i];
    // U+FFFE and U+FFFF (EF BF BE / EF BF BF) are not XML characters: the replacement character.
    if (static_cast<unsigned char>(c) == 0xEF && i + 2 < in.size() && static_cast<unsigned char>(in[i + 1]) == 0xBF &&
        (static_cast<unsigned char>(in[i + 2]) == 0xBE || static_cast<unsigned char>(in[i + 2]) == 0xBF)) {
      out += "\xEF\xBF\xBD";
      i += 2;
      continue;
    }
    switch (c) {
      case '&': out += "&amp;"; break;
      case '<': out += "&lt;"; break;
      case '>': out += "&gt;"; break;
      case '"': out += "&quot;"; break;
      case '\'': out += "&apos;"; break;
      default:
        // XML 1.0 allows no control characters but tab, newline and carriage return.
        if (static_cast<unsigned char>(c) < 0x20 && c != '\t' && c != '\n' && c != '\r') out += ' ';
        else out += c;
    }
  }
  return out;
}

std::string number(double v) {
  if (!std::isfinite(v)) v = 0.0;
  char text[32];
  std::snprintf(text, sizeof text, "%.17g", v);
  return text;
}

struct Point {
  double x = 0, y = 0, z = 0;
};
Point metres(const pb::Vec3& v) { return {v.x_mm() / 1000.0, v.y_mm() / 1000.0, v.z_mm() / 1000.0}; }

std::string xyz(const char* tag, const Point& p) {
  return std::string("<") + tag + "><X>" + number(p.x) + "</X><Y>" + number(p.y) + "</Y><Z>" + number(p.z) + "</Z></" + tag + ">";
}

// A second Guid derived from the topic's (the viewpoint's): SHA-256 of it, as a version 8 UUID.
std::string derived_guid(const std::string& guid, const char* what) {
  const std::string input = guid + "/" + what;
  unsigned char digest[SHA256_DIGEST_LENGTH];
  SHA256(reinterpret_cast<const unsigned char*>(input.data()), input.size(), digest);
  digest[6] = static_cast<unsigned char>((digest[6] & 0x0F) | 0x80);
  digest[8] = static_cast<unsigned char>((digest[8] & 0x3F) | 0x80);
  char text[37];
  std::snprintf(text, sizeof text, "%02x%02x%02x%02x-%02x%02x-%02x%02x-%02x%02x-%02x%02x%02x%02x%02x%02x", digest[0], digest[1],
                digest[2], digest[3], digest[4], digest[5], digest[6], digest[7], digest[8], digest[9], digest[10], digest[11],
                digest[12], digest[13], digest[14], digest[15]);
  return text;
}

// The clash tools' words for the review statuses (a report without statuses: New).
const char* status_word(pb::ClashStatus s) {
  switch (s) {
    case pb::CLASH_ACTIVE: return "Active";
    case pb::CLASH_REVIEWED: return "Reviewed";
    case pb::CLASH_APPROVED: return "Approved";
    case pb::CLASH_RESOLVED: return "Resolved";
    default: return "New";
  }
}

const char* verdict_word(const pb::Clash& c) {
  switch (c.verdict()) {
    case pb::COLLISION: return "COLLISION";
    case pb::TOUCHING: return "TOUCHING";
    case pb::INCONCLUSIVE: return "INCONCLUSIVE";
    default: return c.clearance_violation() ? "CLEARANCE" : "CLEAR";
  }
}

std::string markup(const pb::Clash& c, const std::string& job, const std::string& date, const std::string& author,
                   const std::string& viewpoint_guid) {
  const std::string a = c.name_a().empty() ? c.object_a() : c.name_a();
  const std::string b = c.name_b().empty() ? c.object_b() : c.name_b();
  std::string description = std::string(verdict_word(c)) + " between " + a + " and " + b;
  if (!c.reason().empty()) description += ": " + c.reason();
  if (c.verdict() == pb::COLLISION) {
    if (c.depth_mm() >= 0.0) description += "; depth " + number(c.depth_mm()) + " mm (upper bound)";
    if (c.volume_mm3() >= 0.0)
      description += "; shared volume " + number(c.volume_mm3()) + " mm3 (within " + number(c.volume_error_bound_mm3()) + ")";
  } else {
    description += "; distance " + number(c.distance_mm()) + " mm";
  }
  description += "; " + std::to_string(c.contact_pairs()) + " triangle pairs; objects " + c.object_a() + " and " + c.object_b() +
                 "; audit " + job;
  std::string out = "<?xml version=\"1.0\" encoding=\"UTF-8\"?>\n<Markup>\n";
  out += "  <Topic Guid=\"" + c.clash_id() + "\" TopicType=\"Clash\" TopicStatus=\"" + status_word(c.status()) + "\">\n";
  out += "    <Title>" + xml_text(std::string(verdict_word(c)) + ": " + a + " / " + b) + "</Title>\n";
  std::set<std::string> labels;
  for (const std::string& l : {c.category_a(), c.category_b()})
    if (!l.empty() && labels.insert(l).second) out += "    <Labels>" + xml_text(l) + "</Labels>\n";
  out += "    <CreationDate>" + date + "</CreationDate>\n";
  out += "    <CreationAuthor>" + xml_text(author) + "</CreationAuthor>\n";
  out += "    <Description>" + xml_text(description) + "</Description>\n";
  out += "  </Topic>\n";
  out += "  <Viewpoints Guid=\"" + viewpoint_guid + "\">\n    <Viewpoint>viewpoint.bcfv</Viewpoint>\n  </Viewpoints>\n";
  out += "</Markup>\n";
  return out;
}

// Looks at the clash down the diagonal (-1, -1, -1), z up, from where a 60 degree view holds the
// clash's extent (its witnesses and contact regions, at least 0.1 m) with a margin.
std::string viewpoint(const pb::Clash& c, const std::string& guid) {
  Point lo = metres(c.point()), hi = lo;
  const auto grow = [&](const Point& p) {
    lo = {std::min(lo.x, p.x), std::min(lo.y, p.y), std::min(lo.z, p.z)};
    hi = {std::max(hi.x, p.x), std::max(hi.y, p.y), std::max(hi.z, p.z)};
  };
  grow(metres(c.point_b()));
  for (const pb::ContactRegion& r : c.contact_regions()) {
    grow(metres(r.bounds_min()));
    grow(metres(r.bounds_max()));
  }
  const Point target{0.5 * (lo.x + hi.x), 0.5 * (lo.y + hi.y), 0.5 * (lo.z + hi.z)};
  const double size = std::max(std::hypot(hi.x - lo.x, hi.y - lo.y, hi.z - lo.z), 0.1);
  const double distance = 1.5 * size / std::tan(30.0 * 3.14159265358979323846 / 180.0);
  const double k = 1.0 / std::sqrt(3.0), u = 1.0 / std::sqrt(6.0);
  const Point eye{target.x + k * distance, target.y + k * distance, target.z + k * distance};
  std::string out = "<?xml version=\"1.0\" encoding=\"UTF-8\"?>\n<VisualizationInfo Guid=\"" + guid + "\">\n  <Components>\n";
  out += "    <Selection>\n";
  for (const std::string& id : {c.object_a(), c.object_b()})
    out += "      <Component><OriginatingSystem>gatekeeperd</OriginatingSystem><AuthoringToolId>" + xml_text(id) +
           "</AuthoringToolId></Component>\n";
  out += "    </Selection>\n    <Visibility DefaultVisibility=\"true\"/>\n  </Components>\n";
  out += "  <PerspectiveCamera>\n    " + xyz("CameraViewPoint", eye) + "\n    " + xyz("CameraDirection", {-k, -k, -k}) + "\n    " +
         xyz("CameraUpVector", {-u, -u, 2.0 * u}) + "\n    <FieldOfView>60</FieldOfView>\n  </PerspectiveCamera>\n";
  out += "</VisualizationInfo>\n";
  return out;
}

}  // namespace

bool write_bcf(const pb::AuditReport& report, const BcfOptions& options, std::string* archive, std::string* error) {
  static const std::regex guid("[a-fA-F0-9]{8}-[a-fA-F0-9]{4}-[a-fA-F0-9]{4}-[a-fA-F0-9]{4}-[a-fA-F0-9]{12}");
  std::set<std::string> seen;
  for (const pb::Clash& c : report.clashes()) {
    if (!std::regex_match(c.clash_id(), guid)) {
      *error = "clash " + c.object_a() + " / " + c.object_b() + " has no clash_id (a report from a daemon older than that field)";
      return false;
    }
    if (!seen.insert(c.clash_id()).second) {
      *error = "clash_id " + c.clash_id() + " appears twice in the report";
      return false;
    }
  }
  const std::time_t now = options.created_unix_s > 0 ? static_cast<std::time_t>(options.created_unix_s) : std::time(nullptr);
  std::tm utc{};
  gmtime_r(&now, &utc);
  char date[32];
  std::strftime(date, sizeof date, "%Y-%m-%dT%H:%M:%SZ", &utc);
  const auto dos_date = static_cast<std::uint16_t>(((std::max(utc.tm_year, 80) - 80) << 9) | ((utc.tm_mon + 1) << 5) | utc.tm_mday);
  const auto dos_time = static_cast<std::uint16_t>((utc.tm_hour << 11) | (utc.tm_min << 5) | (utc.tm_sec / 2));
  ZipWriter zip(dos_date, dos_time);
  zip.add("bcf.version",
          "<?xml version=\"1.0\" encoding=\"UTF-8\"?>\n<Version VersionId=\"2.1\">\n  <DetailedVersion>2.1</DetailedVersion>\n</Version>\n");
  for (const pb::Clash& c : report.clashes()) {
    const std::string view = derived_guid(c.clash_id(), "viewpoint");
    zip.add(c.clash_id() + "/markup.bcf", markup(c, report.progress().job_id(), date, options.author, view));
    zip.add(c.clash_id() + "/viewpoint.bcfv", viewpoint(c, view));
  }
  *archive = zip.finish();
  return true;
}

}  // namespace gk::client
