// FCL 0.7 as the peer of the kernel's queries: a mesh as FCL's OBBRSS model (the same vertex and
// face arrays) and a pose as FCL's transform. Header-only: only targets that link FCL include it.
#pragma once

#include "kernel/core/rigid_transform.h"
#include "kernel/mesh/triangle_mesh.h"

#include <fcl/geometry/bvh/BVH_model.h>
#include <fcl/math/bv/OBBRSS.h>

#include <memory>
#include <vector>

namespace gk::testing {

using FclModel = fcl::BVHModel<fcl::OBBRSSd>;

// The mesh as an FCL model of any bounding volume (OBBRSS, or OBB: the RAPID-style peer).
template <typename BV>
std::shared_ptr<fcl::BVHModel<BV>> make_fcl_bvh(const TriangleMesh& mesh) {
  auto model = std::make_shared<fcl::BVHModel<BV>>();
  std::vector<fcl::Vector3d> points;
  for (const Vec3& v : mesh.vertices()) points.emplace_back(v.x(), v.y(), v.z());
  std::vector<fcl::Triangle> triangles;
  for (const auto& f : mesh.faces()) triangles.emplace_back(f[0], f[1], f[2]);
  model->beginModel();
  model->addSubModel(points, triangles);
  model->endModel();
  return model;
}

inline std::shared_ptr<FclModel> make_fcl_model(const TriangleMesh& mesh) { return make_fcl_bvh<fcl::OBBRSSd>(mesh); }

inline fcl::Transform3d to_fcl(const RigidTransform& pose) {
  fcl::Transform3d out = fcl::Transform3d::Identity();
  out.linear() = pose.rotation;
  out.translation() = pose.translation;
  return out;
}

}  // namespace gk::testing
