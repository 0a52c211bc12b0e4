"""The Python client against the real gatekeeperd on a loopback port (Debian's python3-grpcio).

Run by ../run_tests.sh on the package as pip-installed into a throwaway venv."""
import hashlib
import os
import signal
import subprocess
import tempfile
import time
import unittest

import grpc

from gatekeeper_client import layout_tool, sequencer_sim
from gatekeeper_client.connection import connect, pb

DAEMON = os.environ.get("GATEKEEPERD", os.path.join(os.path.dirname(__file__), "..", "..", "..", "build", "server", "gatekeeperd"))
SHARED = os.environ.get("GATEKEEPER_SHARED_DATA", os.path.join(os.path.dirname(__file__), "..", "..", "..", "..", "shared", "data"))


class DaemonTest(unittest.TestCase):
    @classmethod
    def setUpClass(cls):
        cls.data = tempfile.mkdtemp(prefix="gk-py-e2e-")
        port_file = os.path.join(cls.data, "port")
        cls.proc = subprocess.Popen([DAEMON, "--listen", "127.0.0.1:0", "--data-dir", cls.data, "--port-file", port_file,
                                     "--log-level", "warn", "--drain-seconds", "1"])
        port = ""
        for _ in range(400):
            if os.path.exists(port_file):
                with open(port_file) as f:
                    port = f.read().strip()
                if port:
                    break
            time.sleep(0.025)
        else:
            cls.proc.kill()
            raise RuntimeError(f"{DAEMON} wrote no port file in 10 s")
        cls.address = "127.0.0.1:" + port
        cls.stub, cls.channel = connect(cls.address)

    @classmethod
    def tearDownClass(cls):
        cls.channel.close()
        cls.proc.send_signal(signal.SIGTERM)
        assert cls.proc.wait(timeout=30) == 0

    def bend(self, flange, angle=90.0):
        return pb.ValidateStepRequest(
            part=pb.SheetPart(width_mm=1000, depth_mm=800, thickness_mm=1.5),
            state=pb.MachineState(clamp_z_mm=1.5, manipulator_y_mm=-400),
            step=pb.Step(kind=pb.BEND_UP, bend_point=pb.Vec2(y_mm=800 - flange), bend_direction=pb.Vec2(x_mm=1),
                         target_angle_deg=angle))

    def test_validate_step_clear_collision_and_bad_input(self):
        self.assertEqual(self.stub.ValidateStep(self.bend(150), timeout=10).verdict, pb.CLEAR)
        tall = self.stub.ValidateStep(self.bend(300), timeout=10)
        self.assertEqual(tall.verdict, pb.COLLISION)
        self.assertEqual(tall.collisions[0].organ, "upper_beam")
        with self.assertRaises(grpc.RpcError) as err:
            self.stub.ValidateStep(self.bend(150, angle=float("nan")), timeout=10)
        self.assertEqual(err.exception.code(), grpc.StatusCode.INVALID_ARGUMENT)
        self.assertIn("target_angle_deg", err.exception.details())

    def test_streamed_upload_and_part_info(self):
        with open(os.path.join(SHARED, "meshes", "fcl", "rob.obj"), "rb") as f:
            data = f.read()
        header = pb.UploadHeader(name="rob.obj", format="obj", size_bytes=len(data), sha256=hashlib.sha256(data).hexdigest())

        def chunks():
            yield pb.UploadPartChunk(header=header)
            for at in range(0, len(data), 4096):
                yield pb.UploadPartChunk(data=data[at:at + 4096])

        info = self.stub.UploadPart(chunks(), timeout=30)
        self.assertEqual(info.triangles, 216)
        self.assertEqual(self.stub.GetPartInfo(pb.GetPartInfoRequest(part_id=info.part_id), timeout=5).part_id, info.part_id)
        with self.assertRaises(grpc.RpcError) as err:
            self.stub.GetPartInfo(pb.GetPartInfoRequest(part_id="0" * 64), timeout=5)
        self.assertEqual(err.exception.code(), grpc.StatusCode.NOT_FOUND)

    def test_layout_tool_session(self):
        with tempfile.TemporaryDirectory() as tmp:
            page = os.path.join(tmp, "audit.html")
            self.assertEqual(layout_tool.main(["--address", self.address, "--data", SHARED, "--report", page]), 0)
            with open(page, encoding="utf-8") as f:
                html = f.read()
            self.assertIn('<canvas id="canvas">', html)
            self.assertIn("layout demo", html)

    def test_sequencer_simulator_runs_and_finds_a_sequence(self):
        self.assertEqual(sequencer_sim.main(["--address", self.address, "--orders", "6"]), 0)


if __name__ == "__main__":
    unittest.main()
