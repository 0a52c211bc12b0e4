#!/usr/bin/env bash
# The main job: installs what is missing, builds, starts gatekeeperd on the embedded default P4
# machine model, runs the Phase-3 sequencer simulator against it (its table is the demo), and
# stops the daemon. The daemon listens on a free loopback port chosen at start (its default,
# without --listen, is 127.0.0.1:50051).
set -euo pipefail
cd "$(dirname "$0")/.."
echo "building (log: /tmp/gatekeeper-build.log) ..."
bash scripts/build.sh > /tmp/gatekeeper-build.log 2>&1 || { tail -40 /tmp/gatekeeper-build.log; exit 1; }
DATA=$(mktemp -d)
./build/server/gatekeeperd --listen 127.0.0.1:0 --data-dir "$DATA" --port-file "$DATA/port" --log-level warn &
PID=$!
trap 'kill -TERM $PID 2>/dev/null; wait $PID 2>/dev/null; rm -rf "$DATA"' EXIT
for _ in $(seq 200); do [ -s "$DATA/port" ] && break; sleep 0.05; done
[ -s "$DATA/port" ] || { echo "gatekeeperd did not start"; exit 1; }
cd clients/python
/usr/bin/python3 -m gatekeeper_client.sequencer_sim --address "127.0.0.1:$(cat "$DATA/port")" "$@"
