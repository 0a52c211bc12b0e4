// Fixture assembly through the real daemon (AssembleFixture, seed 004): CAD elements uploaded as
// BREP files, a plate's holes and a pin's side found on their faces and mated by those names, a
// fast hand passing through a block between two clear frames, an overlap smaller than the
// tessellation, and refused steps that name their field and leave the session as it was. The
// oracle is OCCT on the whole placed shapes in this process (a Boolean common's volume), not the
// daemon's face-pair path.
#include "kernel/core/rigid_transform.h"
#include "occt_adapters/fixture_elements.h"
#include "occt_adapters/shape_builders.h"
#include "occt_adapters/shape_impl.h"
#include "tests/server/daemon_fixture.h"

#include <BRepAlgoAPI_Common.hxx>
#include <BRepGProp.hxx>
#include <BRepPrimAPI_MakeCylinder.hxx>
#include <BRepTools.hxx>
#include <GProp_GProps.hxx>
#include <gp_Ax2.hxx>

#include <gtest/gtest.h>

#include <cmath>
#include <sstream>

namespace gk {
namespace {

namespace pb = ::gatekeeper::v1;
using testing::Daemon;

std::string brep_of(const TopoDS_Shape& s) {
  std::ostringstream out;
  BRepTools::Write(s, out);
  return out.str();
}
TopoDS_Shape pin_shape(double r, double length) {
  return BRepPrimAPI_MakeCylinder(gp_Ax2(gp_Pnt(0, 0, 0), gp_Dir(0, 0, 1)), r, length).Shape();
}

double shared_volume(const TopoDS_Shape& a, const Vec3& at_a, const TopoDS_Shape& b, const Vec3& at_b) {
  const auto pa = occt::place(occt::wrap(a), RigidTransform::from_translation(at_a)).value();
  const auto pb = occt::place(occt::wrap(b), RigidTransform::from_translation(at_b)).value();
  BRepAlgoAPI_Common common(pa.impl().shape, pb.impl().shape);
  GProp_GProps props;
  BRepGProp::VolumeProperties(common.Shape(), props);
  return props.Mass();
}

void at(const Vec3& t, pb::Pose* pose) {
  pose->mutable_translation()->set_x_mm(t.x());
  pose->mutable_translation()->set_y_mm(t.y());
  pose->mutable_translation()->set_z_mm(t.z());
}

class Session {
 public:
  explicit Session(pb::Gatekeeper::Stub& stub) : stream_(stub.AssembleFixture(&ctx_)) {}
  pb::FixtureReply send(const pb::FixtureRequest& r) {
    EXPECT_TRUE(stream_->Write(r));
    pb::FixtureReply reply;
    EXPECT_TRUE(stream_->Read(&reply));
    return reply;
  }
  pb::FixtureReply start() {
    pb::FixtureRequest r;
    r.mutable_start()->mutable_plate();
    return send(r);
  }
  pb::FixtureReply assemble(const std::string& id, const std::string& part, const Vec3& t) {
    pb::FixtureRequest r;
    r.mutable_assemble()->set_element_id(id);
    r.mutable_assemble()->set_part_id(part);
    at(t, r.mutable_assemble()->mutable_pose());
    return send(r);
  }
  pb::FixtureReply begin(const std::string& id, const std::string& part, const Vec3& t, const std::vector<pb::Mate>& mates = {}) {
    pb::FixtureRequest r;
    r.mutable_begin_moving()->mutable_element()->set_element_id(id);
    r.mutable_begin_moving()->mutable_element()->set_part_id(part);
    at(t, r.mutable_begin_moving()->mutable_element()->mutable_pose());
    for (const pb::Mate& m : mates) *r.mutable_begin_moving()->add_mates() = m;
    return send(r);
  }
  pb::FixtureReply frame(const Vec3& t, bool pose_only = false) {
    pb::FixtureRequest r;
    at(t, r.mutable_frame()->mutable_pose());
    r.mutable_frame()->set_pose_only(pose_only);
    return send(r);
  }
  grpc::Status finish() {
    stream_->WritesDone();
    return stream_->Finish();
  }

