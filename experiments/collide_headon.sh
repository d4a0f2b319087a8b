#!/usr/bin/env bash
# results/collide_headon.csv: the dynamic `collide` scene with a vertex meeting a vertex
# head-on (offset_cells = 0, not the default half cell), both outer methods, at several mesh
# levels: outer steps per time step (mean, max), the steps' statuses and wall time.
#
# Usage: bash experiments/collide_headon.sh [N ...]   (default: 16 24 32 48; the cells around
# each ring). Environment: CONTACTLAB_BIN (default target/release/contactlab), METHODS
# (default "pantz sqp"), BACKEND (default clarabel, which made the committed CSV), EXTRA (more
# run flags), OUT (default results/collide_headon.csv).
# Each run: `contactlab run collide --dynamic --n N --param offset_cells=0 --outer-method M
# --backend BACKEND --max-outer 2000 --quiet --frame-every 1000000` into runs/collide_headon/M-N/.
set -euo pipefail
cd "$(dirname "$0")/.."
source experiments/contactlab_bin.sh
out=${OUT:-results/collide_headon.csv}
methods=${METHODS:-pantz sqp}
sizes=${*:-16 24 32 48}
mkdir -p runs/collide_headon
for n in $sizes; do
  for m in $methods; do
    dir=runs/collide_headon/$m-$n
    echo "collide head-on n=$n $m" >&2
    # shellcheck disable=SC2086
    "$bin" run collide --dynamic --n "$n" --param offset_cells=0 --outer-method "$m" \
      --backend "${BACKEND:-clarabel}" --max-outer 2000 --quiet --frame-every 1000000 --out "$dir" ${EXTRA:-} >/dev/null \
      2>"$dir.stderr" || echo "  exit $? (see $dir.stderr)" >&2
  done
done
python3 - "$out" "$methods" "$sizes" <<'PY'
import csv, json, sys
out, methods, sizes = sys.argv[1], sys.argv[2].split(), sys.argv[3].split()
cols = ["n", "h", "eps", "outer_method", "run_status", "steps_taken", "outer_total",
        "outer_mean_per_step", "outer_max_per_step", "steps_not_converged", "statuses",
        "all_admissible", "energy_drift", "momentum_error", "wall_time_s"]
rows = []
for n in sizes:
    for m in methods:
        d = f"runs/collide_headon/{m}-{n}"
        try:
            s = json.load(open(f"{d}/summary.json"))
        except FileNotFoundError:
            continue
        h = list(csv.DictReader(open(f"{d}/history.csv")))[1:]
        outer = [int(r["outer_iterations"]) for r in h]
        st = {}
        for r in h:
            st[r["status"]] = st.get(r["status"], 0) + 1
        mt = s["metrics"]
        rows.append({
            "n": n, "h": s["h"], "eps": s["eps"], "outer_method": m,
            "run_status": mt["status"], "steps_taken": mt["steps_taken"],
            "outer_total": sum(outer),
            "outer_mean_per_step": round(sum(outer) / max(len(outer), 1), 2),
            "outer_max_per_step": max(outer, default=0),
            "steps_not_converged": sum(v for k, v in st.items() if k != "converged"),
            "statuses": ";".join(f"{k}:{v}" for k, v in sorted(st.items())),
            "all_admissible": mt["all_admissible"], "energy_drift": mt["energy_drift"],
            "momentum_error": mt["momentum_error"], "wall_time_s": round(mt["wall_time_s"], 3),
        })
with open(out, "w", newline="") as fh:
    w = csv.DictWriter(fh, fieldnames=cols, lineterminator="\n")
    w.writeheader()
    w.writerows(rows)
print(f"{out}: {len(rows)} rows", file=sys.stderr)
PY
