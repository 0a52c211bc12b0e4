#!/usr/bin/env bash
# Installs the build into a temporary prefix, then builds and runs a consumer against it with
# find_package(gatekeeper) alone, and checks the pkg-config file.
#   tests/package/consumer_test.sh BUILD_DIR
set -euo pipefail
BUILD=$(cd "$1" && pwd)
HERE=$(cd "$(dirname "$0")" && pwd)
PREFIX=$(mktemp -d)
trap 'rm -rf "$PREFIX"' EXIT
cmake --install "$BUILD" --prefix "$PREFIX" > "$PREFIX/install.log"
LAUNCHER=()
command -v ccache > /dev/null && LAUNCHER=(-DCMAKE_CXX_COMPILER_LAUNCHER=ccache)
cmake -S "$HERE/consumer" -B "$PREFIX/consumer-build" -G Ninja -DCMAKE_BUILD_TYPE=Release \
  -DCMAKE_PREFIX_PATH="$PREFIX" "${LAUNCHER[@]}" > "$PREFIX/configure.log" || { cat "$PREFIX/configure.log"; exit 1; }
cmake --build "$PREFIX/consumer-build" > "$PREFIX/build.log" || { cat "$PREFIX/build.log"; exit 1; }
"$PREFIX/consumer-build/gatekeeper_consumer"
# The consumer used the installed headers, not the checkout's.
grep -q "$PREFIX/include/gatekeeper" "$PREFIX/consumer-build/CMakeFiles/gatekeeper_consumer.dir/flags.make" 2> /dev/null ||
  grep -rq "$PREFIX/include/gatekeeper" "$PREFIX/consumer-build/build.ninja"
PKG_CONFIG_PATH="$PREFIX/lib/pkgconfig" pkg-config --exists --print-errors gatekeeper
PKG_CONFIG_PATH="$PREFIX/lib/pkgconfig" pkg-config --libs gatekeeper | grep -q -- -lgatekeeper_engine
echo "consumer_test: the installed package builds and runs a consumer"
