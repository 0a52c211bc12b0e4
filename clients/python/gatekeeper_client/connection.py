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


def _read(path):
    with open(path, "rb") as f:
        return f.read()


def channel_credentials(tls_ca=None, tls_cert=None, tls_key=None, token=None):
    """The same choices as the C++ clients: TLS when a CA is given (a client certificate for
    mutual TLS), else gRPC's local credentials (loopback only); a bearer token on every call."""
    if tls_ca:
        creds = grpc.ssl_channel_credentials(
            root_certificates=_read(tls_ca),
            private_key=_read(tls_key) if tls_key else None,
            certificate_chain=_read(tls_cert) if tls_cert else None,
        )
    else:
        creds = grpc.local_channel_credentials(grpc.LocalConnectionType.LOCAL_TCP)
    if token:
        creds = grpc.composite_channel_credentials(creds, grpc.access_token_call_credentials(token))
    return creds


def connect(address="127.0.0.1:50051", wait_s=10.0, tls_ca=None, tls_cert=None, tls_key=None, token=None,
            server_name=None):
    """A stub on a ready channel (waits for the daemon up to wait_s seconds)."""
    options = [("grpc.ssl_target_name_override", server_name)] if server_name else []
    channel = grpc.secure_channel(address, channel_credentials(tls_ca, tls_cert, tls_key, token), options=options)
    grpc.channel_ready_future(channel).result(timeout=wait_s)
    return pb_grpc.GatekeeperStub(channel), channel


def add_connection_arguments(parser):
    """--address, --tls-ca, --tls-cert, --tls-key, --tls-server-name, --token-file (as the C++ clients)."""
    parser.add_argument("--address", default="127.0.0.1:50051")
    parser.add_argument("--tls-ca")
    parser.add_argument("--tls-cert")
    parser.add_argument("--tls-key")
    parser.add_argument("--tls-server-name")
    parser.add_argument("--token-file")


def connect_from_arguments(args):
    token = _read(args.token_file).decode().strip() if args.token_file else None
    return connect(args.address, tls_ca=args.tls_ca, tls_cert=args.tls_cert, tls_key=args.tls_key, token=token,
                   server_name=args.tls_server_name)
