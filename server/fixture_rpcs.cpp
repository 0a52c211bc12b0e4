// AssembleFixture: one client stream is one fixture assembly session (engine/fixtures/
// assembly_session.h). Each message is a step (start, assemble, disassemble, begin moving, a frame)
// answered before the next is read. A step the session refuses is answered with its error, naming
// the field, and changes nothing: a designer's typo does not cost the fixture assembled so far.
// The session lives as long as the stream (it is not stored: the fixture is the client's document).
#include "server/gatekeeper_service.h"

#include "engine/fixtures/assembly_session.h"
#include "engine/input_checks.h"
#include "server/access_control.h"
#include "server/proto_convert.h"
#include "server/rpc_helpers.h"

#include <memory>
#include <optional>

namespace gk::server {
namespace {

using engine::AssemblyFrame;
using engine::AssemblySession;
using engine::CylinderFeature;
using engine::FixtureElement;
using engine::Mate;

// One session holds at most this many assembled elements: a fixture has tens to hundreds. The
// layer model is rebuilt in part on every assembly, and its cost grows steeply with the elements
// that overlap a layer (3,000 scattered elements took 30 ms each to add); beyond this an
// assemble is refused (RESOURCE_EXHAUSTED, in-band).
constexpr std::size_t kMaxAssembledElements = 1000;

std::vector<CylinderFeature> features_from_proto(const google::protobuf::RepeatedPtrField<pb::CylinderFeature>& in) {
  std::vector<CylinderFeature> out;
  out.reserve(static_cast<std::size_t>(in.size()));
  for (const pb::CylinderFeature& f : in) {
    CylinderFeature c;
    c.name = f.name();
    c.origin = Vec3(f.origin().x_mm(), f.origin().y_mm(), f.origin().z_mm());
    c.axis = Vec3(f.axis().x(), f.axis().y(), f.axis().z());
    c.radius_mm = f.radius_mm();
    c.half_length_mm = f.half_length_mm();
    c.hole = f.hole();
    c.triangles.assign(f.triangles().begin(), f.triangles().end());
    out.push_back(std::move(c));
  }
  return out;
}

std::vector<engine::SlotFeature> slots_from_proto(const google::protobuf::RepeatedPtrField<pb::SlotFeature>& in) {
  std::vector<engine::SlotFeature> out;
  out.reserve(static_cast<std::size_t>(in.size()));
  for (const pb::SlotFeature& f : in) {
    engine::SlotFeature c;
    c.name = f.name();
    c.origin = Vec3(f.origin().x_mm(), f.origin().y_mm(), f.origin().z_mm());
    c.across = Vec3(f.across().x(), f.across().y(), f.across().z());
    c.along = Vec3(f.along().x(), f.along().y(), f.along().z());
    c.width_mm = f.width_mm();
    c.half_length_mm = f.half_length_mm();
    c.half_depth_mm = f.half_depth_mm();
    c.triangles.assign(f.triangles().begin(), f.triangles().end());
    out.push_back(std::move(c));
  }
  return out;
}

void element_to_proto(const FixtureElement& e, pb::FixtureElementInfo* out) {
  out->set_element_id(e.id);
  out->set_triangles(e.mesh->mesh().triangle_count());
  out->set_cad(e.is_cad());
  out->set_deflection_mm(e.part ? e.part->deflection_mm : 0.0);
  for (const CylinderFeature& f : e.features) {
    pb::CylinderFeature* p = out->add_features();
    p->set_name(f.name);
    to_proto(f.origin, p->mutable_origin());
    if (auto axis = Direction::of(f.axis)) to_proto(*axis, p->mutable_axis());
    p->set_radius_mm(f.radius_mm);
    p->set_half_length_mm(f.half_length_mm);
    p->set_hole(f.hole);
    p->set_deviation_mm(f.deviation_mm);
  }
  for (const engine::SlotFeature& f : e.slots) {
    pb::SlotFeature* p = out->add_slots();
    p->set_name(f.name);
    to_proto(f.origin, p->mutable_origin());
    if (auto across = Direction::of(f.across)) to_proto(*across, p->mutable_across());
    if (auto along = Direction::of(f.along)) to_proto(*along, p->mutable_along());
    p->set_width_mm(f.width_mm);
    p->set_half_length_mm(f.half_length_mm);
    p->set_half_depth_mm(f.half_depth_mm);
    p->set_deviation_mm(f.deviation_mm);
  }
}

void frame_to_proto(const AssemblyFrame& frame, pb::FixtureFrameResult* out) {
  out->set_verdict(to_proto(frame.verdict));
  for (const engine::AssemblyContact& c : frame.contacts) {
    pb::FixtureContact* p = out->add_contacts();
    p->set_element_id(c.element_id);
    p->set_verdict(to_proto(c.verdict));
    to_proto(c.point, p->mutable_point());
    p->set_between_frames(c.between_frames);
    p->set_motion_fraction(c.motion_s);
    p->set_intended(c.intended);
    p->set_why(c.why);
    p->set_inconclusive_reason(to_proto(c.inconclusive_reason));
    p->set_decided_on_brep(c.decided_on_brep);
  }
  pb::FixtureWork* w = out->mutable_work();
  w->set_bounding_volume_tests(frame.work.bounding_volume_tests());
  w->set_triangle_pairs(frame.work.triangle_pairs);
  w->set_exact_checks(frame.work.exact_checks);
  w->set_sweep_steps(frame.work.sweep_steps);
}

void error_to_proto(const Error& e, pb::FixtureStepError* out) {
  out->set_code(static_cast<int>(to_status(e).error_code()));
  out->set_field(e.field);
  out->set_message(e.message);
}

// The session names the element it was given "element" (assembled) or "moving" (begin_moving),
// its id "id": on the wire they are the step's element and its element_id.
Error on_the_wire(Error e, const std::string& step, const std::string& element) {
  const auto starts = [&](const char* p) { return e.field.rfind(p, 0) == 0; };
  for (const char* own : {"element", "moving"}) {
    const std::string id = std::string(own) + ".id";
    if (starts(id.c_str())) {
      e.field = element + ".element_id" + e.field.substr(id.size());
      return e;
    }
    if (starts(own)) {
      e.field = element + e.field.substr(std::string(own).size());
      return e;
    }
  }
  e.field = e.field.empty() ? step : step + "." + e.field;
  return e;
}

class FixtureReactor final : public grpc::ServerBidiReactor<pb::FixtureRequest, pb::FixtureReply> {
 public:
  FixtureReactor(GatekeeperService& service, grpc::CallbackServerContext* ctx)
      : service_(service), ctx_(ctx), call_(begin_call(ctx, "AssembleFixture")) {
    StartRead(&request_);
  }
  void OnReadDone(bool ok) override {
    if (!ok) return end(ctx_->IsCancelled() ? grpc::Status(grpc::StatusCode::CANCELLED, "cancelled by the client") : grpc::Status::OK);
    const Call step = begin_frame(call_, request_.has_frame() ? "AssembleFixture.frame" : "AssembleFixture.step");
    // Loading a part, deciding on exact faces: milliseconds to seconds, never on gRPC's threads.
    if (!service_.scene_pool().try_submit([this, step] { answer(step); })) {
      service_.stats().record(step.method, us_since(step.t0), true);
      end({grpc::StatusCode::RESOURCE_EXHAUSTED, "AssembleFixture: too much scene work queued, retry later"});
    }
  }
  void OnWriteDone(bool ok) override {
    if (!ok) return end({grpc::StatusCode::CANCELLED, "the client went away"});
    StartRead(&request_);
  }
  void OnDone() override { delete this; }

