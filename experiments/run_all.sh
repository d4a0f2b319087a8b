#!/usr/bin/env bash
# The committed sweeps and their plots, in order. Each sweep resumes (--resume), so a rerun
# after an interruption runs only the missing rows. Timing sweeps use --jobs 1.
# Usage: bash experiments/run_all.sh [NAME ...]   (default: all eight)
set -euo pipefail
cd "$(dirname "$0")/.."
source scripts/ensure-cmake.sh
source experiments/contactlab_bin.sh
names=("$@")
[ ${#names[@]} -gt 0 ] || names=(lemma56 iterations backends tradeoff scaling extremes iterations_methods lemma56_fixed_points)
for name in "${names[@]}"; do
  case $name in
    lemma56|iterations|extremes) jobs=2 ;;
    *) jobs=1 ;;
  esac
  out=results/$name.csv
  [ "$name" != scaling ] || out=results/scaling_sweep.csv
  "$bin" sweep "experiments/$name.toml" --out "$out" --jobs $jobs --resume
  case $name in
    lemma56)
      "$bin" plot results/lemma56.csv --x h --y residual_hm1,bound --group scene \
        --where accuracy=high --title "Lemma 5.6: ||R||_H-1 and B against h (Clarabel, high)" \
        --out results/lemma56.svg
      "$bin" plot results/lemma56.csv --x h --y residual_hm1,bound --group scene \
        --where accuracy=default --title "Lemma 5.6: ||R||_H-1 and B against h (Clarabel, default)" \
        --out results/lemma56_default.svg ;;
    iterations)
      for s in balloons ring; do
        for k in 50 1; do
          "$bin" plot results/iterations.csv --x "1/max(h,eps)" --y outer_iterations \
            --group eps_rule --where scene=$s --where max_inner=$k \
            --title "$s, max_inner=$k: outer iterations against max(h, eps)^-1" \
            --out results/iterations_${s}_inner$k.svg
        done
        "$bin" plot results/iterations.csv --x "1/max(h,eps)" --y inner_iterations \
          --group eps_rule --where scene=$s --where max_inner=50 \
          --title "$s, max_inner=50: inner (Newton-type) steps against max(h, eps)^-1" \
          --out results/iterations_inner_$s.svg
      done ;;
    iterations_methods)
      for s in balloons rod; do
        "$bin" plot results/iterations_methods.csv --x 1/h --y outer_iterations \
          --group outer_method,eps_rule --where scene=$s \
          --title "$s (asymmetric start for balloons): outer steps against 1/h, both outer methods" \
          --out results/iterations_methods_$s.svg
      done ;;
    lemma56_fixed_points)
      "$bin" plot results/lemma56_fixed_points.csv --x h --y residual_hm1,bound --group outer_method \
        --title "Asymmetric balloons: ||R||_H-1 and B against h, Pantz fixed points and sqp end states" \
        --out results/lemma56_fixed_points.svg ;;
    backends)
      for s in balloons ring; do
        "$bin" plot results/backends.csv --x n --y wall_time_s --group backend \
          --where scene=$s --where accuracy=default \
          --title "$s: wall time per backend (default preset)" --out results/backends_$s.svg
      done ;;
    tradeoff)
      "$bin" plot results/tradeoff.csv --x wall_time_s --y energy_error --group backend --pareto \
        --no-fit --where scene=balloons --where n=80 --title "balloons n=80: energy error against time" \
        --out results/tradeoff.svg
      "$bin" plot results/tradeoff.csv --x wall_time_s --y position_error_h1 --group backend \
        --pareto --no-fit --where scene=balloons --where n=80 \
        --title "balloons n=80: H1 position error against time" --out results/tradeoff_h1.svg ;;
    extremes)
      # the eps/h regime (h fixed within each block, so eps stands for eps/h); params= keeps
      # the other regimes of the same scene out
      for s in "balloons 40" "rod 2"; do
        set -- $s
        "$bin" plot results/extremes.csv --x eps --y wall_time_s,energy_error --group backend \
          --where scene=$1 --where n=$2 --where params= \
          --title "$1 n=$2: time and energy error against eps (h fixed), converged rows" \
          --out results/extremes_eps_$1.svg
      done ;;
    scaling)
      # balloons only: the 3D rows (capped at 50 outer steps, n a mesh level) are a table in
      # results/README.md, not a series to fit
      "$bin" plot results/scaling_sweep.csv --x n --y wall_time_s --group pruning \
        --where scene=balloons --title "balloons: wall time of the whole solve against n" --out results/scaling_sweep.svg ;;
  esac
done
