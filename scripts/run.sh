#!/usr/bin/env bash
# The README's main command: builds contactlab and runs it. With no arguments it runs the
# default scene (balloons, n = 40, the default backend ip) into runs/balloons-default.
set -euo pipefail
cd "$(dirname "$0")/.."
source scripts/ensure-cmake.sh
if [ $# -eq 0 ]; then set -- run; fi
cargo run --release --quiet --bin contactlab -- "$@"
