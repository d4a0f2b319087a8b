#!/usr/bin/env python3
"""A 2D sliding scene: an elastic block slides, frictionless, down a fixed circular bowl to its
bottom, a distance of many mesh sizes, under its own weight. Written as scene files (one per
level and start), run with both outer methods, and tabulated: outer steps, status, the
certificate kappa, Lemma 5.6's residual R and bound, and where the block stops.

Why this scene (results/README.md, "sliding2d.csv"): the block's bottom corners slide along
the bowl, a curved body meshed with another mesh size (the bowl's edges are 0.7 times the
block's: non-matching meshes), so the contacting vertices do not face vertices of the other
body and Lemma 5.6's residual is not trivially zero. The bowl is a polygon, so the discrete
minimum need not be the symmetric state: the block is started at the bottom and on both sides
(theta0 = 0, +30, -30 degrees), and the end states are compared.

Geometry (lengths in units of the block width w = 0.5): bowl a circular arc of radius 1.5,
centre (0, 1.5), from -70 to +70 degrees about its lowest point, every vertex fixed; block
[-w/2, w/2] x [0, w/2], neo-Hookean (E = 100, nu = 0.3, plane strain), density 1, gravity
(0, -1), meshed by a structured grid of 8k x 4k cells (h = w / (8k)), placed with its bottom
edge a chord of the bowl lifted by 2 eps, rotated to the bowl's angle theta0. eps = h / 10.

Usage (from the repository root, after `cargo build --release`):

    python3 experiments/sliding2d.py                 # results/sliding2d.csv
    python3 experiments/sliding2d.py --levels 1 2    # a subset (written to --out)
    python3 experiments/sliding2d.py --variants "pantz=--outer-method pantz" \
        "sqp=--outer-method sqp"                     # the `outer_method` column is the label

`CONTACTLAB_BIN` overrides the binary; `--work DIR` the work directory (default
runs/sliding2d); `--time-limit S` per run (default 300). Standard library only.
"""

import argparse
import math
import os
import re
import sys
import time

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import benchmarks as bm  # noqa: E402

RB = 1.5  # bowl radius
W = 0.5  # block width
HB = 0.25  # block height
ARC = math.radians(70.0)
BOWL_RATIO = 0.7  # bowl edge length / block edge length

COMMENT = """A block slides, frictionless, down a fixed circular bowl (radius {rb}) to its bottom under
its own weight: an elastic block {w} x {hb} (neo-Hookean, E = 100, nu = 0.3, plane strain,
density 1, gravity (0, -1)), {nx} x {ny} cells (h = {h:.6g}), started at {deg:g} degrees up the bowl,
its bottom edge a chord of the bowl lifted by 2 eps. The bowl's edges are {ratio} h (non-matching).
eps = h / 10. Written by: python3 experiments/sliding2d.py"""


def rot(p, c, s):
    return (c * p[0] - s * p[1], s * p[0] + c * p[1])


def scene(path, level, theta_deg, bowl_ratio=BOWL_RATIO):
    """Writes the scene file of `level` (k) started at `theta_deg`; returns (h, eps)."""
    k = level
    nx, ny = 8 * k, 4 * k
    h = W / nx
    eps = h / 10
    # the bowl: arc points from -ARC to +ARC, spacing BOWL_RATIO * h
    nb = max(2, int(math.ceil(2 * ARC * RB / (bowl_ratio * h))))
    bowl = [(RB * math.sin(-ARC + 2 * ARC * i / nb), RB - RB * math.cos(-ARC + 2 * ARC * i / nb))
            for i in range(nb + 1)]
    # the block at the bottom: its bottom edge the chord of half-width W/2, lifted by 2 eps
    y0 = RB - math.sqrt(RB * RB - (W / 2) ** 2) + 2 * eps
    pts, tris = bm.rectangle(-W / 2, W / 2, y0, y0 + HB, nx, ny)
    # rotate about the bowl's centre by theta (the block stays on the bowl, same gaps)
    t = math.radians(theta_deg)
    c, s = math.cos(t), math.sin(t)
    centre = (0.0, RB)
    moved = []
    for p in pts:
        q = rot((p[0] - centre[0], p[1] - centre[1]), c, s)
        moved.append((q[0] + centre[0], q[1] + centre[1]))
    d = os.path.dirname(path)
    stem = os.path.splitext(os.path.basename(path))[0]
    bm.write_msh(os.path.join(d, stem + "_block.msh"), moved, tris, 2)
    block = {"name": "block", "kind": "solid", "mesh": stem + "_block.msh",
             "material": {"model": "neo-hookean", "E": 100.0, "nu": 0.3, "plane": "strain"},
             "density": 1.0}
    bowl_body = {"name": "bowl", "kind": "curve", "vertices": [list(p) for p in bowl],
                 "elements": [[i, i + 1] for i in range(nb)], "fixed": {"all": True}}
    header = {"name": stem, "dim": 2, "eps": eps, "gravity": [0.0, -1.0],
              "contact": {"pairs": [["block", "bowl"]], "self": []}}
    bm.write_scene(path, header, [block, bowl_body],
                   COMMENT.format(rb=RB, w=W, hb=HB, nx=nx, ny=ny, h=h, deg=theta_deg,
                                  ratio=bowl_ratio))
    return h, eps


