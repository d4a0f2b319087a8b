#!/usr/bin/env bash
# The balloons state table: for n = 20, 40, 80, the state and energy reached with no
# perturbation, with a relative perturbation 1e-6, 1e-3, 1e-2 of C_0, and from the asymmetric
# start (heights 0.9, 0.2, 0.9, 0.2). One run directory per case under runs/states/, then
# results/balloons_states.csv collected from their summary.json files.
# Usage: bash experiments/balloons_states.sh [BACKEND] [N ...]   (default: clarabel 20 40 80)
# PRUNING=lazy|trust-region|all-pairs picks the pruning mode (default lazy); run directories
# are runs/states/<backend>-<pruning>-n<N>-<case>/, rows are keyed by (backend, pruning, outer
# method, n, case). OUTER=pantz|sqp picks the outer method (default pantz; sqp run directories are
# runs/states/<backend>-<pruning>-sqp-n<N>-<case>/). TIME_LIMIT=S passes --time-limit S to each run
# (default 120). Each row carries the minimality certificate kappa and the status it implies.
set -euo pipefail
cd "$(dirname "$0")/.."
source scripts/ensure-cmake.sh
backend=${1:-clarabel}
shift || true
ns=${*:-20 40 80}
pruning=${PRUNING:-lazy}
outer=${OUTER:-pantz}
time_limit=${TIME_LIMIT:-120}
tag=$backend-$pruning
[ "$outer" = pantz ] || tag=$tag-$outer
source experiments/contactlab_bin.sh
for n in $ns; do
  for case in none p1e-6 p1e-3 p1e-2 asymmetric; do
    out=runs/states/$tag-n$n-$case
    [ -f "$out/summary.json" ] && { echo "skip $out (done)"; continue; }
    case $case in
      none) extra=() ;;
      p1e-6) extra=(--perturb 0:1e-6) ;;
      p1e-3) extra=(--perturb 0:1e-3) ;;
      p1e-2) extra=(--perturb 0:1e-2) ;;
      asymmetric) extra=(--heights 0.9,0.2,0.9,0.2) ;;
    esac
    echo "n=$n case=$case backend=$backend pruning=$pruning outer=$outer" >&2
    $bin run balloons --backend "$backend" --pruning "$pruning" --outer-method "$outer" --time-limit "$time_limit" --n "$n" --frame-every 1000000 --quiet --out "$out" "${extra[@]}" || echo "run $out: non-zero exit (a status other than converged, or a failure; its summary has the status if written)" >&2
  done
done
python3 - "$backend" "$pruning" "$outer" "$tag" $ns <<'PY'
import csv, json, os, sys
backend, pruning, outer, tag, ns = sys.argv[1], sys.argv[2], sys.argv[3], sys.argv[4], sys.argv[5:]
path = "results/balloons_states.csv"
rows = {}
if os.path.exists(path):
    for r in csv.DictReader(open(path)):
        r.setdefault("pruning", "all-pairs")  # rows written before the pruning modes existed
        r.setdefault("outer_method", "pantz")  # rows written before the SQP method existed
        r.setdefault("kappa", "")  # rows written before the certificate existed
        rows[(r["backend"], r["pruning"], r["outer_method"], r["n"], r["case"])] = r
cols = ["backend", "pruning", "outer_method", "n", "h", "eps", "case", "status", "kappa", "state", "final_energy", "outer_iterations",
        "inner_iterations", "backend_iterations", "min_distance_over_eps", "energy_monotone",
        "all_iterates_admissible", "wall_time_s", "contact_pattern"]
for n in ns:
    for case in ["none", "p1e-6", "p1e-3", "p1e-2", "asymmetric"]:
        f = f"runs/states/{tag}-n{n}-{case}/summary.json"
        if not os.path.exists(f):
            continue
        s = json.load(open(f))
        rows[(backend, pruning, outer, str(n), case)] = {
            "backend": backend, "pruning": pruning, "outer_method": outer, "n": n, "h": s["h"], "eps": s["eps"],
            "case": case, "status": s["status"], "kappa": repr(s["certificate"]["kappa"]), "state": s["state"], "final_energy": repr(s["final_energy"]),
            "outer_iterations": s["outer_iterations"], "inner_iterations": s["inner_iterations"],
            "backend_iterations": s["backend_iterations"],
            "min_distance_over_eps": s["min_distance"] / s["eps"],
            "energy_monotone": s["energy_monotone"], "all_iterates_admissible": s["all_iterates_admissible"],
            "wall_time_s": round(s["wall_time_s"], 2),
            "contact_pattern": " ".join(f"{a}-{b}" for a, b in s["contact_pattern"]),
        }
tmp = path + ".tmp"
with open(tmp, "w", newline="") as fh:
    w = csv.DictWriter(fh, fieldnames=cols)
    w.writeheader()
    for k in sorted(rows, key=lambda k: (k[0], k[1], k[2], int(k[3]), k[4])):
        w.writerow(rows[k])
os.replace(tmp, path)
print(f"wrote {path}")
PY
