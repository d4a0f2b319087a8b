#!/usr/bin/env bash
# results/default_backend_scenes.csv: Clarabel against `ip` (the default backend) on every
# committed scene file, the default built-in scene, the textbook cases and the dynamic `drop`:
# status, J, outer / inner / backend iterations, κ, QPs handed to Clarabel, wall time.
# Each run: `contactlab run SCENE --backend B --outer-method pantz --time-limit 600 --quiet --frame-every 1000000`
# into runs/default_backend/NAME-B/ (skipped when its summary.json exists; `drop` with
# `--dynamic`). Usage: bash experiments/default_backend_scenes.sh. Environment:
# CONTACTLAB_BIN (default target/release/contactlab), OUT (default
# results/default_backend_scenes.csv).
set -euo pipefail
cd "$(dirname "$0")/.."
if [ -z "${CONTACTLAB_BIN:-}" ]; then
  source scripts/ensure-cmake.sh
  cargo build --release --quiet --bin contactlab
fi
bin=${CONTACTLAB_BIN:-target/release/contactlab}
out=${OUT:-results/default_backend_scenes.csv}
work=runs/default_backend
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
  for b in clarabel ip; do
    dir=$work/$name-$b
    [ -f "$dir/summary.json" ] && continue
    echo "$name $b" >&2
    "$bin" run "$sc" "${extra[@]}" --backend "$b" --outer-method pantz --time-limit 600 --quiet \
      --frame-every 1000000 --out "$dir" >/dev/null 2>"$dir.stderr" || true
  done
done
python3 - "$work" "$out" "${scenes[@]}" <<'PY'
import csv, json, os, sys
work, out, scenes = sys.argv[1], sys.argv[2], sys.argv[3:]
cols = ["scene", "backend", "status", "final_energy", "outer_iterations", "inner_iterations",
        "backend_iterations", "kappa", "qp_fallbacks", "wall_time_s"]
with open(out, "w", newline="") as f:
    w = csv.DictWriter(f, fieldnames=cols)
    w.writeheader()
    for sc in scenes:
        name = "builtin_balloons" if sc == "balloons" else os.path.basename(sc)[:-5]
        for b in ["clarabel", "ip"]:
            p = os.path.join(work, f"{name}-{b}", "summary.json")
            if not os.path.exists(p):
                w.writerow({"scene": name, "backend": b, "status": "no summary"})
                continue
            s = json.load(open(p))
            if s.get("dynamic"):
                m = s["metrics"]
                row = {"status": m["status"], "final_energy": m["final_energy"],
                       "outer_iterations": m["outer_iterations"], "kappa": m["max_kappa"],
                       "qp_fallbacks": m.get("qp_fallbacks"), "wall_time_s": m["wall_time_s"]}
            else:
                row = {"status": s["status"], "final_energy": s["final_energy"],
                       "outer_iterations": s["outer_iterations"],
                       "inner_iterations": s["inner_iterations"],
                       "backend_iterations": s["backend_iterations"],
                       "kappa": s["certificate"]["kappa"], "qp_fallbacks": s.get("qp_fallbacks"),
                       "wall_time_s": s["wall_time_s"]}
            row.update(scene=name, backend=b)
            w.writerow(row)
print(out)
PY
