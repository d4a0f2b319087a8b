#!/usr/bin/env bash
# results/second_order.csv: is each end state a local minimum? For the built-in scenes and the
# scene files, one `contactlab run` each with `--second-order-max-dofs 1500` (the default
# bound is 1 200 free dofs; default backend and outer method unless the row's flags say), and
# from its summary.json: the status, J, κ, and the second-order check (docs/method.md, "The
# second-order check"): its status, λ_min / max|λ| of the restricted Hessian of the
# Lagrangian, the negative and zero modes, and where it found a lower admissible point the
# step (a length) and the decrease of J. The `escape` rows are the default run, which goes on
# from that point (`escapes` counts the times); the other rod rows pass `--no-escape-saddles`
# to show the state where the run would stop without it.
#
# Usage: bash experiments/second_order.sh. Environment: CONTACTLAB_BIN (default
# target/release/contactlab), OUT (default results/second_order.csv), WORK (default
# runs/second_order). A run directory that has a summary.json is not run again.
set -euo pipefail
cd "$(dirname "$0")/.."
source experiments/contactlab_bin.sh
out=${OUT:-results/second_order.csv}
work=${WORK:-runs/second_order}
mkdir -p "$work"
asym=--heights=0.9,0.2,0.9,0.2
line="--outer-method sqp --sqp-drop-endpoint-rows --sqp-extend-rows --sqp-drop-vertex-rows
  --sqp-drop-side-rows --sqp-extend-fixed --sqp-path-rows --sqp-implying-rows"
# label|arguments
runs=(
  "balloons-40|balloons --n 40"
  "balloons-80|balloons --n 80"
  "balloons-160|balloons --n 160"
  "balloons-asym-40|balloons --n 40 $asym"
  "balloons-asym-80|balloons --n 80 $asym"
  "balloons-asym-160|balloons --n 160 $asym"
  "balloons-asym-40-pantz|balloons --n 40 $asym --outer-method pantz"
  "ring|ring"
  "rod-8|rod --n 8 --no-escape-saddles"
  "rod-16|rod --n 16 --no-escape-saddles"
  "rod-8-line|rod --n 8 $line --no-escape-saddles"
  "rod-16-line|rod --n 16 $line --no-escape-saddles"
  "rod-8-escape|rod --n 8"
  "rod-16-escape|rod --n 16"
  "rod-32-escape|rod --n 32 --second-order-max-dofs 2500"
  "rod-64-escape|rod --n 64 --second-order-max-dofs 5000"
  "sheets-2|sheets --n 2"
  "sheets-4|sheets --n 4"
  "solids-3|solids --n 3"
  "solids-4|solids --n 4"
  "balloons3d-1|balloons3d --n 1"
  "balloons3d-2|balloons3d --n 2"
  "balloons3d-3|balloons3d --n 3 --eps 0.013171772805113635 --second-order-max-dofs 4000"
  "two_strings|experiments/scenes/two_strings.toml"
  "patch_test|experiments/scenes/benchmarks/patch_test.toml"
  "hertz2d_rigid|experiments/scenes/benchmarks/hertz2d_rigid.toml --second-order-max-dofs 4000"
  "hertz2d_elastic|experiments/scenes/benchmarks/hertz2d_elastic.toml --second-order-max-dofs 4000"
)
for r in "${runs[@]}"; do
  label=${r%%|*}
  args=${r#*|}
  dir=$work/$label
  [ -f "$dir/summary.json" ] && continue
  echo "$label" >&2
  bound=(--second-order-max-dofs 1500)
  case $args in *--second-order-max-dofs*) bound=() ;; esac
  # shellcheck disable=SC2086
  "$bin" run $args --quiet --frame-every 1000000 --time-limit 600 "${bound[@]}" \
    --out "$dir" >/dev/null 2>&1 || true
done
python3 - "$work" "$out" "${runs[@]}" <<'PY'
import csv, json, os, sys
work, out, runs = sys.argv[1], sys.argv[2], sys.argv[3:]
cols = ["label", "args", "status", "outer_iterations", "escapes", "final_energy", "kappa",
        "second_order",
        "min_eigenvalue_rel", "negative_modes", "zero_modes", "free_dofs", "strongly_active",
        "weakly_active", "descent_step", "descent_decrease", "reason", "seconds"]
rows = []
for r in runs:
    label, args = r.split("|", 1)
    p = os.path.join(work, label, "summary.json")
    if not os.path.exists(p):
        rows.append({"label": label, "args": " ".join(args.split()), "status": "no summary"})
        continue
    s = json.load(open(p))
    so = s.get("second_order") or {}
    row = {"label": label, "args": " ".join(args.split()), "status": s["status"],
           "outer_iterations": s["outer_iterations"], "escapes": s.get("escapes", 0),
           "final_energy": s["final_energy"],
           "kappa": s["certificate"]["kappa"], "second_order": so.get("status", "")}
    for k in cols[8:]:
        v = so.get(k)
        row[k] = "" if v is None else v
    rows.append(row)
with open(out, "w", newline="") as f:
    w = csv.DictWriter(f, fieldnames=cols)
    w.writeheader()
    w.writerows(rows)
print(f"{out}: {len(rows)} rows", file=sys.stderr)
PY