 private:
  void answer(const Call& step) {
    if (ctx_->IsCancelled()) {
      service_.stats().record(step.method, us_since(step.t0), true);
      return end({grpc::StatusCode::CANCELLED, "cancelled by the client"});
    }
    reply_.Clear();
    const StopToken stop([this] { return ctx_->IsCancelled() || past_deadline(ctx_); });
    std::optional<Error> refused;
    const grpc::Status s = guarded_status(step, [&]() -> grpc::Status {
      auto done = take(request_, stop);
      if (done.ok()) return grpc::Status::OK;
      // A stopped frame (cancel, deadline) ends the stream; anything else is refused in-band.
      if (done.error().code == ErrorCode::kStopped) return to_status(done.error());
      refused = done.error();
      return grpc::Status::OK;
    });
    service_.stats().record(step.method, us_since(step.t0), !s.ok() || refused.has_value());
    if (!s.ok()) return end(s);
    if (refused) error_to_proto(*refused, reply_.mutable_error());
    reply_.set_assembled(static_cast<std::uint32_t>(session_ ? session_->assembled() : 0));
    StartWrite(&reply_);
  }

  // One step; its answer goes to reply_.
  Result<bool> take(const pb::FixtureRequest& r, const StopToken& stop) {
    if (r.step_case() == pb::FixtureRequest::STEP_NOT_SET) return invalid_argument("step", "no step set");
    if (r.has_start()) {
      if (session_) return Error{ErrorCode::kFailedPrecondition, "start", "the session has started already"};
      const StoredPose plate = to_stored_pose(r.start().plate());
      auto pose = engine::checked_pose(plate.translation, plate.axis, plate.angle_deg, "start.plate");
      if (!pose.ok()) return pose.error();
      session_ = std::make_unique<AssemblySession>(pose.value().transform().rotation);
      return true;
    }
    if (!session_) return Error{ErrorCode::kFailedPrecondition, "start", "the first message must start the session"};
    switch (r.step_case()) {
      case pb::FixtureRequest::kAssemble: {
        if (session_->assembled() >= kMaxAssembledElements)
          return Error{ErrorCode::kResourceExhausted, "assemble", "a session holds at most " + std::to_string(kMaxAssembledElements) + " elements"};
        auto element = element_of(r.assemble(), "assemble");
        if (!element.ok()) return element.error();
        element_to_proto(element.value(), reply_.mutable_element());
        auto added = session_->assemble(std::move(element).value());
        if (!added.ok()) return on_the_wire(added.error(), "assemble", "assemble");
        return true;
      }
      case pb::FixtureRequest::kDisassemble: {
        auto removed = session_->disassemble(r.disassemble());
        if (!removed.ok()) return Error{removed.error().code, "disassemble", removed.error().message};
        return true;
      }
      case pb::FixtureRequest::kBeginMoving: {
        auto element = element_of(r.begin_moving().element(), "begin_moving.element");
        if (!element.ok()) return element.error();
        std::vector<Mate> mates;
        for (const pb::Mate& m : r.begin_moving().mates())
          mates.push_back({m.moving_feature(), m.element_id(), m.element_feature(), {m.clearance_mm(), m.tolerance_mm()}});
        element_to_proto(element.value(), reply_.mutable_element());
        auto begun = session_->begin_moving(std::move(element).value(), std::move(mates));
        if (!begun.ok()) return on_the_wire(begun.error(), "begin_moving", "begin_moving.element");
        return true;
      }
      case pb::FixtureRequest::kFrame: {
        const StoredPose stored = to_stored_pose(r.frame().pose());
        auto pose = engine::checked_pose(stored.translation, stored.axis, stored.angle_deg, "frame.pose");
        if (!pose.ok()) return pose.error();
        const Clock::time_point t0 = Clock::now();
        auto frame = session_->frame(pose.value().transform(), stop, !r.frame().pose_only());
        if (!frame.ok()) return on_the_wire(frame.error(), "frame", "frame");
        frame_to_proto(frame.value(), reply_.mutable_frame());
        reply_.mutable_frame()->set_elapsed_us(us_since(t0));
        return true;
      }
      default: return invalid_argument("step", "unknown step");
    }
  }

  Result<FixtureElement> element_of(const pb::FixtureElement& e, const std::string& field) {
    return service_.engine().fixture_element(e.element_id(), e.part_id(), to_stored_pose(e.pose()), features_from_proto(e.features()),
                                             field, slots_from_proto(e.slots()));
  }

  void end(const grpc::Status& status) {
    end_call(service_.stats(), call_, status);
    Finish(status);
  }

  GatekeeperService& service_;
  grpc::CallbackServerContext* ctx_;
  const Call call_;
  pb::FixtureRequest request_;
  pb::FixtureReply reply_;
  std::unique_ptr<AssemblySession> session_;
};

}  // namespace

grpc::ServerBidiReactor<pb::FixtureRequest, pb::FixtureReply>* GatekeeperService::AssembleFixture(grpc::CallbackServerContext* ctx) {
  if (auto allowed = require_role(ctx, Role::kRead); !allowed.ok()) {
    end_call(stats_, begin_call(ctx, "AssembleFixture"), allowed);
    return new RefusedStream<grpc::ServerBidiReactor<pb::FixtureRequest, pb::FixtureReply>>(allowed);
  }
  return new FixtureReactor(*this, ctx);
}

}  // namespace gk::server
