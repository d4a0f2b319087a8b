"""How many outer steps Pantz's map takes where it reaches a certified minimum: over the committed
results/*.csv rows that have a `kappa` column, the static runs with the pantz method (the rows
without an `outer_method` column are Pantz's) whose status is `converged`, counted by outer steps.
This is the reading behind `auto`'s AUTO_PANTZ_STEPS (docs/method.md, "Pantz's map, then SQP").

    python3 experiments/pantz_steps.py
"""
import collections
import csv
import glob
import os

ROOT = os.path.join(os.path.dirname(os.path.abspath(__file__)), "..")
steps = collections.Counter()
long_runs = collections.Counter()
for path in sorted(glob.glob(os.path.join(ROOT, "results", "*.csv"))):
    with open(path, newline="") as f:
        rows = list(csv.DictReader(f))
    if not rows or not {"status", "outer_iterations", "kappa"} <= rows[0].keys():
        continue
    for r in rows:
        if (r.get("outer_method") or "pantz") != "pantz" or r["status"] != "converged":
            continue
        if not r["kappa"]:
            continue
        k = int(r["outer_iterations"])
        steps[k] += 1
        if k > 10:
            long_runs[os.path.basename(path)] += 1
print("outer steps: certified pantz runs")
for k in sorted(steps):
    print(f"{k:6d}: {steps[k]}")
print("files of the runs over 10 steps:", dict(long_runs) or "none")
