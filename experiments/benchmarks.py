#!/usr/bin/env python3
"""Classical contact benchmarks as scene files: the 2D contact patch test (Taylor &
Papadopoulos 1991), Hertz contact in 2D (a cylinder on a rigid and on an elastic flat, plane
strain) and in 3D (a sphere on a rigid flat), and the units twin (results/README.md).

Each case is a scene file (`.toml` + Gmsh `.msh` meshes) written into a work directory and run
with `contactlab run FILE --out DIR`; the numbers are read back from the run directory
(`contacts.csv`, `summary.json`) and compared with the analytic answers. Standard library only.

Usage (from the repository root, after `cargo build --release`):

    python3 experiments/benchmarks.py scenes          # the committed example scene files
    python3 experiments/benchmarks.py patch           # results/patch_test.csv
    python3 experiments/benchmarks.py hertz2d         # results/hertz2d*.csv
    python3 experiments/benchmarks.py hertz2d_sqp     # results/hertz2d_sqp*.csv (elastic, sqp)
    python3 experiments/benchmarks.py hertz3d         # results/hertz3d*.csv
    python3 experiments/benchmarks.py units           # results/units.csv

`CONTACTLAB_BIN` overrides the binary (default target/release/contactlab); `--work DIR` the work
directory (default runs/benchmarks).
"""

import argparse
import csv
import json
import math
import os
import subprocess
import sys
import time

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
BIN = os.environ.get("CONTACTLAB_BIN", os.path.join(ROOT, "target", "release", "contactlab"))


# --------------------------------------------------------------------------------------------
# meshes
# --------------------------------------------------------------------------------------------

def write_msh(path, points, elements, etype):
    """Gmsh 2.2 ASCII: `points` (x, y[, z]), `elements` vertex lists (0-based), Gmsh `etype`
    (2 triangle, 4 tetrahedron)."""
    with open(path, "w") as f:
        f.write("$MeshFormat\n2.2 0 8\n$EndMeshFormat\n$Nodes\n%d\n" % len(points))
        for i, p in enumerate(points):
            z = p[2] if len(p) > 2 else 0.0
            f.write("%d %r %r %r\n" % (i + 1, float(p[0]), float(p[1]), float(z)))
        f.write("$EndNodes\n$Elements\n%d\n" % len(elements))
        for i, e in enumerate(elements):
            f.write("%d %d 2 0 1 %s\n" % (i + 1, etype, " ".join(str(v + 1) for v in e)))
        f.write("$EndElements\n")


def grid_triangles(xs_rows, nx, ny):
    """Triangles of a structured (nx+1) x (ny+1) grid of points numbered row by row
    (`v = j (nx+1) + i`), counter-clockwise when rows go up in y and columns right in x; the
    diagonals alternate."""
    tris = []
    m = nx + 1
    for j in range(ny):
        for i in range(nx):
            a, b, c, d = j * m + i, j * m + i + 1, (j + 1) * m + i + 1, (j + 1) * m + i
            if (i + j) % 2 == 0:
                tris += [[a, b, c], [a, c, d]]
            else:
                tris += [[a, b, d], [b, c, d]]
    return tris


def rectangle(x0, x1, y0, y1, nx, ny, xs=None, ys=None):
    """A structured triangle mesh of [x0, x1] x [y0, y1]; `xs`/`ys` node coordinates in
    [0, 1] (default uniform)."""
    xs = xs or [i / nx for i in range(nx + 1)]
    ys = ys or [j / ny for j in range(ny + 1)]
    pts = [(x0 + (x1 - x0) * u, y0 + (y1 - y0) * v) for v in ys for u in xs]
    return pts, grid_triangles(None, nx, ny)


def geometric(n, first, total):
    """n + 1 increasing coordinates from 0 to `total` whose first step is `first` and whose
    steps grow geometrically (uniform if `first * n >= total`)."""
    if first * n >= total:
        return [total * i / n for i in range(n + 1)]
    lo, hi = 1.0, 2.0
    f = lambda q: first * (q ** n - 1) / (q - 1) - total
    while f(hi) < 0:
        hi *= 2
    for _ in range(200):
        mid = 0.5 * (lo + hi)
        if f(mid) < 0:
            lo = mid
        else:
            hi = mid
    q = 0.5 * (lo + hi)
    out, s, step = [0.0], 0.0, first
    for _ in range(n):
        s += step
        out.append(s)
        step *= q
    out[-1] = total
    return out


def coons(bottom, top, left, right):
    """Transfinite interpolation of a 4-sided patch from its node lists: `bottom`, `top`
    (n nodes each, left to right), `left`, `right` (m nodes each, bottom to top), sharing the
    corners. Returns the n x m grid, row by row (v outer)."""
    n, m = len(bottom), len(left)

    def frac(pts):
        d = [0.0]
        for a, b in zip(pts, pts[1:]):
            d.append(d[-1] + math.hypot(b[0] - a[0], b[1] - a[1]))
        return [t / d[-1] for t in d]

    ub, ut, vl, vr = frac(bottom), frac(top), frac(left), frac(right)
    p00, p10, p01, p11 = bottom[0], bottom[-1], top[0], top[-1]
    grid = []
    for j in range(m):
        row = []
        for i in range(n):
            # parameters blended between opposite sides
            v = (1 - ub[i]) * vl[j] + ub[i] * vr[j]
            u = (1 - vl[j]) * ub[i] + vl[j] * ut[i]
            p = []
            for k in range(2):
                p.append(
                    (1 - v) * bottom[i][k] + v * top[i][k] + (1 - u) * left[j][k] + u * right[j][k]
                    - ((1 - u) * (1 - v) * p00[k] + u * (1 - v) * p10[k]
                       + (1 - u) * v * p01[k] + u * v * p11[k]))
            row.append(tuple(p))
        grid.append(row)
    return grid


