#!/usr/bin/env bash
# results/perf.csv: whole-run totals of the sub-problem solver, per scene and size, for one or
# more binaries run side by side in one session (a "before" and an "after" build).
#
# Usage: bash experiments/perf.sh LABEL=BINARY[ FLAGS] [LABEL=BINARY[ FLAGS] ...]
#   e.g. bash experiments/perf.sh before=/tmp/contactlab-old after=target/release/contactlab \
#        "ip=target/release/contactlab --backend ip"
#   (FLAGS, after the binary in the same argument, are added to each of that label's runs)
# Environment: SIZES (balloons n, default "40 160 320 640 1600 6400"), LIMIT (seconds per
# run, default 600), OUT (default results/perf.csv), SCENES3D (default "rod sheets solids
# balloons3d").
#
# Each run is `BINARY run SCENE [--n N] --outer-method pantz --quiet --frame-every 1000000 --time-limit LIMIT`
# (without --outer-method where the binary has no such flag)
# into runs/perf/LABEL-SCENE-N/; its row holds the summary (status, J, outer/inner/backend
# iterations, wall time) and the per-phase totals summed over history.csv (pair search,
# assembly, backend), the QP count (inner steps + lazy re-solves), the certificate's seconds
# and κ (empty for binaries without it) and the peak resident memory (/usr/bin/time). A run directory that
# already has a summary.json is not run again (delete it to redo), so an interrupted
# measurement resumes; rows are written in order, one per run.
set -euo pipefail
cd "$(dirname "$0")/.."
[ $# -ge 1 ] || { echo "usage: $0 LABEL=BINARY [LABEL=BINARY ...]" >&2; exit 2; }
sizes=${SIZES:-40 160 320 640 1600 6400}
limit=${LIMIT:-600}
out=${OUT:-results/perf.csv}
scenes3d=${SCENES3D:-rod sheets solids balloons3d}
mkdir -p runs/perf
cases=()
for n in $sizes; do cases+=("balloons:$n"); done
for s in $scenes3d; do cases+=("$s:"); done
for spec in "$@"; do
  rest=${spec#*=}
  bin=${rest%% *}
  [ -x "$bin" ] || { echo "$bin: not an executable" >&2; exit 2; }
done
for c in "${cases[@]}"; do
  scene=${c%%:*}
  n=${c#*:}
  for spec in "$@"; do
    label=${spec%%=*}
    rest=${spec#*=}
    bin=${rest%% *}
    flags=()
    [ "$rest" = "$bin" ] || read -r -a flags <<< "${rest#"$bin" }"
    dir=runs/perf/$label-$scene-${n:-default}
    if [ -f "$dir/summary.json" ]; then
      echo "skip $dir (done)" >&2
      continue
    fi
    echo "$label $scene ${n:-default}" >&2
    nflag=()
    [ -z "$n" ] || nflag=(--n "$n")
    mkdir -p "$(dirname "$dir")"
    # Pantz's map, the default until `auto` became it (older binaries have no such flag).
    mflag=()
    "$bin" run --help 2>/dev/null | grep -q -- --outer-method && mflag=(--outer-method pantz)
    # The solver's time only: no second-order check (on by default since it exists, up to
    # 1 200 free dofs; older binaries have no such flag).
    "$bin" run --help 2>/dev/null | grep -q -- --second-order-max-dofs &&
      mflag+=(--second-order-max-dofs 0)
    /usr/bin/time -f "%M" -o "$dir.rss" \
      "$bin" run "$scene" "${nflag[@]}" "${mflag[@]}" "${flags[@]}" --quiet --frame-every 1000000 \
      --time-limit "$limit" --out "$dir" >/dev/null 2>"$dir.stderr" \
      || echo "  exit $? (status in its summary if written)" >&2
  done
done
python3 - "$out" "$@" <<'PY'
import csv, json, os, sys
out, specs = sys.argv[1], sys.argv[2:]
cols = ["label", "scene", "n", "status", "final_energy", "outer_iterations", "inner_iterations",
        "qp_solves", "backend_iterations", "wall_time_s", "t_pairs_s", "t_assembly_s",
        "t_solve_s", "max_pairs", "max_rows", "certificate_s", "kappa", "peak_rss_mb"]
def peak_rss(d):
    try:
        return round(int(open(d + ".rss").read().split()[-1]) / 1024, 1)
    except (OSError, ValueError, IndexError):
        return ""

rows = []
sizes = os.environ.get("SIZES", "40 160 320 640 1600 6400").split()
scenes3d = os.environ.get("SCENES3D", "rod sheets solids balloons3d").split()
cases = [("balloons", n) for n in sizes] + [(s, "default") for s in scenes3d]
for scene, n in cases:
    for spec in specs:
        label = spec.split("=", 1)[0]
        d = f"runs/perf/{label}-{scene}-{n}"
        f = f"{d}/summary.json"
        if not os.path.exists(f):
            continue
        s = json.load(open(f))
        h = list(csv.DictReader(open(f"{d}/history.csv")))[1:]
        tot = lambda c: sum(float(r[c]) for r in h)
        rows.append({
            "label": label, "scene": scene, "n": n, "status": s["status"],
            "final_energy": repr(s["final_energy"]), "outer_iterations": s["outer_iterations"],
            "inner_iterations": s["inner_iterations"],
            "qp_solves": sum(int(r["inner_iterations"]) + int(r["lazy_rounds"]) for r in h),
            "backend_iterations": s["backend_iterations"], "wall_time_s": round(s["wall_time_s"], 3),
            "t_pairs_s": round(tot("t_pairs_s"), 3), "t_assembly_s": round(tot("t_assembly_s"), 3),
            "t_solve_s": round(tot("t_solve_s"), 3),
            "max_pairs": max((int(r["pairs"]) for r in h), default=0),
            "max_rows": max((int(r["rows"]) for r in h), default=0),
            "certificate_s": round(s["certificate"]["seconds"], 3) if s.get("certificate") else "",
            "kappa": s["certificate"]["kappa"] if s.get("certificate") else "",
            "peak_rss_mb": peak_rss(d),
        })
with open(out, "w", newline="") as fh:
    w = csv.DictWriter(fh, fieldnames=cols)
    w.writeheader()
    w.writerows(rows)
print(f"{out}: {len(rows)} rows", file=sys.stderr)
PY
