#!/usr/bin/env bash
# results/restart.csv: does a run return to its end state's energy when started from a
# perturbed copy of that state? The asymmetric balloons (heights 0.9, 0.2, 0.9, 0.2) and the
# symmetric ones, both outer methods, n = 40 80 160: one run from the scene's start, then runs
# from its final.vtu perturbed by A·h (`--start-from … --start-perturb A`, A = 0.01 and 0.1;
# the vertices of pairs that would come closer than ε keep their positions). Clarabel, which
# made the committed CSV.
#
# Usage: bash experiments/restart.sh [N ...]   (default 40 80 160). Environment:
# CONTACTLAB_BIN (default target/release/contactlab), OUT (default results/restart.csv),
# METHODS (default "pantz sqp"), EXTRA (more run flags for every run, e.g. SQP options with
# METHODS=sqp), WORK (default runs/restart), SCENE (default balloons; any other static scene
# is run from its own start only, `start` = default in the CSV, at its own ε; a scene file,
# SCENE=path.toml, is run without --n, the sizes then only label the rows). A run directory
# that has a summary.json is not run again (rerun the script to resume an interrupted one;
# delete WORK to redo them all); a run without one gets a row with status `no summary`.
set -euo pipefail
cd "$(dirname "$0")/.."
source experiments/contactlab_bin.sh
out=${OUT:-results/restart.csv}
sizes=${*:-40 80 160}
work=${WORK:-runs/restart}
methods=${METHODS:-pantz sqp}
scene=${SCENE:-balloons}
starts="asym sym"; [ "$scene" = balloons ] || starts=default
mkdir -p "$work"
for n in $sizes; do
  for start in $starts; do
    h=(); [ "$start" = asym ] && h=(--heights 0.9,0.2,0.9,0.2)
    nf=(--n "$n"); case $scene in *.toml) nf=() ;; esac
    for m in $methods; do
      base=$work/$start-$m-$n
      echo "$start n=$n $m" >&2
      # shellcheck disable=SC2086
      [ -f "$base/summary.json" ] ||
      "$bin" run "$scene" "${nf[@]}" "${h[@]}" --outer-method "$m" --backend clarabel --quiet \
        --frame-every 1000000 --out "$base" ${EXTRA:-} >/dev/null 2>&1 || true
      for a in 0.01 0.1; do
        [ -f "$base-restart$a/summary.json" ] && continue
        # shellcheck disable=SC2086
        "$bin" run "$scene" "${nf[@]}" "${h[@]}" --outer-method "$m" --backend clarabel --quiet \
          --frame-every 1000000 --start-from "$base/final.vtu" --start-perturb "$a" --out "$base-restart$a" ${EXTRA:-} >/dev/null 2>&1 || true
      done
    done
  done
done
python3 - "$out" "$work" "$sizes" "$methods" "$starts" <<'PY'
import csv, json, sys
out, work, sizes, methods = sys.argv[1], sys.argv[2], sys.argv[3].split(), sys.argv[4].split()
starts = sys.argv[5].split()
cols = ["start", "n", "outer_method", "perturb", "perturb_used", "unperturbed_vertices", "status",
        "outer_iterations", "initial_energy", "final_energy", "kappa", "state",
        "energy_minus_first_run"]
def load(path):
    try:
        with open(path) as f:
            return json.load(f)
    except FileNotFoundError:
        return None


rows = []
for n in sizes:
    for start in starts:
        for m in methods:
            base = f"{work}/{start}-{m}-{n}"
            s0 = load(f"{base}/summary.json")
            for a, d in [("", base), ("0.01", base + "-restart0.01"), ("0.1", base + "-restart0.1")]:
                s = load(f"{d}/summary.json")
                if s is None or s0 is None:
                    rows.append({"start": start, "n": n, "outer_method": m, "perturb": a,
                                 "status": "no summary" if s is None else s["status"]})
                    continue
                p = s["params"]
                rows.append({
                    "start": start, "n": n, "outer_method": m, "perturb": a,
                    "perturb_used": p.get("start_perturb", ""),
                    "unperturbed_vertices": p.get("start_unperturbed_vertices", ""),
                    "status": s["status"], "outer_iterations": s["outer_iterations"],
                    "initial_energy": repr(s["initial_energy"]), "final_energy": repr(s["final_energy"]),
                    "kappa": s["certificate"]["kappa"], "state": s["state"],
                    "energy_minus_first_run": s["final_energy"] - s0["final_energy"],
                })
with open(out, "w", newline="") as fh:
    w = csv.DictWriter(fh, fieldnames=cols, lineterminator="\n")
    w.writeheader()
    w.writerows(rows)
print(f"{out}: {len(rows)} rows", file=sys.stderr)
PY
