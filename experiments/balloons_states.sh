#!/usr/bin/env bash
# The balloons state table: for n = 20, 40, 80, the state and energy reached with no
# perturbation, with a relative perturbation 1e-6, 1e-3, 1e-2 of C_0, and from the asymmetric
# start (heights 0.9, 0.2, 0.9, 0.2). One run directory per case under runs/states/, then
# results/balloons_states.csv collected from their summary.json files.
# Usage: bash experiments/balloons_states.sh [BACKEND] [N ...]   (default: clarabel 20 40 80)
# PRUNING=lazy|trust-region|all-pairs picks the pruning mode (default lazy); run directories
# are runs/states/<backend>-<pruning>-n<N>-<case>/, rows are keyed by (backend, pruning, n, case).
set -euo pipefail
cd "$(dirname "$0")/.."
source scripts/ensure-cmake.sh
backend=${1:-clarabel}
shift || true
ns=${*:-20 40 80}
pruning=${PRUNING:-lazy}
[ -n "${CONTACTLAB_BIN:-}" ] || cargo build --release --quiet --bin contactlab
bin=${CONTACTLAB_BIN:-target/release/contactlab}
for n in $ns; do
  for case in none p1e-6 p1e-3 p1e-2 asymmetric; do
    out=runs/states/$backend-$pruning-n$n-$case
    [ -f "$out/summary.json" ] && { echo "skip $out (done)"; continue; }
    case $case in
      none) extra=() ;;
      p1e-6) extra=(--perturb 0:1e-6) ;;
      p1e-3) extra=(--perturb 0:1e-3) ;;
      p1e-2) extra=(--perturb 0:1e-2) ;;
      asymmetric) extra=(--heights 0.9,0.2,0.9,0.2) ;;
    esac
    echo "n=$n case=$case backend=$backend pruning=$pruning" >&2
    $bin run balloons --backend "$backend" --pruning "$pruning" --n "$n" --frame-every 1000000 --quiet --out "$out" "${extra[@]}" || echo "run $out failed (status in its summary if written)" >&2
  done
done
python3 - "$backend" "$pruning" $ns <<'PY'
import csv, json, os, sys
backend, pruning, ns = sys.argv[1], sys.argv[2], sys.argv[3:]
path = "results/balloons_states.csv"
rows = {}
if os.path.exists(path):
    for r in csv.DictReader(open(path)):
        r.setdefault("pruning", "all-pairs")  # rows written before the pruning modes existed
        rows[(r["backend"], r["pruning"], r["n"], r["case"])] = r
cols = ["backend", "pruning", "n", "h", "eps", "case", "status", "state", "final_energy", "outer_iterations",
        "inner_iterations", "backend_iterations", "min_distance_over_eps", "energy_monotone",
        "all_iterates_admissible", "wall_time_s", "contact_pattern"]
for n in ns:
    for case in ["none", "p1e-6", "p1e-3", "p1e-2", "asymmetric"]:
        f = f"runs/states/{backend}-{pruning}-n{n}-{case}/summary.json"
        if not os.path.exists(f):
            continue
        s = json.load(open(f))
        rows[(backend, pruning, str(n), case)] = {
            "backend": backend, "pruning": pruning, "n": n, "h": s["h"], "eps": s["eps"], "case": case,
            "status": s["status"], "state": s["state"], "final_energy": repr(s["final_energy"]),
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
    for k in sorted(rows, key=lambda k: (k[0], k[1], int(k[2]), k[3])):
        w.writerow(rows[k])
os.replace(tmp, path)
print(f"wrote {path}")
PY
