//! Writes the built-in scenes ring, rod, sheets, solids, balloons, balloons3d and the dynamic
//! scene drop (default parameters) as scene files in `experiments/scenes/`: one TOML each, the
//! reference meshes (`.obj` for curves, surfaces and 2D solids, Gmsh 2.2 `.msh` for
//! tetrahedra) and, where the initial configuration differs from the reference, an
//! initial-position file. The balloons' membranes are welded to the box (`weld`).
//! `tests/scenefiles.rs` checks that each file scene and its built-in twin give the same
//! energy and the same run (drop: the same first time steps).
//!
//! `cargo run --release --example export_scenes [DIR]`

use contactlab::scene::mesh::{BodyKind, Mesh};
use contactlab::scene::meshio::{write_msh22, write_obj};
use contactlab::scene::{balloons, balloons3d, dynamic, ring, rod, sheets, solids, Scene};
use std::collections::HashMap;
use std::fmt::Write as _;
use std::path::Path;

/// The body's vertices, in the order of its vertex list, as a local flat array of `x`.
fn local(mesh: &Mesh, b: usize, x: &[f64]) -> Vec<f64> {
    let d = mesh.dim;
    mesh.bodies[b]
        .vertices
        .iter()
        .flat_map(|&v| x[d * v..d * v + d].iter().copied())
        .collect()
}

/// Writes body `b`'s mesh (and initial positions if they differ); returns the TOML lines
/// `mesh = …`, `initial = …`, `fixed = …`. Local vertex `k` is the body's `vertices[k]`.
fn body_files(s: &Scene, b: usize, dir: &Path, stem: &str) -> String {
    let m = &s.mesh;
    let body = &m.bodies[b];
    let xr = local(m, b, &m.x_ref);
    let x0 = local(m, b, &s.x0);
    let loc: HashMap<usize, usize> = body
        .vertices
        .iter()
        .enumerate()
        .map(|(k, &v)| (v, k))
        .collect();
    let sh2 = |e: &[usize; 2]| e.map(|v| loc[&v]);
    let sh3 = |t: &[usize; 3]| t.map(|v| loc[&v]);
    let sh4 = |t: &[usize; 4]| t.map(|v| loc[&v]);
    let write = |name: &str, x: &[f64]| {
        let text = match body.kind {
            BodyKind::Curve => {
                let l: Vec<_> = body.edges.iter().map(|&e| sh2(&m.edges[e])).collect();
                write_obj(m.dim, x, &l, &[])
            }
            BodyKind::Surface => {
                let t: Vec<_> = body
                    .triangles
                    .iter()
                    .map(|&t| sh3(&m.triangles[t]))
                    .collect();
                write_obj(m.dim, x, &[], &t)
            }
            BodyKind::Solid if m.dim == 2 => {
                let t: Vec<_> = body
                    .triangles
                    .iter()
                    .map(|&t| sh3(&m.triangles[t]))
                    .collect();
                write_obj(m.dim, x, &[], &t)
            }
            BodyKind::Solid => {
                let t: Vec<_> = body.tets.iter().map(|&t| sh4(&m.tets[t])).collect();
                write_msh22(m.dim, x, &[], &[], &t)
            }
        };
        std::fs::write(dir.join(name), text).unwrap();
    };
    let ext = if body.kind == BodyKind::Solid && m.dim == 3 {
        "msh"
    } else {
        "obj"
    };
    let mesh_name = format!("{stem}_{}.{ext}", body.name);
    write(&mesh_name, &xr);
    let mut out = format!("mesh = {mesh_name:?}\n");
    if x0 != xr {
        let init = format!("{stem}_{}_initial.{ext}", body.name);
        write(&init, &x0);
        writeln!(out, "initial = {init:?}").unwrap();
    }
    let fixed: Vec<usize> = (0..body.vertices.len())
        .filter(|&k| m.fixed[body.vertices[k]])
        .collect();
    if fixed.len() == body.vertices.len() {
        out.push_str("fixed = { all = true }\n");
    } else if !fixed.is_empty() {
        writeln!(out, "fixed = {{ vertices = {fixed:?} }}").unwrap();
    }
    out
}

/// `weld = [...]` joining each vertex to its first occurrence, bodies written in `order`.
fn welds(m: &Mesh, order: &[usize]) -> String {
    let mut out = String::from("weld = [\n");
    for (i, &b) in order.iter().enumerate() {
        for (k, v) in m.bodies[b].vertices.iter().enumerate() {
            if let Some((a, ka)) = order[..i].iter().find_map(|&a| {
                m.bodies[a]
                    .vertices
                    .iter()
                    .position(|w| w == v)
                    .map(move |ka| (a, ka))
            }) {
                writeln!(
                    out,
                    "  [{:?}, {ka}, {:?}, {k}],",
                    m.bodies[a].name, m.bodies[b].name
                )
                .unwrap();
            }
        }
    }
    out.push_str("]\n");
    out
}

