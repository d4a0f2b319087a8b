//! Seeded fuzz and property tests.
//!
//! * Parsers: random bytes and mutated valid files (scene TOML, `.msh`, `.obj`) must give `Ok`
//!   or `Err`, never a panic. Scene files are loaded as a run loads them, with the solver's
//!   rules for `[solver]` and `[dynamics]` (`harness::scene_file::SolveRules`).
//! * Distance kernels (`point_edge`, `point_triangle`, `segment_segment`): on finite inputs,
//!   degenerate ones included, no NaN; symmetric under the argument swaps that leave the
//!   distance unchanged; equal to a dense sampling of the primitives within the sampling's
//!   own error bound (Lipschitz: `L/N` for a parameter step `1/N` on an element of longest
//!   edge `L`), never above the sampled minimum.
//!
//! CI runs a few hundred cases per target (a few seconds); `CONTACTLAB_FUZZ_SCALE=K`
//! multiplies every case count by `K`, e.g. `CONTACTLAB_FUZZ_SCALE=100 cargo test --release
//! --test fuzz`.

use contactlab::contact::distance::{
    edge_edge_distance, point_edge_distance, point_triangle_distance,
};
use contactlab::harness::scene_file::SolveRules;
use contactlab::scene::file;
use contactlab::scene::meshio::{msh::parse_msh, obj::parse_obj};
use nalgebra::{Vector2, Vector3};
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;
use std::cell::Cell;
use std::path::{Path, PathBuf};

fn scale() -> usize {
    std::env::var("CONTACTLAB_FUZZ_SCALE")
        .ok()
        .and_then(|s| s.parse().ok())
        .unwrap_or(1)
        .max(1)
}

fn root() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR"))
}

const TOKENS: &[&str] = &[
    "nan",
    "inf",
    "-inf",
    "0",
    "-0",
    "-1",
    "1e308",
    "-1e308",
    "1e-320",
    "99999999999999999999",
    "18446744073709551616",
    "[",
    "]",
    "{",
    "}",
    "=",
    "\"",
    "\n",
    "[[body]]",
    "#",
    ",",
    "$Nodes",
    "$EndNodes",
    "$Elements",
    "4.1",
    "2.2",
    "v",
    "l",
    "f",
    "-2",
    "/",
    "1/1/1",
    "true",
];

/// One random mutation of `text`: delete, insert bytes or a token, replace a number, duplicate
/// or drop a line, truncate.
fn mutate(rng: &mut ChaCha8Rng, text: &str) -> String {
    let mut b = text.as_bytes().to_vec();
    let n = b.len().max(1);
    match rng.gen_range(0..7) {
        0 => {
            let i = rng.gen_range(0..n);
            let j = (i + rng.gen_range(1..20)).min(b.len());
            if i < b.len() {
                b.drain(i..j);
            }
        }
        1 => {
            let i = rng.gen_range(0..=b.len());
            let k = rng.gen_range(1..8);
            let ins: Vec<u8> = (0..k).map(|_| rng.gen()).collect();
            b.splice(i..i, ins);
        }
        2 => {
            let i = rng.gen_range(0..=b.len());
            let t = TOKENS[rng.gen_range(0..TOKENS.len())];
            b.splice(i..i, t.bytes());
        }
        3 => {
            // replace one number-looking token
            let s = String::from_utf8_lossy(&b).into_owned();
            let starts: Vec<usize> = s
                .char_indices()
                .filter(|&(i, c)| {
                    c.is_ascii_digit() && (i == 0 || !s.as_bytes()[i - 1].is_ascii_alphanumeric())
                })
                .map(|(i, _)| i)
                .collect();
            if !starts.is_empty() {
                let i = starts[rng.gen_range(0..starts.len())];
                let j = s[i..]
                    .find(|c: char| !(c.is_ascii_alphanumeric() || c == '.' || c == '-'))
                    .map_or(s.len(), |k| i + k);
                let t = TOKENS[rng.gen_range(0..10)];
                return format!("{}{}{}", &s[..i], t, &s[j..]);
            }
        }
        4 | 5 => {
            let s = String::from_utf8_lossy(&b).into_owned();
            let mut lines: Vec<&str> = s.lines().collect();
            if !lines.is_empty() {
                let i = rng.gen_range(0..lines.len());
                if rng.gen_bool(0.5) {
                    let l = lines[i];
                    lines.insert(rng.gen_range(0..=lines.len()), l);
                } else {
                    lines.remove(i);
                }
            }
            return lines.join("\n");
        }
        _ => {
            let k = rng.gen_range(0..=b.len());
            b.truncate(k);
        }
    }
    String::from_utf8_lossy(&b).into_owned()
}