 private:
  grpc::ClientContext ctx_;
  std::unique_ptr<grpc::ClientReaderWriter<pb::FixtureRequest, pb::FixtureReply>> stream_;
};

std::string feature(const pb::FixtureReply& r, bool hole, double radius, const Vec3& near = Vec3::Zero(), double within = 1e300) {
  for (const pb::CylinderFeature& f : r.element().features()) {
    const Vec3 o(f.origin().x_mm(), f.origin().y_mm(), f.origin().z_mm());
    if (f.hole() == hole && std::abs(f.radius_mm() - radius) < 1e-6 &&
        Vec3(o.x() - near.x(), o.y() - near.y(), 0.0).norm() <= within)
      return f.name();
  }
  return "";
}

TEST(FixtureE2E, CadElementsAreAssembledMatedAndCheckedBetweenFramesThroughTheDaemon) {
  Daemon daemon(testing::temp_dir("fixture-e2e"));
  auto stub = daemon.stub();
  // A 200 x 150 x 20 plate (top at z = 0) with 3 x 2 holes of 12 mm at x 50/100/150, y 50/100; a
  // 30 x 35 x 30 block on it; a pin fitting a hole with 0.05 mm clearance; a probe.
  const TopoDS_Shape plate = occt::base_plate(200, 150, 20, {3, 2, 50, 12}).value().impl().shape;
  const TopoDS_Shape block = occt::block_element(30, 35, 30, {}).value().impl().shape;
  const TopoDS_Shape pin = pin_shape(6.0 - 0.025, 40.0);
  const TopoDS_Shape probe = pin_shape(5.0, 20.0);
  const std::string plate_id = testing::upload_part_id(*stub, brep_of(plate), "brep");
  const std::string block_id = testing::upload_part_id(*stub, brep_of(block), "brep");
  const std::string pin_id = testing::upload_part_id(*stub, brep_of(pin), "brep");
  const std::string probe_id = testing::upload_part_id(*stub, brep_of(probe), "brep");
  const Vec3 block_at(110, 110, 0);

  Session s(*stub);
  // Before the start: refused, naming it.
  pb::FixtureReply early = s.frame(Vec3::Zero());
  ASSERT_TRUE(early.has_error());
  EXPECT_EQ(early.error().code(), static_cast<int>(grpc::StatusCode::FAILED_PRECONDITION));
  EXPECT_EQ(early.error().field(), "start");
  ASSERT_FALSE(s.start().has_error());

  const pb::FixtureReply plate_reply = s.assemble("plate", plate_id, Vec3::Zero());
  ASSERT_FALSE(plate_reply.has_error()) << plate_reply.error().message();
  EXPECT_TRUE(plate_reply.element().cad());
  const std::string hole = feature(plate_reply, true, 6.0, Vec3(50, 50, 0), 1e-6);
  ASSERT_FALSE(hole.empty()) << "the hole at (50, 50) is a feature of the plate";
  ASSERT_FALSE(s.assemble("block", block_id, block_at).has_error());
  EXPECT_EQ(s.assemble("block", block_id, block_at).error().field(), "assemble.element_id");  // already assembled
  // Refused steps change nothing: an unknown part, a malformed part id, a NaN pose.
  const pb::FixtureReply unknown = s.assemble("ghost", std::string(64, 'a'), Vec3::Zero());
  EXPECT_EQ(unknown.error().code(), static_cast<int>(grpc::StatusCode::NOT_FOUND));
  EXPECT_EQ(unknown.error().field(), "assemble.part_id");
  const pb::FixtureReply malformed = s.assemble("ghost", "../../etc/passwd", Vec3::Zero());
  EXPECT_EQ(malformed.error().code(), static_cast<int>(grpc::StatusCode::INVALID_ARGUMENT));
  EXPECT_EQ(malformed.error().field(), "assemble.part_id");
  const pb::FixtureReply bad_id = s.assemble("no spaces allowed", block_id, Vec3::Zero());
  EXPECT_EQ(bad_id.error().field(), "assemble.element_id");
  const pb::FixtureReply nan = s.assemble("nan", block_id, Vec3(std::nan(""), 0, 0));
  EXPECT_EQ(nan.error().code(), static_cast<int>(grpc::StatusCode::INVALID_ARGUMENT));
  EXPECT_EQ(nan.error().field().rfind("assemble.pose", 0), 0u) << nan.error().field();
  EXPECT_EQ(nan.assembled(), 2u);

  // The pin, its side found on its face, mated with the hole.
  pb::FixtureReply pin_reply = s.begin("pin", pin_id, Vec3(50, 50, 60));
  ASSERT_FALSE(pin_reply.has_error()) << pin_reply.error().message();
  const std::string side = feature(pin_reply, false, 6.0 - 0.025);
  ASSERT_FALSE(side.empty());
  pb::Mate mate;
  mate.set_moving_feature(side);
  mate.set_element_id("plate");
  mate.set_element_feature(hole);
  mate.set_clearance_mm(0.05);
  mate.set_tolerance_mm(0.02);
  pb::Mate bad_mate = mate;
  bad_mate.set_element_feature("face.99999");
  const pb::FixtureReply refused = s.begin("pin", pin_id, Vec3(50, 50, 60), {bad_mate});
  EXPECT_EQ(refused.error().field(), "begin_moving.mates[0].element_feature");
  ASSERT_FALSE(s.begin("pin", pin_id, Vec3(50, 50, 60), {mate}).has_error());
  // Down into the hole: clear all the way (the fit's contact is intended); the oracle agrees no
  // volume is shared at the last pose.
  for (double z : {40.0, 20.0, 5.0, -5.0, -15.0}) {
    const pb::FixtureReply f = s.frame(Vec3(50, 50, z));
    ASSERT_TRUE(f.has_frame()) << f.error().message();
    EXPECT_EQ(f.frame().verdict(), pb::CLEAR) << "z " << z;
    for (const pb::FixtureContact& c : f.frame().contacts()) EXPECT_TRUE(c.intended()) << c.element_id() << " " << c.why();
  }
  EXPECT_LT(shared_volume(pin, Vec3(50, 50, -15), plate, Vec3::Zero()), 1e-9);
  // A NaN frame is refused, naming it; the next frame is still answered.
  const pb::FixtureReply nan_frame = s.frame(Vec3(50, std::nan(""), 0));
  EXPECT_EQ(nan_frame.error().field().rfind("frame.pose", 0), 0u) << nan_frame.error().field();
  EXPECT_EQ(s.frame(Vec3(50, 50, -15)).frame().verdict(), pb::CLEAR);

  // The probe, left of the block, then right of it in one frame: both poses clear, the motion
  // passes through the block (the oracle: the middle pose shares volume with it).
  ASSERT_FALSE(s.begin("probe", probe_id, Vec3(100, 127, 5)).has_error());
  const Vec3 left(100, 127, 5), right(150, 127, 5);
  EXPECT_LT(shared_volume(probe, right, block, block_at), 1e-9);
  EXPECT_GT(shared_volume(probe, 0.5 * (left + right), block, block_at), 1.0);
  const pb::FixtureReply pass = s.frame(right);
  ASSERT_TRUE(pass.has_frame());
  EXPECT_EQ(pass.frame().verdict(), pb::COLLISION);
  bool between = false;
  for (const pb::FixtureContact& c : pass.frame().contacts())
    between = between || (c.element_id() == "block" && c.between_frames() && c.verdict() == pb::COLLISION);
  EXPECT_TRUE(between);
  const pb::FixtureReply seed004 = s.frame(left, true);  // the same motion back, pose only: seed 004 sees nothing
  EXPECT_EQ(seed004.frame().verdict(), pb::CLEAR);
  // Against the block's face (x = 110) by 0.01 mm in and out: decided on the exact faces.
  for (double offset : {-0.01, 0.01}) {
    const Vec3 p(110.0 - 5.0 - offset, 127, 5);
    const pb::FixtureReply f = s.frame(p, true);
    ASSERT_TRUE(f.has_frame());
    const bool shares = shared_volume(probe, p, block, block_at) > 1e-9;
    EXPECT_EQ(shares, offset < 0.0);
    EXPECT_EQ(f.frame().verdict(), shares ? pb::COLLISION : pb::CLEAR) << "offset " << offset;
  }
  // Taken away, the block is no longer met.
  pb::FixtureRequest away;
  away.set_disassemble("block");
  EXPECT_EQ(s.send(away).assembled(), 1u);
  EXPECT_EQ(s.frame(Vec3(125, 127, 5), true).frame().verdict(), pb::CLEAR);
  away.set_disassemble("block");
  EXPECT_EQ(s.send(away).error().code(), static_cast<int>(grpc::StatusCode::NOT_FOUND));
  EXPECT_TRUE(s.finish().ok());
}

}  // namespace
}  // namespace gk

