//! Starting a static run from a saved state: the positions of a run directory's `final.vtu`
//! (or any frame of the same scene), optionally perturbed, replace the scene's φ_0
//! (`contactlab run … --start-from FILE [--start-perturb A]`; docs/cli.md).
//!
//! What it is for: whether an end state is a minimum that a run returns to. A run started
//! from a perturbed copy of a certified end state should end at the same energy; a Pantz
//! fixed point that is not a minimum need not (docs/method.md, "The minimality certificate").
//!
//! The perturbation moves every free degree of freedom by `A·h·u`, `u` uniform in `[−1, 1]`
//! from a fixed-seed generator (the same file and `A` give the same start), `h` the scene's
//! mesh size. An end state has pairs at distance ε, so a random perturbation is in general
//! not admissible: while the exact check finds a pair closer than ε (or than the saved
//! state's own minimum distance, which may sit at ε minus round-off), that pair's vertices
//! keep their saved positions; if they already do, the amplitude is halved. The amplitude
//! used and the number of free vertices left unperturbed are reported.

use anyhow::{anyhow, bail, Context, Result};
use std::path::Path;

use crate::contact::min_distance;
use crate::contact::ClosestPair;
use crate::scene::mesh::Mesh;
use crate::scene::Scene;

/// The `Points` of a VTK XML unstructured-grid file written in ASCII (the run directory's
/// `final.vtu` and frames), as `dim` coordinates per point.
pub fn read_vtu_points(path: &Path, dim: usize) -> Result<Vec<f64>> {
    let text = std::fs::read_to_string(path)
        .with_context(|| format!("--start-from {}: cannot read the file", path.display()))?;
    let bad = |what: &str| anyhow!("--start-from {}: {what}", path.display());
    let start = text.find("Name=\"Points\"").ok_or_else(|| {
        bad("no DataArray named Points (not a VTK unstructured grid written by contactlab?)")
    })?;
    let rest = &text[start..];
    let open = rest
        .find('>')
        .ok_or_else(|| bad("the Points DataArray tag is not closed"))?;
    if !rest[..open].contains("format=\"ascii\"") {
        bail!(bad("the Points DataArray is not in ASCII format"));
    }
    let close = rest
        .find("</DataArray>")
        .ok_or_else(|| bad("the Points DataArray has no end tag"))?;
    let mut vals = Vec::new();
    for tok in rest[open + 1..close].split_whitespace() {
        let v: f64 = tok
            .parse()
            .map_err(|_| bad(&format!("Points holds {tok:?}, not a number")))?;
        if !v.is_finite() {
            bail!(bad(&format!("Points holds a non-finite value {v}")));
        }
        vals.push(v);
    }
    if vals.len() % 3 != 0 {
        bail!(bad(&format!(
            "Points holds {} values, not 3 per point",
            vals.len()
        )));
    }
    let n = vals.len() / 3;
    let mut x = Vec::with_capacity(dim * n);
    for p in vals.chunks_exact(3) {
        x.extend_from_slice(&p[..dim]);
    }
    Ok(x)
}

/// A small deterministic generator (xorshift64*), so that a start is reproducible without a
/// dependency.
struct Rng(u64);

impl Rng {
    fn uniform(&mut self) -> f64 {
        self.0 ^= self.0 >> 12;
        self.0 ^= self.0 << 25;
        self.0 ^= self.0 >> 27;
        let r = self.0.wrapping_mul(0x2545_F491_4F6C_DD1D);
        (r >> 11) as f64 / (1u64 << 53) as f64 * 2.0 - 1.0
    }
}

/// A start read from a file.
#[derive(Clone, Debug)]
pub struct Start {
    /// The positions.
    pub x: Vec<f64>,
    /// The perturbation amplitude used, relative to h.
    pub amplitude: f64,
    /// Free vertices left at their saved positions to keep the start admissible.
    pub unperturbed: usize,
}