/// Feeds `cases` mutants (1 to 4 mutations each) and random-byte strings to `f`, reporting the
/// input of any panic.
fn fuzz(seed: u64, seeds: &[String], cases: usize, f: &dyn Fn(&str)) {
    let mut rng = ChaCha8Rng::seed_from_u64(seed);
    for case in 0..cases {
        let text = if case % 10 == 9 {
            let k = rng.gen_range(0..200);
            String::from_utf8_lossy(&(0..k).map(|_| rng.gen()).collect::<Vec<u8>>()).into_owned()
        } else {
            let mut t = seeds[case % seeds.len()].clone();
            for _ in 0..rng.gen_range(1..=4) {
                t = mutate(&mut rng, &t);
            }
            t
        };
        let r = std::panic::catch_unwind(std::panic::AssertUnwindSafe(|| f(&text)));
        assert!(r.is_ok(), "case {case} panicked on input:\n{text:?}");
    }
}

fn read(p: &str) -> String {
    std::fs::read_to_string(root().join(p)).unwrap()
}

#[test]
fn fuzz_scene_loading_never_panics() {
    // mesh paths resolve next to the seeds, so mutants also exercise the mesh loading
    let ring_path = root().join("experiments/scenes/ring.toml");
    let good_path = root().join("tests/data/good_strings.toml");
    let seeds = vec![
        read("experiments/scenes/ring.toml"),
        read("tests/data/good_strings.toml"),
        read("tests/data/bad/unbounded.toml"),
        read("tests/data/bad/open_gas_surface.toml"),
        // [solver] and [dynamics] tables, checked by the solver's rules: good ones, and ones
        // the rules refuse (a bad newton_model, a bad scheme)
        read("experiments/scenes/two_strings.toml"),
        read("tests/data/dynamic_string.toml"),
        read("tests/data/bad/solver_bad_newton_model.toml"),
        read("tests/data/bad/dynamics_bad_scheme.toml"),
    ];
    let n = 300 * scale();
    // mutants that only the solver's rules refuse: the loader under test applies them (the
    // scene stage's `parse` alone accepts these)
    let refused_by_rules = Cell::new(0);
    fuzz(1, &seeds, n, &|t: &str| {
        for path in [&ring_path, &good_path] {
            let run = file::parse_with(t, path, &SolveRules);
            if run.is_err() && file::parse(t, path).is_ok() {
                refused_by_rules.set(refused_by_rules.get() + 1);
            }
        }
    });
    assert!(
        refused_by_rules.get() > 0,
        "no mutant was refused by the [solver] or [dynamics] rules alone"
    );
}

#[test]
fn fuzz_msh_and_obj_readers_never_panic() {
    let msh = vec![
        read("experiments/scenes/solids_lower.msh"),
        read("tests/data/bad/inverted_tet.msh"),
        read("tests/data/bad/dangling.msh"),
    ];
    let obj = vec![
        read("experiments/scenes/ring_ring.obj"),
        read("experiments/scenes/sheets_lower.obj"),
        read("tests/data/bad/inverted_triangle.obj"),
    ];
    let n = 1000 * scale();
    fuzz(2, &msh, n, &|t: &str| {
        let _ = parse_msh(t, "fuzz.msh");
    });
    fuzz(3, &obj, n, &|t: &str| {
        let _ = parse_obj(t, "fuzz.obj");
    });
}

