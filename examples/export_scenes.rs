//! Writes the built-in scenes ring, rod, sheets and solids (default parameters) as scene files
//! in `experiments/scenes/`: one TOML each, the reference meshes (`.obj` for curves and
//! surfaces, Gmsh 2.2 `.msh` for tetrahedra) and, where the initial configuration differs from
//! the reference, an initial-position file. `tests/scenefiles.rs` checks that each file scene
//! and its built-in twin give the same energy and the same run.
//!
//! `cargo run --release --example export_scenes [DIR]`

use contactlab::mesh::{BodyKind, Mesh};
use contactlab::meshio::{write_msh22, write_obj};
use contactlab::scene::{ring, rod, sheets, solids, Scene};
use std::fmt::Write as _;
use std::path::Path;

/// The body's vertices (contiguous in the built-in numbering), as a local flat array of `x`.
fn local(mesh: &Mesh, b: usize, x: &[f64]) -> (usize, Vec<f64>) {
    let vs = &mesh.bodies[b].vertices;
    let off = vs[0];
    assert!(vs.iter().enumerate().all(|(k, &v)| v == off + k));
    let d = mesh.dim;
    (off, x[d * off..d * (off + vs.len())].to_vec())
}

/// Writes body `b`'s mesh (and initial positions if they differ); returns the TOML lines
/// `mesh = …`, `initial = …`, `fixed = …`.
fn body_files(s: &Scene, b: usize, dir: &Path, stem: &str) -> String {
    let m = &s.mesh;
    let body = &m.bodies[b];
    let (off, xr) = local(m, b, &m.x_ref);
    let (_, x0) = local(m, b, &s.x0);
    let sh2 = |e: &[usize; 2]| [e[0] - off, e[1] - off];
    let sh3 = |t: &[usize; 3]| t.map(|v| v - off);
    let sh4 = |t: &[usize; 4]| t.map(|v| v - off);
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
            BodyKind::Solid => {
                let t: Vec<_> = body.tets.iter().map(|&t| sh4(&m.tets[t])).collect();
                write_msh22(m.dim, x, &[], &[], &t)
            }
        };
        std::fs::write(dir.join(name), text).unwrap();
    };
    let ext = if body.kind == BodyKind::Solid {
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
        .filter(|&k| m.fixed[off + k])
        .collect();
    if !fixed.is_empty() {
        writeln!(out, "fixed = {{ vertices = {fixed:?} }}").unwrap();
    }
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
    println!("wrote ring, rod, sheets, solids to {}", dir.display());
}
