"""Opening a channel to gatekeeperd."""
import grpc  # Debian's python3-grpcio

try:  # generated from proto/gatekeeper/v1/gatekeeper.proto when the package is built (setup.py)
    from gatekeeper_client.v1 import gatekeeper_pb2 as pb
    from gatekeeper_client.v1 import gatekeeper_pb2_grpc as pb_grpc
except ModuleNotFoundError as e:  # typically: run from the source tree, which holds no stubs
    if e.name != "gatekeeper_client.v1":
        raise
    raise ModuleNotFoundError("gatekeeper_client.v1 (the gRPC stubs) exists only in the installed package: "
                              "/usr/bin/python3 -m pip install --no-build-isolation --no-index clients/python "
                              "into a venv (README)", name=e.name) from e

__all__ = ["pb", "pb_grpc", "channel_credentials", "connect", "add_connection_arguments", "connect_from_arguments"]


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


def read_audit_report(stub, job_id, page_size=5000, timeout=120.0):
    """An audit's whole report, read in pages of page_size clashes (a factory's report exceeds
    gRPC's default 4 MiB receive limit in one reply); its HTML page is asked for separately."""
    request = pb.GetAuditReportRequest(job_id=job_id, page_size=page_size)
    report = None
    restarts = 0
    while True:
        page = stub.GetAuditReport(request, timeout=timeout)
        if report is None:
            report = page
        elif page.progress.state != report.progress.state:
            # A running audit lists its clashes as found and sorts them when it ends: pages read
            # across its end would overlap. Read again from the first page.
            restarts += 1
            if restarts > 3:
                raise RuntimeError("the report kept changing while it was read; try again")
            request.page_token = ""
            report = None
            continue
        else:
            report.clashes.extend(page.clashes)
            report.progress.CopyFrom(page.progress)
        if not page.next_page_token:
            break
        request.page_token = page.next_page_token
    report.next_page_token = ""
    report.clashes_total = len(report.clashes)
    return report
