#!/usr/bin/env bash
# The classical contact benchmarks (results/README.md, "Contact benchmarks"): the committed
# example scene files, the patch test, Hertz 2D and 3D, and their plots.
# Usage: bash experiments/benchmarks.sh [scenes|patch|hertz2d|hertz2d_sqp|hertz3d|units|plots ...]  (default: all)
set -euo pipefail
cd "$(dirname "$0")/.."
source scripts/ensure-cmake.sh
source experiments/contactlab_bin.sh
export CONTACTLAB_BIN=$bin
steps=("$@")
[ ${#steps[@]} -gt 0 ] || steps=(scenes patch hertz2d hertz2d_sqp hertz3d units plots)
for s in "${steps[@]}"; do
  case $s in
    scenes|patch|hertz2d|hertz2d_sqp|hertz3d|units) python3 experiments/benchmarks.py "$s" ;;
    plots)
      for lvl in 0 3; do
        "$bin" plot results/hertz2d_profile.csv --x x_over_a \
          --y p_over_p0,pairs_over_p0,hertz_over_p0 --dashed hertz_over_p0 \
          --where case=rigid_l${lvl}_cylinder --linear \
          --title "Hertz 2D, rigid flat, level $lvl: nodal pressure / p0 against x / a" \
          --out results/hertz2d_profile_rigid_l$lvl.svg
      done
      for b in cylinder flat; do
        "$bin" plot results/hertz2d_profile.csv --x x_over_a \
          --y p_over_p0,two_sided_over_p0,pairs_over_p0,hertz_over_p0 --dashed hertz_over_p0 \
          --where case=elastic_l2_$b --linear \
          --title "Hertz 2D, elastic flat, level 2, $b side: pressure / p0 against x / a" \
          --out results/hertz2d_profile_elastic_$b.svg
      done
      "$bin" plot results/hertz2d.csv --x h_c --y err_a_moment,err_p0 --group flat \
        --where eps_over_hc=1.000000000e-02 \
        --title "Hertz 2D: relative errors of a and p0 against the contact element size" \
        --out results/hertz2d_convergence.svg
      "$bin" plot results/hertz3d_profile.csv --x r_over_a \
        --y p_over_p0,hertz_over_p0 --dashed hertz_over_p0 --group case --linear \
        --title "Hertz 3D, rigid flat: nodal pressure / p0 against r / a" \
        --out results/hertz3d_profile.svg ;;
    *) echo "unknown step $s" >&2; exit 2 ;;
  esac
done