class Mesh2:
    """Points merged by coordinates (blocks sharing sides), and triangles."""

    def __init__(self):
        self.points, self.index, self.tris = [], {}, []

    def point(self, p):
        key = (round(p[0], 12), round(p[1], 12))
        if key not in self.index:
            self.index[key] = len(self.points)
            self.points.append((p[0], p[1]))
        return self.index[key]

    def add_grid(self, grid):
        """A structured block (rows of points, v outer) split into triangles, each made
        counter-clockwise."""
        ids = [[self.point(p) for p in row] for row in grid]
        for j in range(len(grid) - 1):
            for i in range(len(grid[0]) - 1):
                a, b, c, d = ids[j][i], ids[j][i + 1], ids[j + 1][i + 1], ids[j + 1][i]
                for t in ([a, b, c], [a, c, d]) if (i + j) % 2 == 0 else ([a, b, d], [b, c, d]):
                    self.tris.append(self.ccw(t))

    def ccw(self, t):
        (x0, y0), (x1, y1), (x2, y2) = (self.points[v] for v in t)
        area = (x1 - x0) * (y2 - y0) - (x2 - x0) * (y1 - y0)
        if abs(area) < 1e-300:
            raise ValueError("degenerate triangle %r" % (t,))
        return t if area > 0 else [t[0], t[2], t[1]]


def quarter_disk(R, yc, n_arc_a, n_arc_b, n_rad, h_contact, s_frac=0.5):
    """The quarter disk {x >= 0, y <= yc} of radius R centred at (0, yc), meshed by three
    transfinite blocks (an inner square of side s = s_frac R and two curved blocks between it
    and the arc), the arc graded from `h_contact` at the bottom point, the radial lines from
    `h_contact` at the arc. The bottom block's arc spans 0..45 degrees from the bottom point."""
    s = s_frac * R
    C = (0.0, yc)
    arc = lambda th: (R * math.sin(th), yc - R * math.cos(th))
    # arc nodes: bottom block from theta = 0 (graded) to 45 degrees; right block 45..90
    ta = [t / R for t in geometric(n_arc_a, h_contact, R * math.pi / 4)]
    arc_a = [arc(t) for t in ta]
    hb = R * (ta[-1] - ta[-2])
    tb = [math.pi / 4 + t / R for t in geometric(n_arc_b, hb, R * math.pi / 4)]
    arc_b = [arc(t) for t in tb]
    S1, S2, S3 = (0.0, yc - s), (s, yc - s), (s, yc)
    lin = lambda p, q, n: [(p[0] + (q[0] - p[0]) * k / n, p[1] + (q[1] - p[1]) * k / n)
                           for k in range(n + 1)]
    B, D, E = arc_a[0], arc_a[-1], arc_b[-1]

    def radial(p, q):
        # from the arc point p inward to q, graded from h_contact at p
        L = math.hypot(q[0] - p[0], q[1] - p[1])
        ts = geometric(n_rad, min(h_contact, L / n_rad), L)
        return [(p[0] + (q[0] - p[0]) * t / L, p[1] + (q[1] - p[1]) * t / L) for t in ts]

    m = Mesh2()
    # bottom block: bottom = arc B..D, top = S1..S2, left = B..S1 (x = 0), right = D..S2
    m.add_grid(coons(arc_a, lin(S1, S2, n_arc_a), radial(B, S1), radial(D, S2)))
    # right block: bottom = arc D..E, top = S2..S3, left = D..S2, right = E..S3 (y = yc)
    m.add_grid(coons(arc_b, lin(S2, S3, n_arc_b), radial(D, S2), radial(E, S3)))
    # inner square: bottom = S1..S2, top = C..S3, left = S1..C, right = S2..S3
    m.add_grid(coons(lin(S1, S2, n_arc_a), lin(C, S3, n_arc_a), lin(S1, C, n_arc_b),
                     lin(S2, S3, n_arc_b)))
    return m


# --------------------------------------------------------------------------------------------
# scene files and runs
# --------------------------------------------------------------------------------------------

def toml_value(v):
    if isinstance(v, bool):
        return "true" if v else "false"
    if isinstance(v, (int,)):
        return str(v)
    if isinstance(v, float):
        return repr(v)
    if isinstance(v, str):
        return json.dumps(v)
    if isinstance(v, (list, tuple)):
        return "[" + ", ".join(toml_value(x) for x in v) + "]"
    if isinstance(v, dict):
        return "{ " + ", ".join("%s = %s" % (k, toml_value(x)) for k, x in v.items()) + " }"
    raise TypeError(v)


def write_scene(path, header, bodies, comment=""):
    """A scene file: `header` top-level keys and tables (dicts), `bodies` dicts whose
    `support`, `traction`, `force` lists become [[body.support]] ... tables."""
    lines = [("# " + l).rstrip() for l in comment.strip().splitlines()] if comment else []
    tables = {k: v for k, v in header.items() if isinstance(v, dict)}
    for k, v in header.items():
        if not isinstance(v, dict):
            lines.append("%s = %s" % (k, toml_value(v)))
    for name, t in tables.items():
        lines.append("\n[%s]" % name)
        for k, v in t.items():
            lines.append("%s = %s" % (k, toml_value(v)))
    for b in bodies:
        lines.append("\n[[body]]")
        subs = {}
        for k, v in b.items():
            if k in ("support", "traction", "force"):
                subs[k] = v
            else:
                lines.append("%s = %s" % (k, toml_value(v)))
        for k, lst in subs.items():
            for item in lst:
                lines.append("[[body.%s]]" % k)
                for kk, vv in item.items():
                    if kk == "comment":
                        continue
                    lines.append("%s = %s" % (kk, toml_value(vv)))
    with open(path, "w") as f:
        f.write("\n".join(lines) + "\n")


