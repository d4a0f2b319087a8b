#!/usr/bin/env bash
# The dynamic case (§6): the dt / h sweep of experiments/dynamics.toml into
# results/dynamics.csv (resumable), and the contact force of the drop scene over time
# (implicit Euler: results/dynamics.svg; Newmark: results/dynamics_newmark.svg), from
# `contactlab run drop --dynamic --backend clarabel --outer-method pantz` with the scene's defaults (dt = 0.02, 300 steps).
# Usage: bash experiments/dynamics.sh
set -euo pipefail
cd "$(dirname "$0")/.."
source scripts/ensure-cmake.sh
source experiments/contactlab_bin.sh
"$bin" sweep experiments/dynamics.toml --out results/dynamics.csv --jobs 1 --resume
for s in euler newmark; do
  # a run that ends early (Newmark on drop: a sub-problem failed) still writes its directory
  "$bin" run drop --dynamic --scheme "$s" --backend clarabel --outer-method pantz --quiet --out "runs/dynamics-drop-$s" \
    || echo "drop $s: exit $? (its status is in runs/dynamics-drop-$s/summary.json)" >&2
done
cp runs/dynamics-drop-euler/contact_force.svg results/dynamics.svg
cp runs/dynamics-drop-newmark/contact_force.svg results/dynamics_newmark.svg
