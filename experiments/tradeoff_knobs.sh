#!/usr/bin/env bash
# Speed against accuracy: inexact sub-problems (--max-inner), the backend
# tolerance (--qp-tol) and the outer tolerance (--tol-j), one knob at a time from the default,
# on two balloons scenes with lazy rows and Pantz's map (--outer-method pantz). Each case's error is measured against a reference run
# with tighter settings (tol_j = 1e-12, the default 50 inner steps and QP tolerance).
# One run directory per case under runs/tradeoff/ (skipped when its summary.json exists),
# then results/tradeoff_knobs.csv.
# Usage: bash experiments/tradeoff_knobs.sh [BACKEND]   (default clarabel; rows of other backends
# already in the CSV are kept)
set -euo pipefail
cd "$(dirname "$0")/.."
source scripts/ensure-cmake.sh
backend=${1:-clarabel}
source experiments/contactlab_bin.sh
scenes=("n80:--n 80" "n40-p1e-2:--n 40 --perturb 0:1e-2")
cases=("reference:--tol-j 1e-12" "default:" "max_inner=1:--max-inner 1" "max_inner=3:--max-inner 3"
       "max_inner=10:--max-inner 10" "qp_tol=1e-6:--qp-tol 1e-6" "qp_tol=1e-7:--qp-tol 1e-7"
       "tol_j=1e-6:--tol-j 1e-6" "tol_j=1e-8:--tol-j 1e-8" "no_warm_start:--no-warm-start")
for sc in "${scenes[@]}"; do
  sname=${sc%%:*}; sargs=${sc#*:}
  for c in "${cases[@]}"; do
    cname=${c%%:*}; cargs=${c#*:}
    out=runs/tradeoff/$backend-$sname-$cname
    [ -f "$out/summary.json" ] && { echo "skip $out (done)" >&2; continue; }
    echo "$sname $cname" >&2
    # shellcheck disable=SC2086
    # the solver's time only: no second-order check (on by default up to 1 200 free dofs)
    $bin run balloons --backend "$backend" --outer-method pantz --second-order-max-dofs 0 $sargs $cargs --frame-every 1000000 --quiet --out "$out" \
      || echo "run $out failed (status in its summary if written)" >&2
  done
done
python3 - "$backend" <<'PY'
import csv, json, os, sys
backend = sys.argv[1]
scenes = ["n80", "n40-p1e-2"]
cases = ["reference", "default", "max_inner=1", "max_inner=3", "max_inner=10", "qp_tol=1e-6",
         "qp_tol=1e-7", "tol_j=1e-6", "tol_j=1e-8", "no_warm_start"]
cols = ["backend", "scene", "case", "max_inner", "qp_tol", "tol_j", "warm_start", "status", "state",
        "outer_iterations", "inner_iterations", "backend_iterations", "wall_time_s",
        "final_energy", "rel_energy_error", "min_distance_over_eps"]
rows = []
for sc in scenes:
    ref = f"runs/tradeoff/{backend}-{sc}-reference/summary.json"
    jref = json.load(open(ref))["final_energy"] if os.path.exists(ref) else None
    for c in cases:
        f = f"runs/tradeoff/{backend}-{sc}-{c}/summary.json"
        if not os.path.exists(f):
            continue
        s = json.load(open(f))
        j = s["final_energy"]
        rows.append({
            "backend": backend, "scene": sc, "case": c,
            "max_inner": s["settings"]["inner"]["max_inner"], "qp_tol": s["qp_tol"],
            "tol_j": s["settings"]["tol_j"], "warm_start": s["settings"]["inner"]["warm_start"],
            "status": s["status"], "state": s["state"],
            "outer_iterations": s["outer_iterations"], "inner_iterations": s["inner_iterations"],
            "backend_iterations": s["backend_iterations"], "wall_time_s": round(s["wall_time_s"], 3),
            "final_energy": repr(j),
            "rel_energy_error": "" if jref is None else f"{(j - jref) / abs(jref):.3e}",
            "min_distance_over_eps": s["min_distance"] / s["eps"],
        })
path = "results/tradeoff_knobs.csv"
old = []
if os.path.exists(path):
    old = [r for r in csv.DictReader(open(path)) if r["backend"] != backend]
with open(path + ".tmp", "w", newline="") as fh:
    w = csv.DictWriter(fh, fieldnames=cols)
    w.writeheader()
    w.writerows(old + rows)
os.replace(path + ".tmp", path)
print(f"wrote {path}")
PY
