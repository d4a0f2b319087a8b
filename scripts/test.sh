#!/usr/bin/env bash
# The README's test command: formatting, lints, then every test (optimized build).
set -euo pipefail
cd "$(dirname "$0")/.."
source scripts/ensure-cmake.sh
cargo fmt --all -- --check
cargo clippy --workspace --all-targets --release -- -D warnings
cargo test --workspace --release