#[test]
fn fuzz_read_mesh_file_on_random_files_never_panics() {
    let dir = std::env::temp_dir().join("contactlab-fuzz-files");
    std::fs::create_dir_all(&dir).unwrap();
    let mut rng = ChaCha8Rng::seed_from_u64(4);
    for case in 0..50 * scale() {
        let ext = ["msh", "obj", "txt"][case % 3];
        let p = dir.join(format!("f{case}.{ext}"));
        let k = rng.gen_range(0..300);
        std::fs::write(&p, (0..k).map(|_| rng.gen()).collect::<Vec<u8>>()).unwrap();
        let r =
            std::panic::catch_unwind(|| contactlab::scene::meshio::read_mesh_file(Path::new(&p)));
        assert!(r.is_ok(), "panic on {}", p.display());
    }
}

/// A random coordinate: mixed scales, with repeats and exact zeros to hit degenerate cases.
fn coord(rng: &mut ChaCha8Rng, pool: &[f64]) -> f64 {
    match rng.gen_range(0..5) {
        0 => pool[rng.gen_range(0..pool.len())],
        1 => 0.0,
        2 => rng.gen_range(-1e-8..1e-8),
        3 => rng.gen_range(-1e3..1e3),
        _ => rng.gen_range(-1.0..1.0),
    }
}

fn v3(rng: &mut ChaCha8Rng, pool: &[f64]) -> Vector3<f64> {
    Vector3::new(coord(rng, pool), coord(rng, pool), coord(rng, pool))
}

/// Degenerate configurations: repeated points, collinear points.
fn maybe_degenerate(rng: &mut ChaCha8Rng, pts: &mut [Vector3<f64>]) {
    match rng.gen_range(0..4) {
        0 => {
            let (i, j) = (rng.gen_range(0..pts.len()), rng.gen_range(0..pts.len()));
            pts[i] = pts[j];
        }
        1 if pts.len() >= 3 => {
            let t = rng.gen_range(-2.0..2.0);
            pts[2] = pts[0] + (pts[1] - pts[0]) * t;
        }
        _ => {}
    }
}

#[test]
fn fuzz_point_edge_no_nan_symmetric_and_matches_sampling() {
    let mut rng = ChaCha8Rng::seed_from_u64(5);
    let pool = [0.5, -0.25, 1.0, 3.0];
    for _ in 0..3000 * scale() {
        let mut p: Vec<Vector3<f64>> = (0..3).map(|_| v3(&mut rng, &pool)).collect();
        maybe_degenerate(&mut rng, &mut p);
        let q = |v: &Vector3<f64>| Vector2::new(v.x, v.y);
        let (x, a0, a1) = (q(&p[0]), q(&p[1]), q(&p[2]));
        let r = point_edge_distance(&x, &a0, &a1);
        assert!(r.distance.is_finite() && r.distance >= 0.0, "{p:?} {r:?}");
        assert!(r.alpha.iter().all(|a| a.is_finite()));
        let rev = point_edge_distance(&x, &a1, &a0);
        let scale = x.norm() + a0.norm() + a1.norm();
        assert!((rev.distance - r.distance).abs() <= 1e-12 * scale, "{p:?}");
        let n = 200;
        let sampled = (0..=n)
            .map(|k| (a0 + (a1 - a0) * (k as f64 / n as f64) - x).norm())
            .fold(f64::INFINITY, f64::min);
        let l = (a1 - a0).norm();
        assert!(r.distance <= sampled + 1e-12 * scale, "{p:?}");
        assert!(
            sampled - r.distance <= l / n as f64 + 1e-12 * scale,
            "{p:?}"
        );
    }
}

