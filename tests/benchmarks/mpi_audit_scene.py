"""A scene for measuring gatekeeper-audit over MPI (docs/PERFORMANCE.md, "Distributed audit"):
N machines (TR12J 67,498 triangles, motor 13,500, video_part 9,694) on a jittered grid at PITCH mm,
turned at random about z, most touching or overlapping a neighbour. Uploads through a running
gatekeeperd with gatekeeper-cli, prints the scene id.

    python3 tests/benchmarks/mpi_audit_scene.py PORT 1500 430
"""
import json
import os
import random
import subprocess
import sys
port, n, pitch = sys.argv[1], int(sys.argv[2]), float(sys.argv[3])
cli = [os.path.join(os.path.dirname(__file__), "../../build/clients/gatekeeper-cli"), "--address", "127.0.0.1:" + port, "--timeout", "600"]
parts = []
for f in ["occt/TR12J_OCC64K.stl", "occt/motor.stl", "occt/video_part.stl"]:
    parts.append(json.loads(subprocess.check_output(cli + ["upload", os.path.join(os.path.dirname(__file__), "../../../shared/data/meshes", f)]))["partId"])
scene = json.loads(subprocess.check_output(cli + ["create-scene"]))["sceneId"]
rng = random.Random(20261126)
side = int(n ** 0.5 + 0.999)
objs = []
for i in range(n):
    x, y = pitch * (i % side) + rng.uniform(-60, 60), pitch * (i // side) + rng.uniform(-60, 60)
    objs.append({"name": "m%d" % i, "category": "machine", "partId": rng.choice(parts),
                 "pose": {"translation": {"xMm": x, "yMm": y, "zMm": 0}, "rotationAxis": {"zMm": 1}, "rotationDeg": rng.uniform(0, 360)}})
for at in range(0, len(objs), 100):
    subprocess.run(cli + ["put-objects", json.dumps({"sceneId": scene, "objects": objs[at:at + 100]})], check=True, stdout=subprocess.DEVNULL)
print(scene)
