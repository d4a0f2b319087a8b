#!/usr/bin/env bash
# results/default_backend_scenes.csv: Clarabel against `ip` (the default backend) on every
# committed scene file, the default built-in scene, the textbook cases and the dynamic `drop`:
# status, J, outer / inner / backend iterations, κ, QPs handed to Clarabel, wall time.
# Each run: `contactlab run SCENE --backend B --outer-method M --time-limit 600 --quiet --frame-every 1000000`
# (M = pantz unless METHODS says)
# into runs/default_backend/NAME-B/ (skipped when its summary.json exists; `drop` with
# `--dynamic`). Usage: bash experiments/default_backend_scenes.sh. Environment:
# CONTACTLAB_BIN (default target/release/contactlab), OUT (default
# results/default_backend_scenes.csv), BACKENDS (default "clarabel ip"), WORK (default
# runs/default_backend), METHODS (outer methods to run each scene with, e.g. "pantz auto";
# unset: pantz, and the CSV has no outer_method column; set: runs go to WORK/NAME-B-M/).
set -euo pipefail
cd "$(dirname "$0")/.."
source experiments/contactlab_bin.sh
out=${OUT:-results/default_backend_scenes.csv}
work=${WORK:-runs/default_backend}
backends=${BACKENDS:-clarabel ip}
methods=${METHODS:-}
mkdir -p "$work"
scenes=(balloons experiments/scenes/balloons.toml experiments/scenes/ring.toml
  experiments/scenes/rod.toml experiments/scenes/sheets.toml experiments/scenes/solids.toml
  experiments/scenes/solids_noself.toml experiments/scenes/balloons3d.toml
  experiments/scenes/two_strings.toml experiments/scenes/benchmarks/patch_test.toml
  experiments/scenes/benchmarks/hertz2d_rigid.toml
  experiments/scenes/benchmarks/hertz2d_elastic.toml experiments/scenes/drop.toml)
for sc in "${scenes[@]}"; do
  name=$(basename "$sc" .toml)
  [ "$sc" = balloons ] && name=builtin_balloons
  extra=(); [ "$name" = drop ] && extra=(--dynamic)
  for b in $backends; do
    for m in ${methods:-pantz}; do
      dir=$work/$name-$b${methods:+-$m}
      [ -f "$dir/summary.json" ] && continue
      echo "$name $b $m" >&2
      "$bin" run "$sc" "${extra[@]}" --backend "$b" --outer-method "$m" --time-limit 600 --quiet \
        --frame-every 1000000 --out "$dir" >/dev/null 2>"$dir.stderr" || true
    done
  done
done
python3 - "$work" "$out" "$backends" "$methods" "${scenes[@]}" <<'PY'
import csv, json, os, sys
work, out, backends, methods, scenes = (sys.argv[1], sys.argv[2], sys.argv[3].split(),
                                        sys.argv[4].split(), sys.argv[5:])
cols = ["scene", "backend"] + (["outer_method", "sqp_from"] if methods else []) + [
    "status", "final_energy", "outer_iterations", "inner_iterations",
    "backend_iterations", "kappa", "qp_fallbacks", "wall_time_s"]
with open(out, "w", newline="") as f:
    w = csv.DictWriter(f, fieldnames=cols)
    w.writeheader()
    for sc in scenes:
        name = "builtin_balloons" if sc == "balloons" else os.path.basename(sc)[:-5]
        for b, m in [(b, m) for b in backends for m in (methods or [None])]:
            key = {"scene": name, "backend": b}
            if m:
                key["outer_method"] = m
            p = os.path.join(work, f"{name}-{b}" + (f"-{m}" if m else ""), "summary.json")
            if not os.path.exists(p):
                w.writerow(dict(key, status="no summary"))
                continue
            s = json.load(open(p))
            if s.get("dynamic"):
                mt = s["metrics"]
                row = {"status": mt["status"], "final_energy": mt["final_energy"],
                       "outer_iterations": mt["outer_iterations"], "kappa": mt["max_kappa"],
                       "qp_fallbacks": mt.get("qp_fallbacks"), "wall_time_s": mt["wall_time_s"]}
            else:
                row = {"status": s["status"], "final_energy": s["final_energy"],
                       "outer_iterations": s["outer_iterations"],
                       "inner_iterations": s["inner_iterations"],
                       "backend_iterations": s["backend_iterations"],
                       "kappa": s["certificate"]["kappa"], "qp_fallbacks": s.get("qp_fallbacks"),
                       "wall_time_s": s["wall_time_s"]}
                if m:
                    row["sqp_from"] = s.get("sqp_from")
            row.update(key)
            w.writerow(row)
print(out)
PY
