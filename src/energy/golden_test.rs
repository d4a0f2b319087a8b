//! TEMPORARY (energy/ restructuring, removed when it is done): a fingerprint of every energy
//! term of every built-in scene and scene file, as raw bits, to check the restructuring bit for
//! bit against the code before it.
//!
//! For each scene, at `x0`, `x_ref` and two seeded random perturbations of `x0` (amplitudes
//! `0.05 h` and `0.3 h`), each term's [`term_bits`] (value, gradient added to a pattern, exact
//! and projected Hessian triplets in order, rank-one terms) is hashed (FNV-1a over the `u64`
//! words) with its length. `ENERGY_GOLDEN=FILE` runs it (otherwise the test does nothing);
//! with `ENERGY_GOLDEN_WRITE=1` it writes `FILE`, else it compares with `FILE` line by line.

use super::fd_test::term_bits;
use crate::scene::Scene;
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;
use std::path::Path;

fn fnv(words: &[u64]) -> u64 {
    let mut h: u64 = 0xcbf2_9ce4_8422_2325;
    for w in words {
        for b in w.to_le_bytes() {
            h ^= b as u64;
            h = h.wrapping_mul(0x0000_0100_0000_01b3);
        }
    }
    h
}

fn scenes() -> Vec<(String, Scene)> {
    use crate::scene::{balloons, balloons3d, dynamic, ring, rod, sheets, solids};
    let mut out = vec![
        (
            "static:balloons".to_string(),
            balloons::build(&balloons::BalloonsParams::default()).unwrap(),
        ),
        (
            "static:ring".to_string(),
            ring::build(&ring::RingParams {
                n: 40,
                ..Default::default()
            })
            .unwrap(),
        ),
        (
            "static:sheets".to_string(),
            sheets::build(&Default::default()).unwrap(),
        ),
        (
            "static:rod".to_string(),
            rod::build(&Default::default()).unwrap(),
        ),
        (
            "static:solids".to_string(),
            solids::build(&Default::default()).unwrap(),
        ),
        (
            "static:balloons3d".to_string(),
            balloons3d::build(&Default::default()).unwrap(),
        ),
        (
            "dynamic:drop".to_string(),
            dynamic::drop(&Default::default()).unwrap().scene,
        ),
        (
            "dynamic:collide".to_string(),
            dynamic::collide(&Default::default()).unwrap().scene,
        ),
        (
            "dynamic:drop3d".to_string(),
            dynamic::drop3d(&Default::default()).unwrap().scene,
        ),
    ];
    let root = Path::new(env!("CARGO_MANIFEST_DIR"));
    let mut files: Vec<_> = std::fs::read_dir(root.join("experiments/scenes"))
        .unwrap()
        .map(|e| e.unwrap().path())
        .filter(|p| p.extension().is_some_and(|e| e == "toml"))
        .collect();
    files.sort();
    for f in [
        "good_strings.toml",
        "dynamic_string.toml",
        "dynamic_no_density.toml",
    ] {
        files.push(root.join("tests/data").join(f));
    }
    for f in files {
        let sf = crate::scenefile::load(&f).unwrap();
        out.push((
            format!("file:{}", f.file_name().unwrap().to_string_lossy()),
            sf.scene,
        ));
    }
    out
}

fn lines() -> Vec<String> {
    let mut lines = Vec::new();
    for (label, scene) in scenes() {
        let mut rng = ChaCha8Rng::seed_from_u64(2024);
        let mut points = vec![
            ("x0", scene.x0.clone()),
            ("x_ref", scene.mesh.x_ref.clone()),
        ];
        for (tag, amp) in [("x0+0.05h", 0.05), ("x0+0.3h", 0.3)] {
            let a = amp * scene.h;
            let x: Vec<f64> = scene.x0.iter().map(|v| v + rng.gen_range(-a..a)).collect();
            points.push((tag, x));
        }
        for (tag, x) in &points {
            for (k, t) in scene.energy.terms.iter().enumerate() {
                let bits = term_bits(t.as_ref(), x);
                lines.push(format!(
                    "{label} {tag} term{k} {} words={} fnv={:016x} value={:e}",
                    t.name(),
                    bits.len(),
                    fnv(&bits),
                    f64::from_bits(bits[0])
                ));
            }
        }
    }
    lines
}

#[test]
fn energy_golden_bits() {
    let Ok(file) = std::env::var("ENERGY_GOLDEN") else {
        return;
    };
    let now = lines();
    if std::env::var("ENERGY_GOLDEN_WRITE").is_ok_and(|v| v == "1") {
        std::fs::write(&file, now.join("\n") + "\n").unwrap();
        eprintln!("wrote {} lines to {file}", now.len());
        return;
    }
    let golden = std::fs::read_to_string(&file).unwrap();
    let golden: Vec<&str> = golden.lines().collect();
    let mut bad = 0;
    for (g, n) in golden.iter().zip(&now) {
        if g != n {
            eprintln!("golden: {g}\nnow:    {n}");
            bad += 1;
        }
    }
    assert_eq!(golden.len(), now.len(), "number of lines");
    assert_eq!(bad, 0, "{bad} lines differ");
    eprintln!("all {} lines bit-identical to {file}", now.len());
}
