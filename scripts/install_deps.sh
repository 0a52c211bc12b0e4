#!/usr/bin/env bash
# Installs every Debian 12 package the project needs to build, test and run.
# Idempotent: packages already present are left alone. Shared by .ci/run, the README and docker/.
set -euo pipefail

PACKAGES=(
  # toolchain
  build-essential cmake ninja-build pkg-config git ca-certificates
  # compiler outputs cached across the three builds of the test command and across clones
  ccache
  # fuzz targets (scripts/fuzz.sh): clang with libFuzzer and its sanitizer runtimes
  clang libclang-rt-14-dev
  # geometry: OpenCASCADE 7.6.3 and Eigen
  libocct-foundation-dev libocct-modeling-data-dev libocct-modeling-algorithms-dev
  libocct-data-exchange-dev libocct-visualization-dev libocct-ocaf-dev
  # OCCT's CMake targets link TBB (libtbb.so): without it ninja stops at gatekeeperd
  libtbb-dev
  libeigen3-dev
  # the one content hash (kernel/core/content_hash.h): XXH3-128, header-only use
  libxxhash-dev
  # the exact mesh volume (kernel/measure/exact_interference_volume): CGAL's corefinement, header-only,
  # on GMP/MPFR rationals and Boost headers
  libcgal-dev libgmp-dev libmpfr-dev libboost-dev
  # mesh files (STL, OBJ, OFF, PLY, glTF)
  # peers and test/benchmark frameworks
  libfcl-dev libgtest-dev libgmock-dev libbenchmark-dev
  # service
  libgrpc++-dev protobuf-compiler-grpc libprotobuf-dev protobuf-compiler grpc-proto
  libspdlog-dev libfmt-dev libsqlite3-dev nlohmann-json3-dev libcli11-dev libssl-dev
  # the tests' independent reader of /metrics (the Prometheus text format)
  python3-prometheus-client
  # the access tests make their TLS certificates with the openssl command
  openssl
  # scripts/check_container.sh lints the container's entrypoint and health check
  shellcheck
  # machine model files
  libtomlplusplus-dev
  # gatekeeper-audit: one scene's audit over the processes of an MPI job (mpiexec from openmpi-bin)
  libopenmpi-dev openmpi-bin
  # installed with libopenmpi-dev (recommended); named so that the shared multiarch include
  # directory it also owns is accounted for by the install-list check
  libcoarrays-dev
  # python clients: grpcio/protobuf at run time; pip, setuptools and wheel install clients/python offline
  python3 python3-grpcio python3-protobuf python3-pip python3-setuptools python3-wheel python3-venv
  # the BCF export test validates the exported XML against buildingSMART's schemas with xmllint
  libxml2-utils
  # the audit report page: three.js from npm, checked in headless Chromium
  # (npm too: Debian packages it apart from nodejs; NodeSource's nodejs includes it and conflicts
  # with Debian's npm, so it is installed below only when the command is missing)
  nodejs chromium
)

missing=()
for p in "${PACKAGES[@]}"; do
  dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q "install ok installed" || missing+=("$p")
done
if [ ${#missing[@]} -eq 0 ]; then
  echo "install_deps: all ${#PACKAGES[@]} packages present"
else
  SUDO=""
  [ "$(id -u)" -eq 0 ] || SUDO="sudo"
  echo "install_deps: installing ${#missing[@]} packages: ${missing[*]}"
  export DEBIAN_FRONTEND=noninteractive
  $SUDO apt-get update -qq
  $SUDO apt-get install -y -qq --no-install-recommends "${missing[@]}"
fi

# three.js for the audit report page, pinned by server/report_page/package-lock.json; the build
# embeds it, so nothing is fetched at build or run time.
if ! command -v npm > /dev/null; then
  echo "install_deps: installing npm"
  export DEBIAN_FRONTEND=noninteractive
  $([ "$(id -u)" -eq 0 ] || echo sudo) apt-get install -y -qq --no-install-recommends npm
fi
REPORT_PAGE="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)/server/report_page"
if [ ! -f "$REPORT_PAGE/node_modules/three/build/three.min.js" ]; then
  echo "install_deps: npm ci in $REPORT_PAGE"
  npm ci --prefix "$REPORT_PAGE" --no-audit --no-fund --loglevel=error
fi
