#!/usr/bin/env bash
# The backends' agreement check: the default balloons scene (n = 40) with each backend at its
# default tolerance and Pantz's map; prints final energy, state and status of each, and the largest relative
# energy difference. Usage: bash experiments/backends_n40.sh [N]
set -euo pipefail
cd "$(dirname "$0")/.."
source scripts/ensure-cmake.sh
n=${1:-40}
source experiments/contactlab_bin.sh
for b in clarabel ip osqp uzawa; do
  [ -f runs/n$n-$b/summary.json ] || $bin run balloons --n "$n" --backend $b --outer-method pantz --quiet --frame-every 1000000 --out runs/n$n-$b >&2 || true
done
python3 - "$n" <<'PY'
import json, os, sys
n = sys.argv[1]
rows = []
for b in ["clarabel", "ip", "osqp", "uzawa"]:
    f = f"runs/n{n}-{b}/summary.json"
    if os.path.exists(f):
        s = json.load(open(f))
        rows.append((b, s["status"], s["state"], s["final_energy"], s["outer_iterations"], s["wall_time_s"]))
        pattern = " ".join(f"{a}-{c}" for a, c in s["contact_pattern"])
        rows[-1] = rows[-1] + (pattern,)
        print(f"{b:9s} {s['status']:22s} {s['state']:14s} J = {s['final_energy']:.12e}  outer {s['outer_iterations']}  {s['wall_time_s']:.1f} s  pruning {s['pruning']}  contact: {pattern}")
    else:
        print(f"{b:9s} no summary (run did not finish)")
js = [r[3] for r in rows if r[1] == "converged"]
if len(js) > 1:
    print(f"max relative energy difference among converged runs: {(max(js) - min(js)) / abs(min(js)):.3e}")
print("same contact pattern in every run:", len({r[6] for r in rows}) == 1)
ja = [r[3] for r in rows]
if len(ja) > 1:
    print(f"max relative energy difference among all runs (any status): {(max(ja) - min(ja)) / abs(min(ja)):.3e}")
PY
