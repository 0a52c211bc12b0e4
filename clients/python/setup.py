"""Generates the gRPC stubs into the package being built (configuration is in pyproject.toml).

protoc and grpc_python_plugin are the ones the C++ build uses (Debian's protobuf-compiler and
protobuf-compiler-grpc; PROTOC and GRPC_PYTHON_PLUGIN override them). The stubs are written into
the build directory only, never into the source tree, and are generated on every build.
"""
import os
import shutil
import subprocess
import tempfile

from setuptools import setup
from setuptools.command.build_py import build_py

HERE = os.path.dirname(os.path.abspath(__file__))
PROTO_ROOT = os.path.normpath(os.path.join(HERE, "..", "..", "proto"))
PROTO = "gatekeeper/v1/gatekeeper.proto"
# grpc_python_plugin imports the messages by their proto path (a top-level `gatekeeper` package);
# in gatekeeper_client.v1 they are a sibling module instead (one package, no generic top-level name
# taken in site-packages; the descriptors keep their file name gatekeeper/v1/gatekeeper.proto).
ABSOLUTE_IMPORT = "from gatekeeper.v1 import gatekeeper_pb2 as"
RELATIVE_IMPORT = "from . import gatekeeper_pb2 as"


def _tool(env, name):
    path = os.environ.get(env) or shutil.which(name)
    if not path:
        raise SystemExit(f"gatekeeper-client: {name} not found (Debian: apt-get install protobuf-compiler "
                         f"protobuf-compiler-grpc), or set {env}")
    return path


def generate_stubs(package_dir):
    """gatekeeper_pb2.py and gatekeeper_pb2_grpc.py into package_dir/v1."""
    if not os.path.isfile(os.path.join(PROTO_ROOT, PROTO)):
        raise SystemExit(f"gatekeeper-client: {PROTO} not found under {PROTO_ROOT}: "
                         "install from a checkout (clients/python beside proto/)")
    with tempfile.TemporaryDirectory() as out:
        subprocess.run([_tool("PROTOC", "protoc"), f"--proto_path={PROTO_ROOT}", f"--python_out={out}",
                        f"--grpc_out={out}", f"--plugin=protoc-gen-grpc={_tool('GRPC_PYTHON_PLUGIN', 'grpc_python_plugin')}",
                        os.path.join(PROTO_ROOT, PROTO)], check=True)
        target = os.path.join(package_dir, "v1")
        os.makedirs(target, exist_ok=True)
        shutil.copy(os.path.join(out, "gatekeeper", "v1", "gatekeeper_pb2.py"), target)
        with open(os.path.join(out, "gatekeeper", "v1", "gatekeeper_pb2_grpc.py"), encoding="utf-8") as f:
            grpc_code = f.read()
        if grpc_code.count(ABSOLUTE_IMPORT) != 1:  # a plugin whose output changed: fail, never ship a broken import
            raise SystemExit(f"gatekeeper-client: expected one '{ABSOLUTE_IMPORT}' in grpc_python_plugin's output")
        with open(os.path.join(target, "gatekeeper_pb2_grpc.py"), "w", encoding="utf-8") as f:
            f.write(grpc_code.replace(ABSOLUTE_IMPORT, RELATIVE_IMPORT))
        with open(os.path.join(target, "__init__.py"), "w", encoding="utf-8") as f:
            f.write(f'"""Generated from proto/{PROTO} when the package was built."""\n')


class BuildPyWithStubs(build_py):
    def run(self):
        if getattr(self, "editable_mode", False):  # the stubs would have to live in the source tree, and go stale there
            raise SystemExit("gatekeeper-client: no editable installs (the gRPC stubs exist only in the built "
                             "package); reinstall after a change, clients/python/run_tests.sh does")
        # setuptools keeps build/lib between builds: a module deleted from the source would still ship.
        package_dir = os.path.join(self.build_lib, "gatekeeper_client")
        shutil.rmtree(package_dir, ignore_errors=True)
        super().run()
        generate_stubs(package_dir)


setup(cmdclass={"build_py": BuildPyWithStubs})
