#include "server/audit_report.h"

#include "engine/audits/audit_request.h"
#include "engine/audits/clash_groups.h"
#include "engine/audits/clash_id.h"
#include "server/proto_convert.h"

#include <algorithm>
#include <cmath>
#include <map>

namespace gk::server {
namespace {

void add_groups(const std::vector<engine::ClashGroup>& groups, google::protobuf::RepeatedPtrField<pb::ClashGroup>* out) {
  for (const engine::ClashGroup& g : groups) {
    pb::ClashGroup* p = out->Add();
    p->set_key(g.key);
    p->set_clashes(g.clashes);
    p->set_collisions(g.collisions);
  }
}

pb::AuditState audit_state(AuditStatus s) {
  switch (s) {
    case AuditStatus::kRunning: return pb::RUNNING;
    case AuditStatus::kDone: return pb::DONE;
    case AuditStatus::kCancelled: return pb::CANCELLED;
    case AuditStatus::kFailed: return pb::FAILED;
  }
  return pb::FAILED;
}

}  // namespace

void progress_to_proto(const std::string& job_id, const AuditSnapshot& s, pb::AuditProgress* out) {
  out->set_job_id(job_id);
  out->set_state(audit_state(s.status));
  out->set_pairs_total(s.pairs_total);
  out->set_pairs_done(s.pairs_done);
  out->set_clashes(s.clashes.size());
  out->set_elapsed_s(s.elapsed_s);
  out->set_eta_s(s.eta_s);
  out->set_message(s.message);
  out->set_tiles_total(s.tiles_total);
  out->set_tiles_done(s.tiles_done);
}

Result<AuditOptions> to_audit_options(const pb::StartAuditRequest& in) {
  AuditOptions asked;
  asked.clearance_mm = in.clearance_mm();
  asked.tile_mm = in.tile_mm();
  // Beyond the engine's limit stays beyond it (it names the field), never wraps.
  asked.threads = static_cast<int>(std::min<std::uint32_t>(in.threads(), static_cast<std::uint32_t>(engine::kMaxAuditThreads) + 1));
  asked.compute_depth = in.compute_depth();
  asked.compute_volume = in.compute_volume();
  for (const pb::ContactRule& r : in.rules()) asked.rules.push_back({r.name(), r.category_a(), r.category_b(), r.same_group_only()});
  return asked;
}

void report_to_proto(const AuditSnapshot& snapshot, const std::string& scene_id, pb::AuditReport* out, std::size_t begin, std::size_t end) {
  end = std::min(end, snapshot.clashes.size());
  for (std::size_t i = std::min(begin, end); i < end; ++i) {
    const ClashRecord& r = snapshot.clashes[i];
    const PairClash& c = r.clash;
    pb::Clash* p = out->add_clashes();
    p->set_object_a(r.a);
    p->set_object_b(r.b);
    p->set_clash_id(engine::clash_id(scene_id, r.a, r.b));
    p->set_name_a(r.name_a);
    p->set_name_b(r.name_b);
    p->set_category_a(r.category_a);
    p->set_category_b(r.category_b);
    p->set_verdict(to_proto(c.verdict));
    p->set_inconclusive_reason(to_proto(c.inconclusive_reason));
    p->set_decided_on_brep(r.decided_on_brep);
    p->set_reason(!r.reason.empty() ? r.reason : c.error);
    p->set_distance_mm(c.distance_mm);
    to_proto(c.point_a, p->mutable_point());
    to_proto(c.point_b, p->mutable_point_b());
    p->set_contact_pairs(c.contacts);
    p->set_clearance_violation(c.clearance_violation);
    p->set_depth_mm(c.depth_mm);
    p->set_volume_mm3(c.volume_mm3);
    p->set_volume_error_bound_mm3(c.volume_error_bound_mm3);
    if (c.depth_direction) to_proto(*c.depth_direction, p->mutable_depth_axis(), p->mutable_depth_direction());
    for (const engine::ContactPlace& place : c.regions) {
      to_proto(place, p->add_contact_regions());
      // The same place in the older message (kept for old clients).
      pb::ClashRegion* q = p->add_regions();
      to_proto(place.point_a, q->mutable_point());
      to_proto(place.bounds.min, q->mutable_bounds_min());
      to_proto(place.bounds.max, q->mutable_bounds_max());
      q->set_contact_pairs(place.triangle_pairs);
      q->set_min_distance_mm(place.min_distance_mm);
    }
  }
  const engine::ClashGroups groups = engine::group_clashes(snapshot.clashes);
  add_groups(groups.by_object, out->mutable_by_object());
  add_groups(groups.by_category, out->mutable_by_category());
  add_groups(groups.by_region, out->mutable_by_region());
  out->set_candidate_pairs(snapshot.candidate_pairs);
  out->set_excluded_by_rules(snapshot.excluded_by_rules);
  out->set_objects(snapshot.objects);
  out->set_triangles(snapshot.triangles);
  out->set_broad_s(snapshot.broad_s);
  out->set_narrow_s(snapshot.narrow_s);
  out->set_recomputed_pairs(snapshot.pairs_done);
}

Result<ReportPage> report_page(const pb::GetAuditReportRequest& request, std::size_t clashes) {
  constexpr std::uint32_t kMaxPageSize = 100000;
  if (request.page_size() > kMaxPageSize) return invalid_argument("page_size", "at most 100000 clashes a page");
  ReportPage page;
  if (!request.page_token().empty()) {
    // "<job id>@<offset>": a token of another job, or past the end, is refused rather than read.
    const std::string prefix = request.job_id() + "@";
    const std::string& token = request.page_token();
    const std::string digits = token.rfind(prefix, 0) == 0 ? token.substr(prefix.size()) : std::string();
    if (digits.empty() || digits.size() > 18 || digits.find_first_not_of("0123456789") != std::string::npos)
      return invalid_argument("page_token", "not a token this job's report gave");
    page.begin = static_cast<std::size_t>(std::stoull(digits));
    if (page.begin > clashes) return invalid_argument("page_token", "beyond the report's clashes");
  }
  page.end = request.page_size() == 0 ? clashes : std::min(clashes, page.begin + request.page_size());
  if (page.end < clashes) page.next_token = request.job_id() + "@" + std::to_string(page.end);
  return page;
}

AuditSnapshot snapshot_from_report(const pb::AuditReport& report) {
  AuditSnapshot s;
  const pb::AuditProgress& p = report.progress();
  switch (p.state()) {
    case pb::DONE: s.status = AuditStatus::kDone; break;
    case pb::CANCELLED: s.status = AuditStatus::kCancelled; break;
    case pb::RUNNING: s.status = AuditStatus::kFailed; break;  // it was running when the daemon stopped
    default: s.status = AuditStatus::kFailed;
  }
  s.tiles_total = p.tiles_total();
  s.tiles_done = p.tiles_done();
  s.pairs_total = p.pairs_total();
  s.pairs_done = p.pairs_done();
  s.elapsed_s = p.elapsed_s();
  s.message = p.message();
  s.candidate_pairs = report.candidate_pairs();
  s.excluded_by_rules = report.excluded_by_rules();
  s.objects = report.objects();
  s.triangles = report.triangles();
  s.broad_s = report.broad_s();
  s.narrow_s = report.narrow_s();
  auto vec = [](const pb::Vec3& v) { return Vec3(v.x_mm(), v.y_mm(), v.z_mm()); };
  for (const pb::Clash& c : report.clashes()) {
    ClashRecord r{c.object_a(), c.object_b(), c.name_a(), c.name_b(), c.category_a(), c.category_b(), {}, false, ""};
    r.clash.verdict = from_proto(c.verdict());
    r.clash.inconclusive_reason = from_proto(c.inconclusive_reason());
    r.decided_on_brep = c.decided_on_brep();
    r.reason = c.reason();
    r.clash.distance_mm = c.distance_mm();
    r.clash.clearance_violation = c.clearance_violation();
    r.clash.point_a = vec(c.point());
    r.clash.point_b = vec(c.point_b());
    r.clash.contacts = c.contact_pairs();
    r.clash.depth_mm = c.depth_mm();
    r.clash.depth_direction = Direction::of(vec(c.depth_direction()));
    r.clash.volume_mm3 = c.volume_mm3();
    r.clash.volume_error_bound_mm3 = c.volume_error_bound_mm3();
    // Archives written before 0.2 hold only the older ClashRegion (no point on B: the point on A).
    for (const pb::ContactRegion& q : c.contact_regions())
      r.clash.regions.push_back({q.min_distance_mm(), vec(q.point_a()), vec(q.point_b()), q.triangle_pairs(),
                                 Aabb{vec(q.bounds_min()), vec(q.bounds_max())}, {}, {}});
    if (c.contact_regions().empty())
      for (const pb::ClashRegion& q : c.regions())
        r.clash.regions.push_back({q.min_distance_mm(), vec(q.point()), vec(q.point()), q.contact_pairs(),
                                   Aabb{vec(q.bounds_min()), vec(q.bounds_max())}, {}, {}});
    s.clashes.push_back(std::move(r));
  }
  return s;
}

namespace {

pb::ClashStatus to_proto(engine::ClashStatus s) {
  switch (s) {
    case engine::ClashStatus::kNew: return pb::CLASH_NEW;
    case engine::ClashStatus::kActive: return pb::CLASH_ACTIVE;
    case engine::ClashStatus::kReviewed: return pb::CLASH_REVIEWED;
    case engine::ClashStatus::kApproved: return pb::CLASH_APPROVED;
    case engine::ClashStatus::kResolved: return pb::CLASH_RESOLVED;
  }
  return pb::CLASH_ACTIVE;
}

}  // namespace

void add_clash_statuses(const std::vector<engine::ClashStatusRecord>& statuses, pb::AuditReport* report) {
  std::map<std::string, engine::ClashStatus> by_id;
  for (const engine::ClashStatusRecord& r : statuses) by_id[r.clash_id] = r.status;
  for (pb::Clash& c : *report->mutable_clashes()) {
    const auto it = by_id.find(c.clash_id());
    // No record: a running or cancelled audit's pair no finished audit has found (yet).
    c.set_status(it == by_id.end() ? pb::CLASH_STATUS_UNSPECIFIED : to_proto(it->second));
  }
}

void status_to_proto(const engine::ClashStatusRecord& r, pb::ClashStatusInfo* out) {
  out->set_scene_id(r.scene_id);
  out->set_clash_id(r.clash_id);
  out->set_object_a(r.object_a);
  out->set_object_b(r.object_b);
  out->set_status(to_proto(r.status));
  out->set_set_by_user(r.set_by_user);
  out->set_first_job_id(r.first_job_id);
  out->set_last_job_id(r.last_job_id);
}

Result<engine::ClashStatus> clash_status_from_proto(pb::ClashStatus status) {
  switch (status) {
    case pb::CLASH_ACTIVE: return engine::ClashStatus::kActive;
    case pb::CLASH_REVIEWED: return engine::ClashStatus::kReviewed;
    case pb::CLASH_APPROVED: return engine::ClashStatus::kApproved;
    case pb::CLASH_RESOLVED: return engine::ClashStatus::kResolved;
    default:
      return invalid_argument("status", "must be CLASH_REVIEWED, CLASH_APPROVED, CLASH_ACTIVE or CLASH_RESOLVED (NEW is the audits' own)");
  }
}

}  // namespace gk::server
