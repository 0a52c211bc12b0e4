#!/usr/bin/env bash
# The main job: installs what is missing, builds, starts gatekeeperd on the embedded default P4
# machine model, runs the Phase-3 sequencer simulator against it (its table is the demo), and
# stops the daemon. The daemon listens on a free loopback port chosen at start (its default,
# without --listen, is 127.0.0.1:50051).
set -euo pipefail
cd "$(dirname "$0")/.."
echo "building (log: /tmp/gatekeeper-build.log) ..."
bash scripts/build.sh > /tmp/gatekeeper-build.log 2>&1 || { tail -40 /tmp/gatekeeper-build.log; exit 1; }
# The Python client package, installed offline from the checkout into a throwaway venv that uses
# Debian's python3, pip, grpcio and protobuf (its gRPC stubs are generated at install time).
VENV=$(mktemp -d)
PID=""
DATA=$(mktemp -d)
trap 'if [ -n "$PID" ]; then kill -TERM $PID 2>/dev/null || true; wait $PID 2>/dev/null || true; fi; rm -rf "$DATA" "$VENV"' EXIT
/usr/bin/python3 -m venv --system-site-packages --without-pip "$VENV"
"$VENV/bin/python" -m pip install --quiet --disable-pip-version-check --no-build-isolation --no-index ./clients/python
./build/server/gatekeeperd --listen 127.0.0.1:0 --data-dir "$DATA" --port-file "$DATA/port" --log-level warn &
PID=$!
for _ in $(seq 200); do [ -s "$DATA/port" ] && break; sleep 0.05; done
[ -s "$DATA/port" ] || { echo "gatekeeperd did not start"; exit 1; }
"$VENV/bin/gatekeeper-sequencer-sim" --address "127.0.0.1:$(cat "$DATA/port")" "$@"
