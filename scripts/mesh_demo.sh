#!/usr/bin/env bash
# The kernel demo: installs what is missing, builds, and checks
# real meshes from ../shared/data against each other with the exact kernel.
set -euo pipefail
cd "$(dirname "$0")/.."
bash scripts/build.sh > /dev/null
DATA="$(cd .. && pwd)/shared/data/meshes"
CHECK=./build/clients/gatekeeper-mesh-check
run() { echo; echo "\$ gatekeeper-mesh-check $*"; "$CHECK" "$@" || true; }
# FCL's classic env/rob pair, rob placed inside env's clutter: they collide.
run "$DATA/fcl/env.obj" "$DATA/fcl/rob.obj" --move 10 20 30
# The same pair moved 2 m up and turned: clear, with the minimum distance and its witnesses.
run "$DATA/fcl/env.obj" "$DATA/fcl/rob.obj" --move 0 0 2000 --rotate-deg 0 0 1 30
# Two closed meshes: the turbine hovering 0.1 mm over the fandisk's top face (clear), then
# lowered 0.4 mm into it (collision, with the crossing triangle pairs counted).
run "$DATA/cgal/fandisk_large.off" "$DATA/cgal/turbine.off" --move 2.4 15.2 0.6 --gap 0.05
run "$DATA/cgal/fandisk_large.off" "$DATA/cgal/turbine.off" --move 2.4 15.2 0.2 --gap 0.05
