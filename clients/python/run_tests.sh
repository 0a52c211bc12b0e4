#!/usr/bin/env bash
# The Python client's tests against the real daemon, on the package as installed: the checkout is
# pip-installed offline into a throwaway venv (Debian's grpcio, protobuf, pip and setuptools seen
# through --system-site-packages), and the tests run with the venv's interpreter in isolated mode
# from outside the source tree, so they import the installed package (whose stubs are generated
# at install time), never clients/python/gatekeeper_client itself.
#   GATEKEEPERD=build/server/gatekeeperd GATEKEEPER_SHARED_DATA=../shared/data clients/python/run_tests.sh [-k pattern]
set -euo pipefail
HERE="$(cd "$(dirname "$0")" && pwd)"
VENV="$(mktemp -d "${TMPDIR:-/tmp}/gatekeeper-py-tests.XXXXXX")"
trap 'rm -rf "$VENV"' EXIT
# Debian's python3 (a python3 earlier in PATH, pyenv's say, lacks Debian's grpcio); no pip of its
# own in the venv: Debian's, from the system site, installs into the venv.
/usr/bin/python3 -m venv --system-site-packages --without-pip "$VENV"
"$VENV/bin/python" -m pip install --quiet --disable-pip-version-check --no-build-isolation --no-index "$HERE"
# The tests run in the venv's directory: paths given relative to here must still hold there.
for v in GATEKEEPERD GATEKEEPER_SHARED_DATA; do
  [ -z "${!v:-}" ] || export "$v=$(realpath -- "${!v}")"
done
cd "$VENV"
"$VENV/bin/python" -I -B -c 'import gatekeeper_client; print("testing", gatekeeper_client.__path__[0])'
"$VENV/bin/python" -I -B -m unittest discover -s "$HERE/tests" -t "$HERE/tests" -v "$@"