#[test]
fn fuzz_point_triangle_no_nan_symmetric_and_matches_sampling() {
    let mut rng = ChaCha8Rng::seed_from_u64(6);
    let pool = [0.5, -0.25, 1.0, 3.0];
    for _ in 0..1500 * scale() {
        let mut p: Vec<Vector3<f64>> = (0..4).map(|_| v3(&mut rng, &pool)).collect();
        let mut tri = [p[1], p[2], p[3]];
        maybe_degenerate(&mut rng, &mut tri);
        p[1..].copy_from_slice(&tri);
        let r = point_triangle_distance(&p[0], &p[1], &p[2], &p[3]);
        assert!(r.distance.is_finite() && r.distance >= 0.0, "{p:?} {r:?}");
        assert!(r.beta.iter().all(|b| b.is_finite()));
        let scale: f64 = p.iter().map(|v| v.norm()).sum();
        for perm in [[2, 3, 1], [3, 1, 2], [1, 3, 2]] {
            let s = point_triangle_distance(&p[0], &p[perm[0]], &p[perm[1]], &p[perm[2]]);
            assert!(
                (s.distance - r.distance).abs() <= 1e-12 * scale,
                "{p:?} {perm:?}"
            );
        }
        let n = 60;
        let mut sampled = f64::INFINITY;
        for i in 0..=n {
            for j in 0..=n - i {
                let (u, v) = (i as f64 / n as f64, j as f64 / n as f64);
                let y = p[1] + (p[2] - p[1]) * u + (p[3] - p[1]) * v;
                sampled = sampled.min((y - p[0]).norm());
            }
        }
        let l = [(p[2] - p[1]).norm(), (p[3] - p[1]).norm()];
        assert!(
            r.distance <= sampled + 1e-12 * scale,
            "{p:?} {} {sampled}",
            r.distance
        );
        assert!(
            sampled - r.distance <= (l[0] + l[1]) / n as f64 + 1e-12 * scale,
            "{p:?}"
        );
    }
}

#[test]
fn fuzz_edge_edge_no_nan_symmetric_and_matches_sampling() {
    let mut rng = ChaCha8Rng::seed_from_u64(7);
    let pool = [0.5, -0.25, 1.0, 3.0];
    for case in 0..1500 * scale() {
        let mut p: Vec<Vector3<f64>> = (0..4).map(|_| v3(&mut rng, &pool)).collect();
        maybe_degenerate(&mut rng, &mut p);
        if case % 5 == 0 {
            // parallel segments
            let t = rng.gen_range(-2.0..2.0);
            p[3] = p[2] + (p[1] - p[0]) * t;
        }
        let r = edge_edge_distance(&p[0], &p[1], &p[2], &p[3]);
        assert!(r.distance.is_finite() && r.distance >= 0.0, "{p:?} {r:?}");
        assert!(r.s.is_finite() && r.t.is_finite());
        let scale: f64 = p.iter().map(|v| v.norm()).sum();
        for s in [
            edge_edge_distance(&p[2], &p[3], &p[0], &p[1]),
            edge_edge_distance(&p[1], &p[0], &p[2], &p[3]),
            edge_edge_distance(&p[0], &p[1], &p[3], &p[2]),
        ] {
            assert!((s.distance - r.distance).abs() <= 1e-12 * scale, "{p:?}");
        }
        let n = 100;
        let mut sampled = f64::INFINITY;
        for i in 0..=n {
            let a = p[0] + (p[1] - p[0]) * (i as f64 / n as f64);
            for j in 0..=n {
                let b = p[2] + (p[3] - p[2]) * (j as f64 / n as f64);
                sampled = sampled.min((a - b).norm());
            }
        }
        let l = (p[1] - p[0]).norm() + (p[3] - p[2]).norm();
        assert!(
            r.distance <= sampled + 1e-12 * scale,
            "{p:?} {} {sampled}",
            r.distance
        );
        assert!(
            sampled - r.distance <= l / n as f64 + 1e-12 * scale,
            "{p:?}"
        );
    }
}
