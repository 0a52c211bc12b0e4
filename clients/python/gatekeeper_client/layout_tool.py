"""A layout-tool session against gatekeeperd: upload meshes, build a scene, drag an object through
it (every frame answered), ask for a clearance, and audit the scene with a progress bar.

    gatekeeper-layout-tool [--address 127.0.0.1:50051] --data ../shared/data (or GATEKEEPER_SHARED_DATA)
        [--report audit.html]   (the audit's page: 3D view and sortable clash table)
"""
import argparse
import hashlib
import os
import sys

from gatekeeper_client.connection import add_connection_arguments, connect_from_arguments, pb, read_audit_report

# An installed package does not know where the checkout's ../shared/data is: the caller says.
DEFAULT_DATA = os.environ.get("GATEKEEPER_SHARED_DATA")


def upload(stub, path):
    with open(path, "rb") as f:
        data = f.read()
    fmt = os.path.splitext(path)[1][1:].lower()
    header = pb.UploadHeader(name=os.path.basename(path), format=fmt, size_bytes=len(data), sha256=hashlib.sha256(data).hexdigest())

    def chunks():
        yield pb.UploadPartChunk(header=header)
        for at in range(0, len(data), 1 << 20):
            yield pb.UploadPartChunk(data=data[at:at + (1 << 20)])

    return stub.UploadPart(chunks(), timeout=120)


def pose(x, y=0.0, z=0.0, deg=0.0):
    return pb.Pose(translation=pb.Vec3(x_mm=x, y_mm=y, z_mm=z), rotation_axis=pb.Vec3(z_mm=1.0), rotation_deg=deg)


def progress_bar(p, width=30):
    done = p.pairs_done / p.pairs_total if p.pairs_total else 1.0
    filled = int(done * width)
    return f"[{'#' * filled}{'.' * (width - filled)}] {p.pairs_done}/{p.pairs_total} pairs, {p.clashes} clashes, eta {p.eta_s:.1f} s"


def main(argv=None):
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    add_connection_arguments(parser)
    parser.add_argument("--data", default=DEFAULT_DATA, required=DEFAULT_DATA is None,
                        help="the shared data directory (default: $GATEKEEPER_SHARED_DATA)")
    parser.add_argument("--report", help="write the audit report page (HTML) here")
    args = parser.parse_args(argv)
    stub, _ = connect_from_arguments(args)
    robot = upload(stub, os.path.join(args.data, "meshes", "fcl", "rob.obj"))
    motor = upload(stub, os.path.join(args.data, "meshes", "occt", "motor.stl"))
    print(f"uploaded robot ({robot.triangles} triangles) and motor ({motor.triangles} triangles)")
    scene = stub.CreateScene(pb.CreateSceneRequest(name="layout demo"), timeout=5)
    placed = {}
    for name, part, p in [("robot.1", robot, pose(0)), ("robot.2", robot, pose(2500)), ("robot.3", robot, pose(5000, deg=90)),
                          ("motor.1", motor, pose(1250, 1500))]:
        r = stub.PutObject(pb.PutObjectRequest(scene_id=scene.scene_id, clearance_mm=50.0,
                                               object=pb.SceneObject(name=name, category=name.split(".")[0], part_id=part.part_id, pose=p)),
                           timeout=10)
        placed[name] = r.object_id
        print(f"put {name}: {pb.Verdict.Name(r.verdict)}")

    # Drag robot.2 from x = 2500 towards robot.1 and back, one frame per move.
    frames = [pose(2500 - 150 * k) for k in range(12)] + [pose(800 + 200 * k) for k in range(8)]

    def moves():
        for p in frames:
            yield pb.MoveObjectRequest(scene_id=scene.scene_id, object_id=placed["robot.2"], pose=p, clearance_mm=50.0)

    print("dragging robot.2:")
    for p, result in zip(frames, stub.DragObject(moves(), timeout=60)):
        names = ", ".join(f"{c.other_object_id[:12]} {pb.Verdict.Name(c.verdict)} {c.distance_mm:.1f} mm" for c in result.contacts)
        print(f"  x={p.translation.x_mm:7.1f}  {pb.Verdict.Name(result.verdict):10s} {result.elapsed_us:7.0f} us  {names}")

    c = stub.ClearanceQuery(pb.ClearanceQueryRequest(a=pb.PosedPart(part_id=robot.part_id),
                                                     b=pb.PosedPart(part_id=robot.part_id, pose=pose(1800)),
                                                     safety_gap_mm=1000.0), timeout=30)
    print(f"clearance robot vs robot 1800 mm apart: {c.distance_mm:.3f} mm ({pb.Verdict.Name(c.verdict)}), "
          f"{c.pairs_within_gap} triangle pairs closer than 1000 mm, {c.elapsed_us:.0f} us")

    # Robots may touch each other inside one cell (an intended contact): a rule leaves them out.
    rule = pb.ContactRule(name="robots of one cell", category_a="robot", category_b="robot", same_group_only=True)
    job = stub.StartAudit(pb.StartAuditRequest(scene_id=scene.scene_id, clearance_mm=100.0, rules=[rule]), timeout=5)
    last = None
    for p in stub.WatchAudit(pb.WatchAuditRequest(job_id=job.job_id), timeout=120):
        last = p
        print("\r  audit " + progress_bar(p), end="", flush=True)
    print()
    report = read_audit_report(stub, job.job_id)
    print(f"audit {pb.AuditState.Name(report.progress.state)}: {len(report.clashes)} clashes "
          f"({report.candidate_pairs} box pairs, {report.excluded_by_rules} excluded by rules)")
    for clash in report.clashes:
        print(f"  {clash.name_a} x {clash.name_b}: {pb.Verdict.Name(clash.verdict)} {clash.distance_mm:.1f} mm")
    for group in report.by_category:
        print(f"  {group.key}: {group.clashes} clashes, {group.collisions} collisions")
    if args.report:
        page = stub.GetAuditReport(pb.GetAuditReportRequest(job_id=job.job_id, html=True, page_size=1), timeout=60)
        with open(args.report, "w", encoding="utf-8") as out:
            out.write(page.html)
        print(f"report page: {args.report}")
    return 0 if last is not None and report.progress.state == pb.DONE else 1


if __name__ == "__main__":
    sys.exit(main())
