"""Finding the generated stubs and opening a channel to gatekeeperd."""
import os
import sys

_HERE = os.path.dirname(os.path.abspath(__file__))
_STUBS = os.environ.get("GATEKEEPER_PY_STUBS", os.path.normpath(os.path.join(_HERE, "..", "..", "..", "build", "python")))
if _STUBS not in sys.path:
    sys.path.insert(0, _STUBS)

import grpc  # noqa: E402  (Debian's python3-grpcio)
from gatekeeper.v1 import gatekeeper_pb2 as pb  # noqa: E402,F401
from gatekeeper.v1 import gatekeeper_pb2_grpc as pb_grpc  # noqa: E402


def connect(address="127.0.0.1:50051", wait_s=10.0):
    """A stub on a ready channel (waits for the daemon up to wait_s seconds)."""
    channel = grpc.insecure_channel(address)
    grpc.channel_ready_future(channel).result(timeout=wait_s)
    return pb_grpc.GatekeeperStub(channel), channel