fn main() {
    let dir = std::env::args()
        .nth(1)
        .unwrap_or("experiments/scenes".into());
    let dir = Path::new(&dir);
    std::fs::create_dir_all(dir).unwrap();
    let header = |name: &str, s: &Scene| {
        format!(
            "# The built-in scene `{name}` (default parameters) as a scene file; written by\n\
             # `cargo run --release --example export_scenes`. Same energy and run as\n\
             # `contactlab run {name}` (tests/scenefiles.rs).\n\
             name = {name:?}\ndim = {}\neps = {:?}\n",
            s.mesh.dim, s.eps
        )
    };

    let p = ring::RingParams::default();
    let s = ring::build(&p).unwrap();
    let mut t = header("ring", &s);
    writeln!(
        t,
        "\n[[body]]\nname = \"ring\"\nkind = \"curve\"\n{}material = {{ model = \"string\", mu = {:?} }}\npressure = {{ p = {:?} }}",
        body_files(&s, 0, dir, "ring"),
        p.mu,
        p.p
    )
    .unwrap();
    std::fs::write(dir.join("ring.toml"), t).unwrap();

    let p = rod::RodParams::default();
    let s = rod::build(&p).unwrap();
    let mut t = header("rod", &s);
    t.push_str("gravity = [0.0, 0.0, -1.0]\n");
    writeln!(
        t,
        "\n[[body]]\nname = \"rod\"\nkind = \"curve\"\n{}material = {{ model = \"string\", mu = {:?} }}\ndensity = {:?}",
        body_files(&s, 0, dir, "rod"),
        p.mu,
        p.weight
    )
    .unwrap();
    std::fs::write(dir.join("rod.toml"), t).unwrap();

    let p = sheets::SheetsParams::default();
    let s = sheets::build(&p).unwrap();
    let mut t = header("sheets", &s);
    t.push_str("gravity = [0.0, 0.0, -1.0]\n");
    for (b, density) in [(0, 0.0), (1, p.weight)] {
        writeln!(
            t,
            "\n[[body]]\nname = {:?}\nkind = \"surface\"\n{}material = {{ model = \"stvk-membrane\", mu = {:?}, lambda = {:?} }}\ndensity = {density:?}",
            s.mesh.bodies[b].name,
            body_files(&s, b, dir, "sheets"),
            p.mu,
            p.lambda
        )
        .unwrap();
    }
    std::fs::write(dir.join("sheets.toml"), t).unwrap();

    let p = solids::SolidsParams::default();
    let s = solids::build(&p).unwrap();
    let mut t = header("solids", &s);
    for b in 0..2 {
        writeln!(
            t,
            "\n[[body]]\nname = {:?}\nkind = \"solid\"\n{}material = {{ model = \"neo-hookean\", mu = {:?}, lambda = {:?} }}",
            s.mesh.bodies[b].name,
            body_files(&s, b, dir, "solids"),
            p.mu,
            p.lambda
        )
        .unwrap();
    }
    std::fs::write(dir.join("solids.toml"), t).unwrap();

    // balloons: the box first, so that the body-by-body numbering of the file (a welded
    // vertex numbered where it first occurs) is the built-in numbering (box vertices first);
    // each membrane's two ends are welded to the box's support ends
    let p = balloons::BalloonsParams::default();
    let s = balloons::build(&p).unwrap();
    let order = [4, 0, 1, 2, 3];
    let mut t = header("balloons", &s);
    t.push_str(&welds(&s.mesh, &order));
    for &b in &order {
        let body = &s.mesh.bodies[b];
        write!(
            t,
            "\n[[body]]\nname = {:?}\nkind = \"curve\"\n{}",
            body.name,
            body_files(&s, b, dir, "balloons")
        )
        .unwrap();
        if b < 4 {
            writeln!(
                t,
                "material = {{ model = \"string\", mu = {:?} }}\ngas = {{ c = {:?} }}",
                p.mu, p.c
            )
            .unwrap();
        }
    }
    std::fs::write(dir.join("balloons.toml"), t).unwrap();

    // balloons3d: no shared vertices (each balloon is held by its fixed pad triangle)
    let p = balloons3d::Balloons3dParams::default();
    let s = balloons3d::build(&p).unwrap();
    let mut t = header("balloons3d", &s);
    for b in 0..3 {
        let body = &s.mesh.bodies[b];
        write!(
            t,
            "\n[[body]]\nname = {:?}\nkind = \"surface\"\n{}",
            body.name,
            body_files(&s, b, dir, "balloons3d")
        )
        .unwrap();
        if b < 2 {
            writeln!(
                t,
                "material = {{ model = \"stvk-membrane\", mu = {:?}, lambda = {:?} }}\ngas = {{ c = {:?} }}",
                p.mu, p.lambda, p.c
            )
            .unwrap();
        }
    }
    std::fs::write(dir.join("balloons3d.toml"), t).unwrap();

    // drop (dynamic): the ring (a 2D solid) and the fixed floor, gravity, [dynamics]
    let p = dynamic::DropParams::default();
    let ds = dynamic::drop(&p).unwrap();
    let s = &ds.scene;
    let mut t = header("drop", s).replace(
        "Same energy and run as\n# `contactlab run drop`",
        "Same energy and time steps\n# as `contactlab run drop --dynamic`",
    );
    writeln!(
        t,
        "gravity = [0.0, {:?}]\n\n[dynamics]\ndt = {:?}\nsteps = {}\nscheme = \"euler\"",
        -p.g, ds.dt, ds.steps
    )
    .unwrap();
    write!(
        t,
        "\n[[body]]\nname = \"ring\"\nkind = \"solid\"\n{}material = {{ model = \"neo-hookean\", mu = {:?}, lambda = {:?} }}\ndensity = {:?}\n",
        body_files(s, 0, dir, "drop"),
        p.ring.mu,
        p.ring.lambda,
        p.density
    )
    .unwrap();
    write!(
        t,
        "\n[[body]]\nname = \"floor\"\nkind = \"curve\"\n{}",
        body_files(s, 1, dir, "drop")
    )
    .unwrap();
    std::fs::write(dir.join("drop.toml"), t).unwrap();
    println!(
        "wrote ring, rod, sheets, solids, balloons, balloons3d, drop to {}",
        dir.display()
    );
}