namespace gk {
namespace {

// A bolt's shank into a T-slot through the daemon: the plate's slots come back with the element
// (found on its faces), the shank mated with the narrow slot at y = 50 goes down into it CLEAR
// against its wall, and the same shank 0.15 mm too large for the fit is a collision; OCCT's common
// on the whole shapes agrees.
TEST(FixtureE2E, ABoltShankIsMatedWithATSlotFoundOnTheUploadedPlate) {
  Daemon daemon(testing::temp_dir("fixture-slot-e2e"));
  auto stub = daemon.stub();
  const TopoDS_Shape plate = occt::base_plate(200, 150, 20, {0, 0, 50, 12}, 2, 14.0).value().impl().shape;
  const std::string plate_id = testing::upload_part_id(*stub, brep_of(plate), "brep");
  Session s(*stub);
  ASSERT_FALSE(s.start().has_error());
  const pb::FixtureReply assembled = s.assemble("plate", plate_id, Vec3::Zero());
  ASSERT_FALSE(assembled.has_error()) << assembled.error().message();
  std::string slot;
  for (const pb::SlotFeature& f : assembled.element().slots())
    if (std::abs(f.width_mm() - 14.0) < 1e-9 && std::abs(f.origin().y_mm() - 50.0) < 1e-9) slot = f.name();
  ASSERT_FALSE(slot.empty()) << "the narrow slot at y = 50 is a feature of the plate";
  for (const double radius : {6.9, 7.0}) {
    const TopoDS_Shape shank = pin_shape(radius, 25.0);
    const std::string shank_id = testing::upload_part_id(*stub, brep_of(shank), "brep");
    const pb::FixtureReply held = s.begin("bolt" + std::to_string(static_cast<int>(radius * 10)), shank_id, Vec3(100, 50.05, 30));
    ASSERT_FALSE(held.has_error()) << held.error().message();
    const std::string side = feature(held, false, radius);
    pb::Mate mate;
    mate.set_moving_feature(side);
    mate.set_element_id("plate");
    mate.set_element_feature(slot);
    mate.set_clearance_mm(0.2);
    mate.set_tolerance_mm(0.05);
    ASSERT_FALSE(s.begin("bolt" + std::to_string(static_cast<int>(radius * 10)), shank_id, Vec3(100, 50.05, 30), {mate}).has_error());
    const Vec3 down(100, 50.05, -5);
    const pb::FixtureReply f = s.frame(down);
    ASSERT_TRUE(f.has_frame()) << f.error().message();
    const bool shares = shared_volume(shank, down, plate, Vec3::Zero()) > 1e-9;
    EXPECT_EQ(shares, radius > 6.96) << "radius " << radius;
    EXPECT_EQ(f.frame().verdict(), radius < 6.96 ? pb::CLEAR : pb::COLLISION) << "radius " << radius;
  }
  EXPECT_TRUE(s.finish().ok());
}

}  // namespace
}  // namespace gk