/// The start read from `path` for `scene`, perturbed by `amplitude·h` on the free dofs.
/// Errors name the file and what does not match the scene: the number of points, a fixed
/// vertex that moved, a start closer than ε even without perturbation.
pub fn start_state(scene: &Scene, path: &Path, amplitude: f64) -> Result<Start> {
    let mesh = &scene.mesh;
    let dim = mesh.dim;
    if !(amplitude >= 0.0 && amplitude.is_finite()) {
        bail!("--start-perturb must be a finite number ≥ 0, got {amplitude}");
    }
    let x = read_vtu_points(path, dim)?;
    if x.len() != scene.x0.len() {
        bail!(
            "--start-from {}: {} points, but the scene {:?} has {} vertices (a state of another scene or level?)",
            path.display(),
            x.len() / dim,
            scene.name,
            mesh.nv()
        );
    }
    let diam = scene
        .x0
        .chunks_exact(dim)
        .fold(0.0f64, |m, p| p.iter().fold(m, |m, v| m.max(v.abs())))
        .max(1.0);
    for v in 0..mesh.nv() {
        for c in 0..dim {
            let k = dim * v + c;
            if mesh.dof_fixed(k) && (x[k] - scene.x0[k]).abs() > 1e-9 * diam {
                bail!(
                    "--start-from {}: vertex {v} is fixed in the scene but sits at {:?} in the file, not at {:?}",
                    path.display(),
                    &x[dim * v..dim * v + dim],
                    &scene.x0[dim * v..dim * v + dim]
                );
            }
        }
    }
    let mut x = x;
    // fixed components exactly the scene's
    for (k, (xk, &x0k)) in x.iter_mut().zip(&scene.x0).enumerate() {
        if mesh.dof_fixed(k) {
            *xk = x0k;
        }
    }
    if amplitude == 0.0 {
        return Ok(Start {
            x,
            amplitude: 0.0,
            unperturbed: 0,
        });
    }
    let mut rng = Rng(0x9E37_79B9_7F4A_7C15);
    let u: Vec<f64> = (0..x.len()).map(|_| rng.uniform()).collect();
    // The saved state is admissible up to the exact check's round-off: the perturbed one must
    // be at least as far from every contact as ε or as the saved state itself.
    let floor = min_distance(mesh, &x, scene.eps, false)
        .distance
        .min(scene.eps);
    let mut a = amplitude;
    let mut kept = vec![true; mesh.nv()];
    for _ in 0..(mesh.nv() + 40) {
        let y: Vec<f64> = x
            .iter()
            .zip(&u)
            .enumerate()
            .map(|(k, (&xi, &ui))| {
                if mesh.dof_fixed(k) || !kept[k / dim] {
                    xi
                } else {
                    xi + a * scene.h * ui
                }
            })
            .collect();
        let md = min_distance(mesh, &y, scene.eps, false);
        if md.distance >= floor {
            let unperturbed = (0..mesh.nv())
                .filter(|&v| !kept[v] && !mesh.fixed[v])
                .count();
            return Ok(Start {
                x: y,
                amplitude: a,
                unperturbed,
            });
        }
        // the closest pair's vertices keep their saved positions; if they all do already,
        // the whole perturbation is halved
        let vs = pair_vertices(mesh, &md.pair);
        if vs.iter().any(|&v| kept[v]) {
            for v in vs {
                kept[v] = false;
            }
        } else {
            a *= 0.5;
        }
    }
    bail!(
        "--start-from {}: no perturbation down to {:.3e}·h leaves the start admissible (some pair is closer than ε = {})",
        path.display(),
        a,
        scene.eps
    )
}