def block_centroid(out):
    """The mean position of the block's vertices in the returned state (final.vtu; the block
    is body 0, so its vertices come first)."""
    text = open(os.path.join(out, "final.vtu")).read()
    m = re.search(r'Name="Points" NumberOfComponents="3" format="ascii">(.*?)</DataArray>',
                  text, re.S)
    vals = [float(v) for v in m.group(1).split()]
    pts = [(vals[3 * i], vals[3 * i + 1]) for i in range(len(vals) // 3)]
    return pts


FIELDS = ["level", "h", "eps", "bowl_ratio", "theta0_deg", "slide_over_h", "outer_method", "status",
          "outer_iterations", "sqp_steps", "fallback_steps", "inner_iterations", "final_energy",
          "kappa", "residual_hm1", "bound", "ratio", "centroid_x", "centroid_angle_deg",
          "min_distance", "energy_monotone", "all_iterates_admissible", "wall_time_s"]


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--levels", type=int, nargs="+", default=[1, 2, 3, 4, 6])
    ap.add_argument("--starts", type=float, nargs="+", default=[30.0, -30.0, 0.0])
    ap.add_argument("--methods", nargs="+", default=["pantz", "sqp"])
    ap.add_argument("--work", default=os.path.join(bm.ROOT, "runs", "sliding2d"))
    ap.add_argument("--out", default=os.path.join(bm.ROOT, "results", "sliding2d.csv"))
    ap.add_argument("--time-limit", type=float, default=300.0)
    ap.add_argument("--max-outer", type=int, default=2000)
    ap.add_argument("--bowl-ratio", type=float, default=BOWL_RATIO,
                    help="bowl edge length / block edge length (default %(default)s)")
    ap.add_argument("--variants", nargs="+", default=None,
                    help="LABEL=FLAGS run variants instead of --methods, e.g. "
                         "'sqp-curv=--outer-method sqp --sqp-curvature psd'")
    args = ap.parse_args()
    os.makedirs(args.work, exist_ok=True)
    rows = []
    for level in args.levels:
        for theta in args.starts:
            tag = "l%d_t%g" % (level, theta)
            path = os.path.join(args.work, "slide2d_%s.toml" % tag)
            h, eps = scene(path, level, theta, args.bowl_ratio)
            variants = ([v.split("=", 1) for v in args.variants] if args.variants else
                        [(m, "--outer-method " + m) for m in args.methods])
            for method, flags in variants:
                out = os.path.join(args.work, "%s_%s" % (tag, method))
                t0 = time.time()
                code, secs, summ = bm.run(path, out, flags.split() + [
                    "--time-limit", str(args.time_limit), "--max-outer", str(args.max_outer),
                    "--frame-every", "1000000"])
                pts = block_centroid(out)
                nblock = (8 * level + 1) * (4 * level + 1)
                cx = sum(p[0] for p in pts[:nblock]) / nblock
                cy = sum(p[1] for p in pts[:nblock]) / nblock
                diag = summ.get("diagnostics") or {}
                cert = summ.get("certificate") or {}
                row = {
                    "level": level, "h": h, "eps": eps, "bowl_ratio": args.bowl_ratio,
                    "theta0_deg": theta,
                    "slide_over_h": (RB - HB / 2) * abs(math.radians(theta)) / h,
                    "outer_method": method, "status": summ["status"],
                    "outer_iterations": summ["outer_iterations"],
                    "sqp_steps": summ.get("sqp_steps", 0),
                    "fallback_steps": summ.get("fallback_steps", 0),
                    "inner_iterations": summ["inner_iterations"],
                    "final_energy": repr(summ["final_energy"]),
                    "kappa": cert.get("kappa", ""),
                    "residual_hm1": diag.get("residual_hm1", ""),
                    "bound": diag.get("bound", ""), "ratio": diag.get("ratio", ""),
                    "centroid_x": cx,
                    "centroid_angle_deg": math.degrees(math.atan2(cx, RB - cy)),
                    "min_distance": summ["min_distance"],
                    "energy_monotone": summ["energy_monotone"],
                    "all_iterates_admissible": summ["all_iterates_admissible"],
                    "wall_time_s": round(summ["wall_time_s"], 3),
                }
                rows.append(row)
                print("level %d theta %g %-5s %-20s outer %5d  J %.12g  kappa %s  R %s  x_c %.3e  %.1f s"
                      % (level, theta, method, summ["status"], summ["outer_iterations"],
                         summ["final_energy"], row["kappa"], row["residual_hm1"], cx,
                         time.time() - t0), file=sys.stderr, flush=True)
                bm.write_csv(args.out, rows, FIELDS)
    print("%s: %d rows" % (args.out, len(rows)), file=sys.stderr)


if __name__ == "__main__":
    main()