REUSE = False


def run(scene, out, extra=()):
    """`contactlab run scene --out out`; returns (exit code, seconds, summary dict). With
    `--reuse`, a run directory made from the same scene text and arguments is read, not rerun
    (its wall time is the recorded one)."""
    # The committed benchmark results were made with Clarabel (the default backend until
    # `ip` became it), so a run that names no backend runs Clarabel.
    if "--backend" not in extra:
        extra = ["--backend", "clarabel"] + list(extra)
    # ... and with Pantz's map (the default until `auto` became it).
    if "--outer-method" not in extra:
        extra = ["--outer-method", "pantz"] + list(extra)
    with open(scene) as f:
        key = f.read() + "\n#args " + " ".join(extra)
    stamp = os.path.join(out, "benchmark_input.txt")
    if REUSE and os.path.exists(stamp) and open(stamp).read() == key:
        with open(os.path.join(out, "summary.json")) as f:
            summ = json.load(f)
        return 0, float(open(os.path.join(out, "benchmark_seconds.txt")).read()), summ
    t0 = time.time()
    p = subprocess.run([BIN, "run", scene, "--quiet", "--out", out] + list(extra),
                       stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
    dt = time.time() - t0
    summ = None
    sp = os.path.join(out, "summary.json")
    if os.path.exists(sp):
        with open(sp) as f:
            summ = json.load(f)
    if summ is None:
        sys.stderr.write(p.stdout + p.stderr)
        raise RuntimeError("run of %s failed (exit %d)" % (scene, p.returncode))
    with open(stamp, "w") as f:
        f.write(key)
    with open(os.path.join(out, "benchmark_seconds.txt"), "w") as f:
        f.write(repr(dt))
    return p.returncode, dt, summ


def contacts(out):
    """The rows of the last step of `contacts.csv`, as dicts of floats (body kept as text)."""
    with open(os.path.join(out, "contacts.csv")) as f:
        rows = list(csv.DictReader(f))
    last = max(int(r["step"]) for r in rows)
    out_rows = []
    for r in rows:
        if int(r["step"]) != last:
            continue
        d = {k: (float(v) if v not in ("",) and k != "body" else (v if k == "body" else float("nan")))
             for k, v in r.items()}
        out_rows.append(d)
    return out_rows


def fit_slope(xs, ys):
    """Least-squares slope of log y against log x."""
    lx = [math.log(x) for x in xs]
    ly = [math.log(y) for y in ys]
    mx, my = sum(lx) / len(lx), sum(ly) / len(ly)
    num = sum((a - mx) * (b - my) for a, b in zip(lx, ly))
    den = sum((a - mx) ** 2 for a in lx)
    return num / den


def write_csv(path, rows, fields):
    with open(path, "w", newline="") as f:
        w = csv.DictWriter(f, fieldnames=fields, lineterminator="\n")
        w.writeheader()
        for r in rows:
            w.writerow({k: r.get(k, "") for k in fields})


def fmt(v):
    return "%.9e" % v if isinstance(v, float) else v


# --------------------------------------------------------------------------------------------
# the contact patch test
# --------------------------------------------------------------------------------------------

PATCH_COMMENT = """The contact patch test (Taylor & Papadopoulos 1991): two linear-elastic blocks, plane
strain, on non-matching meshes ({nl} and {nu} elements along the interface). The lower block
[0, 1] x [0, 0.5] rests on a roller at y = 0; both blocks are held by rollers at x = 0 and
x = 1 (u_x = 0), so that the exact solution is uniform: sigma_yy = -p, eps_xx = 0 in both
blocks whatever their stiffness. A dead pressure p on the upper block's top face pushes it
onto the lower block: the contact pressure must be p at every interface vertex.
Written by: python3 experiments/benchmarks.py scenes"""


def patch_scene(path, nl, nu, ny=2, e_lower=1.0, e_upper=1.0, nu_p=0.3, p=0.01, eps=1e-3,
                gap=2e-3, accuracy="high", inline=True):
    """The patch test with `nl` / `nu` elements along the interface in the lower / upper
    block (`ny` across each)."""
    lo_pts, lo_tris = rectangle(0.0, 1.0, 0.0, 0.5, nl, ny)
    up_pts, up_tris = rectangle(0.0, 1.0, 0.5 + gap, 1.0 + gap, nu, ny)
    d = 0.01  # half-width of the selection boxes, below every element size used

    def body(name, pts, tris, e, supports, traction=None, mesh_name=None):
        b = {"name": name, "kind": "solid"}
        if inline:
            b["vertices"] = [[round(x, 15), round(y, 15)] for x, y in pts]
            b["elements"] = tris
        else:
            write_msh(os.path.join(os.path.dirname(path), mesh_name), pts, tris, 2)
            b["mesh"] = mesh_name
        b["material"] = {"model": "linear-elastic", "E": e, "nu": nu_p, "plane": "strain"}
        b["support"] = supports
        if traction:
            b["traction"] = traction
        return b

    sides = [
        {"box": {"min": [-d, -1.0], "max": [d, 2.0]}, "components": [0]},
        {"box": {"min": [1.0 - d, -1.0], "max": [1.0 + d, 2.0]}, "components": [0]},
    ]
    stem = os.path.splitext(os.path.basename(path))[0]
    lower = body("lower", lo_pts, lo_tris, e_lower,
                 [{"box": {"min": [-1.0, -d], "max": [2.0, d]}, "components": [1]}] + sides,
                 mesh_name=stem + "_lower.msh")
    upper = body("upper", up_pts, up_tris, e_upper, sides,
                 traction=[{"box": {"min": [-1.0, 1.0 + gap - d], "max": [2.0, 2.0]},
                            "pressure": p}],
                 mesh_name=stem + "_upper.msh")
    header = {"name": stem, "dim": 2, "eps": eps, "contact": {"self": []},
              "solver": {"accuracy": accuracy}}
    write_scene(path, header, [lower, upper], PATCH_COMMENT.format(nl=nl, nu=nu))


def patch(args):
    """results/patch_test.csv: the patch test on non-matching meshes, both orders of which mesh
    is finer, with and without a stiffness contrast, per backend and tolerance."""
    work = os.path.join(args.work, "patch")
    os.makedirs(work, exist_ok=True)
    p = 0.01
    solvers = [("clarabel", "default", []), ("clarabel", "high", []),
               ("clarabel", "high", ["--qp-tol", "1e-12"]),
               ("osqp", "high", ["--qp-tol", "1e-10"])]
    rows = []
    for (nl, nu, ny) in [(4, 3, 2), (3, 4, 2), (10, 7, 4), (7, 10, 4), (21, 13, 6), (13, 21, 6)]:
        for e_up in [1.0, 100.0, 0.01]:
            for eps in [1e-3, 1e-5]:
                name = "patch_%d_%d_E%g_eps%g" % (nl, nu, e_up, eps)
                scene = os.path.join(work, name + ".toml")
                patch_scene(scene, nl, nu, ny, e_upper=e_up, p=p, eps=eps, gap=2 * eps,
                            inline=False)
                for backend, acc, extra in solvers:
                    if eps == 1e-5 and (backend, acc, extra) != ("clarabel", "high", []):
                        continue
                    tag = "%s_%s%s" % (backend, acc, "".join(extra).replace("--qp-tol", "_"))
                    out = os.path.join(work, name + "_" + tag)
                    code, dt, summ = run(scene, out, ["--backend", backend, "--accuracy", acc] + extra)
                    row = {"n_lower": nl, "n_upper": nu, "finer": "lower" if nl > nu else "upper",
                           "E_upper_over_E_lower": e_up, "eps": eps, "p": p, "backend": backend,
                           "accuracy": acc, "qp_tol": summ["qp_tol"], "status": summ["status"],
                           "outer_iterations": summ["outer_iterations"], "wall_time_s": round(dt, 3)}
                    if os.path.exists(os.path.join(out, "contacts.csv")):
                        # every status writes its contact outputs; the status column says
                        # whether the state is a certified minimum
                        cs = contacts(out)
                        inter = [c for c in cs if c["normal_force"] > 0.0]
                        rel = lambda key: max(abs(c[key] - p) / p for c in inter)
                        row.update({
                            "interface_vertices": len(inter),
                            "max_rel_err_pressure_nominal": rel("pressure_nominal"),
                            "max_rel_err_pressure_cauchy": rel("pressure"),
                            "max_rel_err_pressure_pairs": rel("pressure_pairs"),
                            "max_gap_minus_eps": max(c["gap"] for c in inter),
                            "upper_contact_force_over_p":
                                sum(c["fy"] for c in inter if c["body"] == "upper") / p,
                            "reaction_y_over_p": summ["contact"]["reaction_total"][1] / p,
                        })
                    rows.append(row)
                    print(name, tag, summ["status"], "err %s" % row.get("max_rel_err_pressure_nominal"))
    fields = []
    for r in rows:
        fields += [k for k in r if k not in fields]
    write_csv(os.path.join(ROOT, "results", "patch_test.csv"),
              [{k: fmt(v) for k, v in r.items()} for r in rows], fields)


# --------------------------------------------------------------------------------------------
# Hertz contact in 2D: a cylinder on a flat, plane strain
# --------------------------------------------------------------------------------------------

HERTZ2D_COMMENT = """Hertz contact in 2D (plane strain): a linear-elastic cylinder of radius R = {R} pressed by a
load P = {P:.6e} per unit length onto a {flat}. By symmetry only the half x >= 0 is
meshed: the quarter disk {{x >= 0, y <= y_c}} with u_x = 0 on x = 0, and a dead traction
-P/(2R) on its top (the diameter y = y_c), so that the half carries P/2. Hertz: a =
sqrt(4 P R / (pi E*)) = {a:.6e}, p0 = 2 P / (pi a) = {p0:.6e}, E* = {Estar:.6e}.
Mesh: the arc graded from h_c = {hc:.3e} at the contact point. [solver] qp_tol = 1e-11: the
pressure error from the scatter of the final gaps is about E * scatter / h_c, and at the
default 1e-9 the finest mesh's p0 was 5% off (results/README.md).
Written by: python3 experiments/benchmarks.py {cmd}"""


def hertz2d_scene(path, level, flat="rigid", eps_rel=1e-2, R=1.0, E=1.0, nu=0.3, a_target=0.05,
                  accuracy="default", cmd="hertz2d", si=None):
    """A Hertz 2D scene at refinement `level` (h_c = a/5 / 2^level); `flat` is "rigid" or
    "elastic" (a block [0, 4R] x [-4R, 0] of the same material). Returns the analytic values.
    `si = (E0, L0)` scales lengths by L0 and moduli and loads by E0 (the units twin)."""
    k = 2 ** level
    hc = a_target / 5 / k
    eps = eps_rel * hc
    e_plane = E / (1 - nu * nu)
    estar = e_plane if flat == "rigid" else e_plane / 2
    P = math.pi * estar * a_target ** 2 / (4 * R)
    a, p0 = a_target, 2 * P / (math.pi * a_target)
    yc = R + 2 * eps
    L0, E0 = (1.0, 1.0) if si is None else (si[1], si[0])
    sc = lambda pts: [(x * L0, y * L0) for x, y in pts]
    d = 1e-3 * hc * L0
    stem = os.path.splitext(os.path.basename(path))[0]
    cyl = quarter_disk(R, yc, 30 * k, 10 * k, 20 * k, hc)
    write_msh(os.path.join(os.path.dirname(path), stem + "_cylinder.msh"), sc(cyl.points), cyl.tris, 2)
    mat = {"model": "linear-elastic", "E": E * E0, "nu": nu, "plane": "strain"}
    sym = {"box": {"min": [-d, -1e3 * L0], "max": [d, 1e3 * L0]}, "components": [0]}
    cylinder = {
        "name": "cylinder", "kind": "solid", "mesh": stem + "_cylinder.msh", "material": mat,
        "support": [sym],
        "traction": [{"box": {"min": [-1e3 * L0, (yc - 1e-6) * L0], "max": [1e3 * L0, 1e3 * L0]},
                      "traction": [0.0, -P / (2 * R) * E0]}],
    }
    if flat == "rigid":
        flat_body = {"name": "flat", "kind": "curve",
                     "vertices": [[-0.5 * R * L0, 0.0], [1.5 * R * L0, 0.0]],
                     "elements": [[0, 1]], "fixed": {"all": True}}
        flat_desc = "rigid flat (a fixed straight edge)"
    else:
        W = 4 * R
        xs = [x / W for x in geometric(24 * k, 1.37 * hc, W)]
        ys = [1 - y / W for y in reversed(geometric(24 * k, 1.37 * hc, W))]
        pts, tris = rectangle(0.0, W, -W, 0.0, 24 * k, 24 * k, xs, ys)
        write_msh(os.path.join(os.path.dirname(path), stem + "_flat.msh"), sc(pts), tris, 2)
        flat_body = {"name": "flat", "kind": "solid", "mesh": stem + "_flat.msh", "material": mat,
                     "support": [sym, {"box": {"min": [-1e3 * L0, (-W - 1e-6) * L0],
                                               "max": [1e3 * L0, (-W + 1e-6) * L0]},
                                       "components": [1]}]}
        flat_desc = ("linear-elastic flat (the block [0, 4R] x [-4R, 0] of the same material, u_x = 0 "
                     "on x = 0, u_y = 0 at its base), meshed with steps 1.37 h_c at the contact (non-matching)")
    header = {"name": stem, "dim": 2, "eps": eps * L0,
              "contact": {"pairs": [["cylinder", "flat"]], "self": []},
              "solver": {"accuracy": accuracy, "qp_tol": 1e-11}}
    write_scene(path, header, [cylinder, flat_body],
                HERTZ2D_COMMENT.format(R=R, P=P, flat=flat_desc, a=a, p0=p0, Estar=estar, hc=hc,
                                       cmd=cmd))
    surf = {"cylinder": lambda c: abs(math.hypot(c["x_ref"] / L0, c["y_ref"] / L0 - yc) - R) < 1e-9,
            "flat": lambda c: abs(c["y_ref"]) < 1e-12 * L0}
    return {"a": a, "p0": p0, "P": P, "hc": hc, "eps": eps, "L0": L0, "E0": E0, "surface": surf}


def hertz_measure(out, ref, body, dim=2, L0=1.0, E0=1.0, surface=None):
    """a and p0 of the run in `out` from the contact vertices of `body` at their reference
    positions (x >= 0; in 3D r = |(x, y)|): p0 the nominal pressure of the vertex on the axis, a from the moments of the
    nodal forces (M0 = sum f, M2 = sum f r^2; 2D: a^2 = 4 M2 / M0, 3D: a^2 = 2.5 M2 / M0, the
    ratios of a Hertz profile), a_edge the midpoint between the last vertex loaded above 1e-3 of
    the largest nodal force and the next one."""
    cs = [c for c in contacts(out) if c["body"] == body and (surface is None or surface(c))]
    for c in cs:
        # reference positions: linear (Hertz) theory does not move the points
        c["r"] = (math.hypot(c["x_ref"], c["y_ref"]) if dim == 3 else abs(c["x_ref"])) / L0
        c["p"] = c["pressure_nominal"] / E0
        c["pp"] = c["pressure_pairs"] / E0
        c["p2"] = c["pressure_nominal_two_sided"] / E0
        c["f"] = c["normal_force"] / (E0 * L0 ** (dim - 1))
    cs.sort(key=lambda c: c["r"])
    fmax = max(c["f"] for c in cs)
    loaded = [c for c in cs if c["f"] > 1e-3 * fmax]
    m0 = sum(c["f"] for c in loaded)
    m2 = sum(c["f"] * c["r"] ** 2 for c in loaded)
    a_mom = math.sqrt((4.0 if dim == 2 else 2.5) * m2 / m0)
    last = max(c["r"] for c in loaded)
    after = [c["r"] for c in cs if c["r"] > last]
    a_edge = 0.5 * (last + min(after)) if after else last
    axis = min(cs, key=lambda c: c["r"])
    prof = lambda r: ref["p0"] * math.sqrt(max(0.0, 1 - (r / ref["a"]) ** 2))
    dev = max(abs(c["p"] - prof(c["r"])) for c in cs if c["r"] <= ref["a"]) / ref["p0"]
    dev_pairs = max(abs(c["pp"] - prof(c["r"])) for c in cs if c["r"] <= ref["a"]) / ref["p0"]
    dev_two = max(abs(c["p2"] - prof(c["r"])) for c in cs if c["r"] <= ref["a"]) / ref["p0"]
    return {"a_moment": a_mom, "a_edge": a_edge, "p0": axis["p"], "p0_two_sided": axis["p2"],
            "force": m0, "max_dev": dev, "max_dev_pairs": dev_pairs, "max_dev_two_sided": dev_two,
            "rows": cs}


def hertz2d(args):
    """results/hertz2d.csv (a and p0 against h_c and eps, rigid and elastic flat) and
    results/hertz2d_profile.csv (the pressure profiles)."""
    cases = [("rigid", lvl, 1e-2) for lvl in range(args.levels)]
    cases += [("rigid", args.eps_level, e) for e in (1e-1, 1e-3, 1e-4)]
    cases += [("elastic", lvl, 1e-2) for lvl in range(args.elastic_levels)]
    cases += [("elastic", args.eps_level, e) for e in (1e-1, 1e-3)]
    hertz2d_study(os.path.join(args.work, "hertz2d"), cases, [], "hertz2d", False)


def hertz2d_sqp(args):
    """results/hertz2d_sqp.csv and results/hertz2d_sqp_profile.csv: the elastic-flat levels of
    `hertz2d` run with `--outer-method sqp`, with the certificate (Pantz's outer map creeps
    there and stops at uncertified fixed points)."""
    cases = [("elastic", lvl, 1e-2) for lvl in range(args.elastic_levels)]
    hertz2d_study(os.path.join(args.work, "hertz2d_sqp"), cases,
                  ["--outer-method", "sqp"], "hertz2d_sqp", True)


def hertz2d_study(work, cases, extra, stem, with_kappa):
    """Runs the Hertz 2D `cases` ((flat, level, eps/h_c)) with the extra `contactlab run`
    arguments and writes results/<stem>.csv and results/<stem>_profile.csv."""
    os.makedirs(work, exist_ok=True)
    rows, prof = [], []
    for flat, lvl, er in cases:
        name = "hertz2d_%s_l%d_eps%g" % (flat, lvl, er)
        scene = os.path.join(work, name + ".toml")
        ref = hertz2d_scene(scene, lvl, flat, er)
        out = os.path.join(work, name)
        code, dt, summ = run(scene, out, extra)
        m = hertz_measure(out, ref, "cylinder", surface=ref["surface"]["cylinder"])
        row = {"flat": flat, "level": lvl, "h_c": ref["hc"], "eps": ref["eps"], "eps_over_hc": er,
               "vertices": summ["n"], "status": summ["status"],
               "outer_iterations": summ["outer_iterations"],
               "a": ref["a"], "a_moment": m["a_moment"], "a_edge": m["a_edge"],
               "p0": ref["p0"], "p0_vertex": m["p0"],
               "err_a_moment": abs(m["a_moment"] - ref["a"]) / ref["a"],
               "err_a_edge": abs(m["a_edge"] - ref["a"]) / ref["a"],
               "err_p0": abs(m["p0"] - ref["p0"]) / ref["p0"],
               "half_load_over_P2": m["force"] / (ref["P"] / 2),
               "max_dev_profile": m["max_dev"], "max_dev_profile_pairs": m["max_dev_pairs"],
               "max_dev_profile_two_sided": m["max_dev_two_sided"],
               "err_p0_two_sided": abs(m["p0_two_sided"] - ref["p0"]) / ref["p0"],
               "wall_time_s": round(dt, 2)}
        if with_kappa:
            row["outer_method"] = summ.get("outer_method")
            row["sqp_steps"] = summ.get("sqp_steps")
            row["fallback_steps"] = summ.get("fallback_steps")
            row["kappa"] = summ["certificate"]["kappa"]
            row["final_energy"] = summ["final_energy"]
        if flat == "elastic":
            mf = hertz_measure(out, ref, "flat", surface=ref["surface"]["flat"])
            row["a_moment_flat"] = mf["a_moment"]
            row["err_p0_flat"] = abs(mf["p0"] - ref["p0"]) / ref["p0"]
            row["max_dev_profile_flat"] = mf["max_dev"]
            row["max_dev_profile_pairs_flat"] = mf["max_dev_pairs"]
            row["max_dev_profile_two_sided_flat"] = mf["max_dev_two_sided"]
        rows.append(row)
        print(name, summ["status"], summ["outer_iterations"],
              "a %.4e (%.2e) p0 %.4e (%.2e) dev %.2e two-sided %.2e pairs %.2e %.1fs" % (
                  m["a_moment"], row["err_a_moment"], m["p0"], row["err_p0"], m["max_dev"],
                  m["max_dev_two_sided"], m["max_dev_pairs"], dt))
        if er == 1e-2:
            bodies = ["cylinder"] + (["flat"] if flat == "elastic" else [])
            for b in bodies:
                mm = m if b == "cylinder" else mf
                for c in mm["rows"]:
                    if c["r"] <= 1.6 * ref["a"]:
                        prof.append({"case": "%s_l%d_%s" % (flat, lvl, b), "flat": flat,
                                     "level": lvl, "body": b, "status": summ["status"],
                                     "x_over_a": c["r"] / ref["a"], "p_over_p0": c["p"] / ref["p0"],
                                     "pairs_over_p0": c["pp"] / ref["p0"],
                                     "two_sided_over_p0": c["p2"] / ref["p0"],
                                     "hertz_over_p0": math.sqrt(max(0.0, 1 - (c["r"] / ref["a"]) ** 2))})
    for flat in ("rigid", "elastic"):
        sub = [r for r in rows if r["flat"] == flat and r["eps_over_hc"] == 1e-2]
        if len(sub) >= 2:
            for key in ("err_a_moment", "err_p0"):
                print(flat, key, "fitted rate %.2f" % fit_slope([r["h_c"] for r in sub], [r[key] for r in sub]))
    fields = []
    for r in rows:
        fields += [k for k in r if k not in fields]
    write_csv(os.path.join(ROOT, "results", stem + ".csv"),
              [{k: fmt(v) for k, v in r.items()} for r in rows], fields)
    write_csv(os.path.join(ROOT, "results", stem + "_profile.csv"),
              [{k: fmt(v) for k, v in r.items()} for r in prof], list(prof[0].keys()))


# --------------------------------------------------------------------------------------------
# Hertz contact in 3D: a sphere on a rigid flat
# --------------------------------------------------------------------------------------------

HERTZ3D_COMMENT = """Hertz contact in 3D: a linear-elastic body whose lower face is the sphere of radius R = {R}
(centre on the z axis), pressed by a load P = {P:.6e} onto a rigid flat. By symmetry one quarter
is meshed: the block x, y in [0, {L}], from the spherical face up to z = {top:.4f}, with u_x = 0
on x = 0, u_y = 0 on y = 0 and a dead traction -P/(4 L^2) on its top. Hertz: a =
(3 P R / (4 E*))^(1/3) = {a:.6e}, p0 = 3 P / (2 pi a^2) = {p0:.6e}, E* = E/(1 - nu^2) =
{Estar:.6e}. The body is a finite block, not a half-space (a/L = {aL:.3f}). Mesh: hexahedra
graded from h_c = {hc:.3e} at the contact point, 6 tetrahedra each.
Written by: python3 experiments/benchmarks.py hertz3d (or scenes)"""


def hertz3d_scene(path, n, R=1.0, E=1.0, nu=0.3, a_target=0.1, L=0.6, H=0.6, eps_rel=1e-2,
                  accuracy="default"):
    """A Hertz 3D scene with n x n x n graded cells (h_c = 3 a / n)."""
    hc = 3 * a_target / n
    eps = eps_rel * hc
    estar = E / (1 - nu * nu)
    P = 4 * estar * a_target ** 3 / (3 * R)
    p0 = 3 * P / (2 * math.pi * a_target ** 2)
    zc = R + 2 * eps
    top = 2 * eps + H
    xs = geometric(n, hc, L)
    zs = [t / H for t in geometric(n, hc, H)]
    m = n + 1
    pts = []
    for k in range(m):
        for j in range(m):
            for i in range(m):
                x, y = xs[i], xs[j]
                zb = zc - math.sqrt(R * R - x * x - y * y)
                pts.append((x, y, zb + (top - zb) * zs[k]))
    step = [1, m, m * m]
    tets = []
    for k in range(n):
        for j in range(n):
            for i in range(n):
                v0 = i + m * j + m * m * k
                for pm in ([0, 1, 2], [0, 2, 1], [1, 0, 2], [1, 2, 0], [2, 0, 1], [2, 1, 0]):
                    v1 = v0 + step[pm[0]]
                    v2 = v1 + step[pm[1]]
                    v3 = v2 + step[pm[2]]
                    t = [v0, v1, v2, v3]
                    a, b, c, d = (pts[v] for v in t)
                    u = [b[q] - a[q] for q in range(3)]
                    w = [c[q] - a[q] for q in range(3)]
                    z = [d[q] - a[q] for q in range(3)]
                    vol = (u[0] * (w[1] * z[2] - w[2] * z[1]) - u[1] * (w[0] * z[2] - w[2] * z[0])
                           + u[2] * (w[0] * z[1] - w[1] * z[0]))
                    tets.append(t if vol > 0 else [v0, v2, v1, v3])
    stem = os.path.splitext(os.path.basename(path))[0]
    write_msh(os.path.join(os.path.dirname(path), stem + "_sphere.msh"), pts, tets, 4)
    d = 1e-3 * hc
    big = 1e3
    sphere = {
        "name": "sphere", "kind": "solid", "mesh": stem + "_sphere.msh",
        "material": {"model": "linear-elastic", "E": E, "nu": nu},
        "support": [{"box": {"min": [-d, -big, -big], "max": [d, big, big]}, "components": [0]},
                    {"box": {"min": [-big, -d, -big], "max": [big, d, big]}, "components": [1]}],
        "traction": [{"box": {"min": [-big, -big, top - d], "max": [big, big, big]},
                      "traction": [0.0, 0.0, -P / (4 * L * L)]}],
    }
    flat = {"name": "flat", "kind": "surface",
            "vertices": [[-0.5 * R, -0.5 * R, 0.0], [1.5 * R, -0.5 * R, 0.0],
                         [1.5 * R, 1.5 * R, 0.0], [-0.5 * R, 1.5 * R, 0.0]],
            "elements": [[0, 1, 3], [1, 2, 3]], "fixed": {"all": True}}
    header = {"name": stem, "dim": 3, "eps": eps,
              "contact": {"pairs": [["sphere", "flat"]], "self": []},
              "solver": {"accuracy": accuracy, "qp_tol": 1e-11}}
    write_scene(path, header, [sphere, flat],
                HERTZ3D_COMMENT.format(R=R, P=P, L=L, top=top, a=a_target, p0=p0, Estar=estar,
                                       aL=a_target / L, hc=hc))
    surface = lambda c: abs(math.sqrt(c["x_ref"] ** 2 + c["y_ref"] ** 2 + (c["z_ref"] - zc) ** 2) - R) < 1e-9
    return {"a": a_target, "p0": p0, "P": P, "hc": hc, "eps": eps, "surface": surface}


def hertz3d(args):
    """results/hertz3d.csv (a and p0 against h_c) and results/hertz3d_profile.csv."""
    work = os.path.join(args.work, "hertz3d")
    os.makedirs(work, exist_ok=True)
    rows, prof = [], []
    for n in args.n3d:
        name = "hertz3d_n%d" % n
        scene = os.path.join(work, name + ".toml")
        ref = hertz3d_scene(scene, n)
        out = os.path.join(work, name)
        code, dt, summ = run(scene, out)
        m = hertz_measure(out, ref, "sphere", dim=3, surface=ref["surface"])
        # p0 of a Hertz profile with the measured half-width carrying the quarter load
        p0_fit = 3 * (4 * m["force"]) / (2 * math.pi * m["a_moment"] ** 2)
        rows.append({"n": n, "h_c": ref["hc"], "eps": ref["eps"], "vertices": summ["n"],
                     "status": summ["status"], "outer_iterations": summ["outer_iterations"],
                     "a": ref["a"], "a_moment": m["a_moment"], "a_edge": m["a_edge"],
                     "p0": ref["p0"], "p0_vertex": m["p0"], "p0_from_a_moment": p0_fit,
                     "err_p0_from_a_moment": abs(p0_fit - ref["p0"]) / ref["p0"],
                     "err_a_moment": abs(m["a_moment"] - ref["a"]) / ref["a"],
                     "err_p0": abs(m["p0"] - ref["p0"]) / ref["p0"],
                     "quarter_load_over_P4": m["force"] / (ref["P"] / 4),
                     "max_dev_profile": m["max_dev"], "max_dev_profile_pairs": m["max_dev_pairs"],
                     "wall_time_s": round(dt, 2)})
        print(name, summ["status"], "a %.4e p0 %.4e dev %.2e %.1fs" % (m["a_moment"], m["p0"], m["max_dev"], dt))
        for c in m["rows"]:
            if c["r"] <= 1.6 * ref["a"]:
                prof.append({"case": "n%d" % n, "n": n, "status": summ["status"],
                             "r_over_a": c["r"] / ref["a"], "p_over_p0": c["p"] / ref["p0"],
                             "pairs_over_p0": c["pp"] / ref["p0"],
                             "two_sided_over_p0": c["p2"] / ref["p0"],
                             "hertz_over_p0": math.sqrt(max(0.0, 1 - (c["r"] / ref["a"]) ** 2))})
    if len(rows) >= 2:
        for key in ("err_a_moment", "err_p0"):
            print(key, "fitted rate %.2f" % fit_slope([r["h_c"] for r in rows], [r[key] for r in rows]))
    write_csv(os.path.join(ROOT, "results", "hertz3d.csv"),
              [{k: fmt(v) for k, v in r.items()} for r in rows], list(rows[0].keys()))
    write_csv(os.path.join(ROOT, "results", "hertz3d_profile.csv"),
              [{k: fmt(v) for k, v in r.items()} for r in prof], list(prof[0].keys()))


# --------------------------------------------------------------------------------------------
# units: a scene in SI units and its non-dimensional twin
# --------------------------------------------------------------------------------------------

def units(args):
    """results/units.csv: Hertz 2D (rigid and elastic flat, level 1) non-dimensional (E = 1,
    R = 1) and in SI units (E = 2e11 Pa, R = 1e-2 m): a / L0, p0 / E0, outer iterations, J."""
    work = os.path.join(args.work, "units")
    os.makedirs(work, exist_ok=True)
    rows = []
    for flat in ("rigid", "elastic"):
        for si in (None, (2e11, 1e-2)):
            tag = "si" if si else "nondim"
            name = "hertz2d_%s_%s" % (flat, tag)
            scene = os.path.join(work, name + ".toml")
            ref = hertz2d_scene(scene, 1, flat, 1e-2, si=si, cmd="units")
            out = os.path.join(work, name)
            code, dt, summ = run(scene, out)
            m = hertz_measure(out, ref, "cylinder", L0=ref["L0"], E0=ref["E0"],
                              surface=ref["surface"]["cylinder"])
            e_scale = ref["E0"] * ref["L0"] ** 2
            rows.append({"flat": flat, "units": tag, "E0": ref["E0"], "L0": ref["L0"],
                         "status": summ["status"], "outer_iterations": summ["outer_iterations"],
                         "final_energy": summ["final_energy"],
                         "final_energy_over_E0_L0sq": summ["final_energy"] / e_scale,
                         "a_moment_over_L0": m["a_moment"], "p0_vertex_over_E0": m["p0"],
                         "max_dev_profile": m["max_dev"], "wall_time_s": round(dt, 2)})
            print(name, summ["status"], summ["outer_iterations"], m["a_moment"], m["p0"])
    write_csv(os.path.join(ROOT, "results", "units.csv"),
              [{k: fmt(v) for k, v in r.items()} for r in rows], list(rows[0].keys()))


def scenes(args):
    """The committed example scene files (the coarsest levels: each runs in seconds)."""
    d = os.path.join(ROOT, "experiments", "scenes", "benchmarks")
    os.makedirs(d, exist_ok=True)
    patch_scene(os.path.join(d, "patch_test.toml"), 4, 3, 2)
    hertz2d_scene(os.path.join(d, "hertz2d_rigid.toml"), 0, "rigid", cmd="scenes")
    hertz2d_scene(os.path.join(d, "hertz2d_elastic.toml"), 0, "elastic", cmd="scenes")
    hertz3d_scene(os.path.join(d, "hertz3d.toml"), 8)


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("what", choices=["scenes", "patch", "hertz2d", "hertz2d_sqp", "hertz3d", "units"])
    ap.add_argument("--work", default=os.path.join(ROOT, "runs", "benchmarks"))
    ap.add_argument("--levels", type=int, default=4, help="mesh levels of the rigid-flat study")
    ap.add_argument("--elastic-levels", type=int, default=3,
                    help="mesh levels of the elastic-flat study")
    ap.add_argument("--eps-level", type=int, default=1, help="mesh level of the eps study")
    ap.add_argument("--n3d", type=int, nargs="+", default=[12, 15, 18],
                    help="cells per direction of the 3D meshes")
    ap.add_argument("--reuse", action="store_true",
                    help="read the run directories made from the same scene text instead of rerunning")
    args = ap.parse_args()
    global REUSE
    REUSE = args.reuse
    globals()[args.what](args)


if __name__ == "__main__":
    main()
