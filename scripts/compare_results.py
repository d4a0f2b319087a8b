#!/usr/bin/env python3
"""Compare a regenerated results CSV with the committed one, column by column, ignoring the
columns that measure time or memory (they depend on the machine, not on the mathematics).

Usage: python3 scripts/compare_results.py COMMITTED.csv NEW.csv [--key COL]

Rows are matched by the `key` column when both files have one (sweep CSVs), otherwise by
position. Prints one line per differing cell (at most 20) and a summary line; exits 0 when
every non-timing cell is identical as text, 1 otherwise, 2 on bad input. A restructuring
that must leave the numbers unchanged is checked with it: rerun the CSV's command into a
temporary file (docs/sweeps.md) and compare.
"""
import csv
import re
import sys

# wall_time_s, t_pairs_s, t_solve_s, ... ; peak memory; the dynamic per-step total time
TIMING = re.compile(r"^(wall_time_s|t_[a-z_]+_s|peak_rss_mb|t_total_s)$")


def read(path):
    with open(path, newline="") as f:
        rows = list(csv.DictReader(f))
        return rows, (rows[0].keys() if rows else [])


def main(argv):
    args = [a for a in argv[1:] if not a.startswith("--")]
    key = None
    if "--key" in argv:
        key = argv[argv.index("--key") + 1]
        args.remove(key)
    if len(args) != 2:
        print(__doc__, file=sys.stderr)
        return 2
    a_rows, a_cols = read(args[0])
    b_rows, b_cols = read(args[1])
    if list(a_cols) != list(b_cols):
        print(f"headers differ:\n  {list(a_cols)}\n  {list(b_cols)}")
        return 1
    cols = [c for c in a_cols if not TIMING.match(c)]
    if key is None and "key" in a_cols:
        key = "key"
    if key:
        a_map = {r[key]: r for r in a_rows}
        b_map = {r[key]: r for r in b_rows}
        only_a = sorted(set(a_map) - set(b_map))
        only_b = sorted(set(b_map) - set(a_map))
        pairs = [(k, a_map[k], b_map[k]) for k in a_map if k in b_map]
    else:
        only_a = [str(i) for i in range(len(b_rows), len(a_rows))]
        only_b = [str(i) for i in range(len(a_rows), len(b_rows))]
        pairs = [(str(i), x, y) for i, (x, y) in enumerate(zip(a_rows, b_rows))]
    diffs = [(k, c, x[c], y[c]) for k, x, y in pairs for c in cols if x[c] != y[c]]
    for k, c, x, y in diffs[:20]:
        print(f"{k}: {c}: {x!r} -> {y!r}")
    rows_diff = len({k for k, *_ in diffs})
    print(
        f"{args[1]}: {len(pairs)} rows compared on {len(cols)} non-timing columns; "
        f"{rows_diff} rows differ ({len(diffs)} cells); "
        f"{len(only_a)} rows only in {args[0]}, {len(only_b)} only in {args[1]}"
    )
    return 0 if not diffs and not only_a and not only_b else 1


if __name__ == "__main__":
    sys.exit(main(sys.argv))
