// The gatekeeper without gRPC: every question the service answers, as plain requests and
// results with typed errors (an error names the field that was wrong). The daemon's server/
// translates its protocol to these calls and nothing else; tests, batch drivers and tools call
// them directly. It holds the stores (parts, scenes, machines) it is given and owns the audit
// jobs and the ValidateStep answer cache.
#pragma once

#include "engine/audits/audit_jobs.h"
#include "engine/clearance/clearance_query.h"
#include "engine/fixtures/part_elements.h"
#include "engine/machines/machine_registry.h"
#include "engine/parts/part_registry.h"
#include "engine/parts/part_store.h"
#include "engine/scenes/drag_session.h"
#include "engine/scenes/scene_store.h"
#include "engine/steps/step_answers.h"
#include "kernel/core/stop_token.h"
#include "kernel/mesh/display_decimation.h"

#include <memory>
#include <set>
#include <string>
#include <vector>

namespace gk::engine {

struct EngineOptions {
  AuditJobs::Options audits;
  int audit_threads = 2;                  // threads of one audit job (an audit asking for 0)
  std::size_t step_answers_kept = 100000;  // the ValidateStep answer cache
};

// A stored object with its contacts at its new place.
struct PlacedMove {
  std::string object_id;
  MoveOutcome outcome;
};

class Engine {
 public:
  // archive may be null: ended audits then live in memory only. checkpoints may be null: a
  // running audit is then lost when the daemon stops (with them it resumes: resume_audits()).
  // statuses may be null: clashes then keep no review status (SetClashStatus is refused).
  Engine(MachineRegistry& machines, PartRegistry& parts, SceneStore& scenes, EndedAudits* archive, EngineOptions options = {},
         AuditCheckpoints* checkpoints = nullptr, ClashStatuses* statuses = nullptr);

  // --- ValidateStep
  StepAnswers& steps() { return steps_; }

  // --- ClearanceQuery
  Result<ClearanceResult> clearance(const ClearanceRequest& request, const StopToken& stop = {});

  // --- parts: an upload is begun (its header checked), fed, then finished (hash checked, the
  // file read and described, recorded durably).
  Result<std::unique_ptr<PartUpload>> begin_upload(const std::string& name, const std::string& format, std::uint64_t size_bytes,
                                                   const std::string& sha256_hex);
  Result<PartRecord> finish_upload(std::unique_ptr<PartUpload> upload);
  Result<PartRecord> part(const std::string& part_id) const;
  // A part's triangles thinned for drawing (a report page), at most max_triangles.
  Result<DisplayMesh> display_mesh(const std::string& part_id, std::size_t max_triangles);

  // --- machines
  std::vector<MachineSnapshot> machines() const { return machines_.list(); }
  Result<MachineSnapshot> machine(const std::string& machine_id) const;  // "" : the default
  Result<MachineSnapshot> set_machine_state(const std::string& machine_id, const p4::MachineState& state);
  Result<MachineSnapshot> put_machine_model(const std::string& machine_id, const std::string& model_toml);

  // --- scenes
  Result<SceneRecord> create_scene(const std::string& name);
  Result<SceneRecord> scene(const std::string& scene_id) const { return scenes_.get(scene_id); }
  // Stores the object (an empty id gets a new one), then answers its contacts as a move would;
  // taken back when the answer fails (see answer_stored_edit).
  Result<PlacedMove> put_object(const std::string& scene_id, SceneObjectRecord object, double clearance_mm,
                                const StopToken& stop = {});
  // All or nothing: every object is checked (fields named objects[i]...) before any is stored.
  Result<std::vector<SceneObjectRecord>> put_objects(const std::string& scene_id, std::vector<SceneObjectRecord> objects);
  // Poses are checked here (engine::checked_pose), whoever calls.
  // Stores the pose, then answers the contacts at it (through the drag's session when there is
  // one); taken back when the answer fails. A drag's poses are logged, not synced one by one
  // (they survive the daemon being killed; WriteDurability in engine/scenes/scene_store).
  Result<MoveOutcome> move_object(const std::string& scene_id, const std::string& object_id, const StoredPose& pose,
                                  double clearance_mm, DragSession* drag = nullptr, const StopToken& stop = {});
  // A drag ended: every pose it logged is synced to the disk.
  Result<bool> end_drag();
  Result<SceneRecord> delete_object(const std::string& scene_id, const std::string& object_id);

  // --- fixture assembly (the session itself is engine/fixtures/assembly_session.h, one per client
  // stream): an element made of an uploaded part at a pose, its features those declared and, for a
  // CAD part, its cylinders and slots (engine/fixtures/part_elements.h). Errors name
  // field.element_id, .part_id, .pose, .features[i], .slots[i].
  Result<FixtureElement> fixture_element(const std::string& element_id, const std::string& part_id, const StoredPose& pose,
                                         std::vector<CylinderFeature> declared, const std::string& field,
                                         std::vector<SlotFeature> declared_slots = {});

  // --- audits
  Result<std::string> start_audit(const std::string& scene_id, const AuditOptions& asked, const std::string& baseline_job_id = "");
  Result<std::shared_ptr<AuditJob>> audit(const std::string& job_id) { return audits_.get(job_id); }
  AuditJobs& audits() { return audits_; }
  // A client's cancel (kept across a restart).
  Result<std::shared_ptr<AuditJob>> cancel_audit(const std::string& job_id) { return audits_.cancel(job_id); }
  // A clash's review status, set by a user (the scene and a clash an audit of it found), and
  // every clash's status in the scene.
  Result<ClashStatusRecord> set_clash_status(const std::string& scene_id, const std::string& clash_id, ClashStatus status);
  Result<std::vector<ClashStatusRecord>> clash_statuses(const std::string& scene_id) const;
  // Queues the audits a stopped or killed daemon left unfinished; returns how many.
  std::size_t resume_audits() { return audits_.resume_unfinished(); }

  // --- what the daemon reports about itself
  std::uint64_t parts_stored() const { return parts_.store().count(); }
  PartRegistry::MemoryStats part_memory() const { return parts_.memory_stats(); }

  // Stops the audit threads (running audits are interrupted and resume at the next start; without
  // checkpoints they end CANCELLED and are archived).
  void stop() { audits_.stop(); }

 private:
  Result<MoveOutcome> answer_stored_edit(const std::string& scene_id, const SceneObjectRecord& stored,
                                         const std::optional<SceneObjectRecord>& previous, double clearance_mm,
                                         const StopToken& stop);
  // Id, labels, pose and part of an object (known_parts: parts a batch has already looked up).
  // The pose is replaced by the checked one (its axis scaled).
  Result<bool> check_object(SceneObjectRecord& object, const std::string& field,
                            std::set<std::string>* known_parts = nullptr) const;

  MachineRegistry& machines_;
  PartRegistry& parts_;
  SceneStore& scenes_;
  EngineOptions options_;
  StepAnswers steps_;
  AuditJobs audits_;
  ClashStatuses* statuses_;
};

}  // namespace gk::engine