/// The vertices of a closest pair.
fn pair_vertices(mesh: &Mesh, p: &ClosestPair) -> Vec<usize> {
    match *p {
        ClosestPair::PointEdge { x, a0, a1, .. } => vec![x, a0, a1],
        ClosestPair::EdgeEdge { a, b } => {
            let (ea, eb) = (mesh.edges[a], mesh.edges[b]);
            vec![ea[0], ea[1], eb[0], eb[1]]
        }
        ClosestPair::PointTriangle { x, face, .. } => vec![x, face[0], face[1], face[2]],
        ClosestPair::Segments { ea, eb, .. } => vec![ea[0], ea[1], eb[0], eb[1]],
        ClosestPair::EdgeThroughFace { a, t } => {
            let (e, f) = (mesh.edges[a], mesh.faces[t]);
            vec![e[0], e[1], f[0], f[1], f[2]]
        }
        ClosestPair::None => Vec::new(),
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::output::vtk::{write_vtu_with, VtuFields};
    use crate::scene::balloons::{build, BalloonsParams};

    fn scene() -> Scene {
        build(&BalloonsParams {
            n: 8,
            ..Default::default()
        })
        .unwrap()
    }

    fn tmp_dir(tag: &str) -> std::path::PathBuf {
        let d =
            std::env::temp_dir().join(format!("contactlab_restart_{tag}_{}", std::process::id()));
        std::fs::create_dir_all(&d).unwrap();
        d
    }

    fn write(dir: &Path, s: &Scene, x: &[f64]) -> std::path::PathBuf {
        let p = dir.join("state.vtu");
        write_vtu_with(
            &p,
            s.mesh.dim,
            x,
            &s.mesh.edges,
            &[],
            &[],
            &VtuFields::default(),
        )
        .unwrap();
        p
    }

    #[test]
    fn reads_back_the_positions_it_wrote() {
        let s = scene();
        let dir = tmp_dir("read");
        let p = write(dir.as_path(), &s, &s.x0);
        let st = start_state(&s, &p, 0.0).unwrap();
        let x = st.x;
        assert_eq!(st.amplitude, 0.0);
        for (u, v) in x.iter().zip(&s.x0) {
            assert!((u - v).abs() <= 1e-15 * v.abs().max(1.0), "{u} vs {v}");
        }
    }

    #[test]
    fn a_perturbed_start_is_admissible_moves_free_dofs_only_and_is_reproducible() {
        let s = scene();
        let dir = tmp_dir("perturb");
        let p = write(dir.as_path(), &s, &s.x0);
        let st = start_state(&s, &p, 0.05).unwrap();
        let (x, a) = (st.x, st.amplitude);
        assert_eq!(x, start_state(&s, &p, 0.05).unwrap().x);
        assert!(a > 0.0 && a <= 0.05);
        let mut moved = 0;
        for (k, (&xk, &x0k)) in x.iter().zip(&s.x0).enumerate() {
            if s.mesh.dof_fixed(k) {
                assert_eq!(xk, x0k);
            } else {
                assert!((xk - x0k).abs() <= a * s.h * (1.0 + 1e-12));
                moved += usize::from(xk != x0k);
            }
        }
        assert!(moved > 0);
        assert!(min_distance(&s.mesh, &x, s.eps, false).distance >= s.eps);
    }

    #[test]
    fn a_state_of_another_scene_or_a_moved_fixed_vertex_is_refused_by_name() {
        let s = scene();
        let other = build(&BalloonsParams {
            n: 12,
            ..Default::default()
        })
        .unwrap();
        let dir = tmp_dir("refuse");
        let p = write(dir.as_path(), &other, &other.x0);
        let e = start_state(&s, &p, 0.0).unwrap_err().to_string();
        assert!(e.contains("points, but the scene"), "{e}");
        let mut x = s.x0.clone();
        let v = (0..s.mesh.nv()).find(|&v| s.mesh.fixed[v]).unwrap();
        x[2 * v] += 0.1;
        let p = write(dir.as_path(), &s, &x);
        let e = start_state(&s, &p, 0.0).unwrap_err().to_string();
        assert!(e.contains(&format!("vertex {v} is fixed")), "{e}");
        let missing = dir.as_path().join("missing.vtu");
        let e = start_state(&s, &missing, 0.0).unwrap_err().to_string();
        assert!(e.contains("missing.vtu"), "{e}");
    }
}
