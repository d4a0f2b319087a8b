//! The scene registry: every built-in scene by name, built from `n` (its mesh level), ε and
//! numeric parameters (`--param NAME=VALUE`, sweep `params`), with its default level, the level
//! for a mesh size h, and its parameters as JSON. Static scenes ([`SCENES`]) and dynamic ones
//! ([`DYNAMIC_SCENES`]; a static scene also runs dynamically, wrapped).

use crate::scene::balloons::{self, BalloonsParams};
use crate::scene::balloons3d::{self, Balloons3dParams};
use crate::scene::dynamic::{self, CollideParams, Drop3dParams, DropParams, DynamicScene};
use crate::scene::ring::{self, RingParams};
use crate::scene::rod::{self, RodParams};
use crate::scene::sheets::{self, SheetsParams};
use crate::scene::solids::{self, SolidsParams};
use crate::scene::Scene;
use anyhow::{bail, Result};
use std::collections::BTreeMap;

/// Scenes `contactlab run` and sweeps know: 2D `balloons`, `ring`; 3D `sheets`, `rod`,
/// `solids`, `balloons3d`.
pub const SCENES: [&str; 6] = ["balloons", "ring", "sheets", "rod", "solids", "balloons3d"];

/// Sets the fields of a 3D scene's parameters from `NAME=VALUE` pairs: `fields` lists the
/// numeric fields by name, `flags` the boolean ones (value 0 or 1). Unknown names and
/// non-0/1 flags are errors naming them.
/// A named numeric field of a parameter struct.
type Field<P> = (&'static str, fn(&mut P) -> &mut f64);
/// A named boolean field of a parameter struct.
type Flag<P> = (&'static str, fn(&mut P) -> &mut bool);

fn set_fields<P>(
    scene: &str,
    p: &mut P,
    params: &BTreeMap<String, f64>,
    fields: &[Field<P>],
    flags: &[Flag<P>],
) -> Result<()> {
    for (k, &v) in params {
        if let Some((_, get)) = fields.iter().find(|(n, _)| n == k) {
            *get(p) = v;
        } else if let Some((_, get)) = flags.iter().find(|(n, _)| n == k) {
            *get(p) = match v {
                0.0 => false,
                1.0 => true,
                _ => bail!("scene {scene}: parameter {k:?} = {v} must be 0 or 1"),
            };
        } else {
            let known: Vec<&str> = fields
                .iter()
                .map(|(n, _)| *n)
                .chain(flags.iter().map(|(n, _)| *n))
                .collect();
            bail!(
                "scene {scene}: unknown parameter {k:?} (known: {})",
                known.join(", ")
            );
        }
    }
    Ok(())
}

fn sheets_params(
    n: usize,
    eps: Option<f64>,
    params: &BTreeMap<String, f64>,
) -> Result<SheetsParams> {
    let mut p = SheetsParams {
        n,
        eps,
        ..Default::default()
    };
    set_fields(
        "sheets",
        &mut p,
        params,
        &[
            ("mu", |p| &mut p.mu),
            ("lambda", |p| &mut p.lambda),
            ("weight", |p| &mut p.weight),
            ("gap", |p| &mut p.gap),
            ("half_size", |p| &mut p.half_size),
            ("angle_deg", |p| &mut p.angle_deg),
            ("stretch_lower", |p| &mut p.stretch_lower),
            ("stretch_upper", |p| &mut p.stretch_upper),
        ],
        &[("lower_fixed", |p| &mut p.lower_fixed)],
    )?;
    Ok(p)
}

fn rod_params(n: usize, eps: Option<f64>, params: &BTreeMap<String, f64>) -> Result<RodParams> {
    let mut p = RodParams {
        n,
        eps,
        ..Default::default()
    };
    set_fields(
        "rod",
        &mut p,
        params,
        &[
            ("mu", |p| &mut p.mu),
            ("weight", |p| &mut p.weight),
            ("height", |p| &mut p.height),
            ("stretch", |p| &mut p.stretch),
            ("slack", |p| &mut p.slack),
            ("swing_deg", |p| &mut p.swing_deg),
        ],
        &[],
    )?;
    Ok(p)
}

fn solids_params(
    n: usize,
    eps: Option<f64>,
    params: &BTreeMap<String, f64>,
) -> Result<SolidsParams> {
    let mut p = SolidsParams {
        n,
        eps,
        ..Default::default()
    };
    set_fields(
        "solids",
        &mut p,
        params,
        &[
            ("mu", |p| &mut p.mu),
            ("lambda", |p| &mut p.lambda),
            ("angle_deg", |p| &mut p.angle_deg),
            ("upper_size", |p| &mut p.upper_size),
            ("overlap", |p| &mut p.overlap),
            ("gap", |p| &mut p.gap),
            ("contrast", |p| &mut p.contrast),
        ],
        &[],
    )?;
    Ok(p)
}

fn balloons3d_params(
    n: usize,
    eps: Option<f64>,
    params: &BTreeMap<String, f64>,
) -> Result<Balloons3dParams> {
    let mut p = Balloons3dParams {
        n,
        eps,
        ..Default::default()
    };
    set_fields(
        "balloons3d",
        &mut p,
        params,
        &[
            ("mu", |p| &mut p.mu),
            ("lambda", |p| &mut p.lambda),
            ("c", |p| &mut p.c),
            ("radius", |p| &mut p.radius),
            ("pad_gap", |p| &mut p.pad_gap),
            ("twist_deg", |p| &mut p.twist_deg),
        ],
        &[],
    )?;
    Ok(p)
}

/// Builds scene `name` at mesh level `n` with ε (`None`: the scene's default, h/10) and numeric
/// parameters. Unknown scene or parameter names are errors naming them.
pub fn build_scene(
    name: &str,
    n: usize,
    eps: Option<f64>,
    params: &BTreeMap<String, f64>,
) -> Result<Scene> {
    match name {
        "balloons" => {
            let mut p = BalloonsParams {
                n,
                eps,
                ..Default::default()
            };
            for (k, &v) in params {
                match k.as_str() {
                    "c" => p.c = v,
                    "mu" => p.mu = v,
                    "perturb0" => p.perturb[0] = v,
                    "perturb1" => p.perturb[1] = v,
                    "perturb2" => p.perturb[2] = v,
                    "perturb3" => p.perturb[3] = v,
                    other => bail!(
                        "scene balloons: unknown parameter {other:?} (known: c, mu, perturb0..perturb3)"
                    ),
                }
            }
            Ok(balloons::build(&p)?)
        }
        "ring" => {
            let mut p = RingParams {
                n,
                eps,
                ..Default::default()
            };
            for (k, &v) in params {
                match k.as_str() {
                    "mu" => p.mu = v,
                    "p" => p.p = v,
                    "aspect" => p.aspect = v,
                    "half_span" => p.half_span = v,
                    other => bail!(
                        "scene ring: unknown parameter {other:?} (known: mu, p, aspect, half_span)"
                    ),
                }
            }
            Ok(ring::build(&p)?)
        }
        "sheets" => Ok(sheets::build(&sheets_params(n, eps, params)?)?),
        "rod" => Ok(rod::build(&rod_params(n, eps, params)?)?),
        "solids" => Ok(solids::build(&solids_params(n, eps, params)?)?),
        "balloons3d" => Ok(balloons3d::build(&balloons3d_params(n, eps, params)?)?),
        other => bail!("unknown scene {other:?} (available: {})", SCENES.join(", ")),
    }
}

/// The default mesh level of scene `name` for `contactlab run` (40 for the 2D scenes, the
/// scene's own default in 3D).
pub fn default_n(name: &str) -> usize {
    match name {
        "sheets" => SheetsParams::default().n,
        "rod" => RodParams::default().n,
        "solids" => SolidsParams::default().n,
        "balloons3d" => Balloons3dParams::default().n,
        _ => 40,
    }
}

/// The full parameter set of a 3D scene built by [`build_scene`] (for summary.json), or
/// `None` for the 2D scenes (whose runs record their own).
pub fn params_json(
    name: &str,
    n: usize,
    eps: Option<f64>,
    params: &BTreeMap<String, f64>,
) -> Result<Option<serde_json::Value>> {
    Ok(Some(match name {
        "sheets" => serde_json::to_value(sheets_params(n, eps, params)?)?,
        "rod" => serde_json::to_value(rod_params(n, eps, params)?)?,
        "solids" => serde_json::to_value(solids_params(n, eps, params)?)?,
        "balloons3d" => serde_json::to_value(balloons3d_params(n, eps, params)?)?,
        _ => return Ok(None),
    }))
}

/// The smallest `n` in `1..=max_n` with `size(n) ≤ h` (the sizes decrease with n).
fn first_level(h: f64, max_n: usize, size: impl Fn(usize) -> f64) -> Result<usize> {
    (1..=max_n)
        .find(|&n| size(n) <= h)
        .ok_or_else(|| anyhow::anyhow!("h = {h} needs a level above the scene's n ≤ {max_n}"))
}

/// The coarsest mesh level `n` of scene `name` (with parameters `params`, which the 3D
/// scenes' mesh sizes depend on) whose mesh size is at most `h`: balloons `h = 1.6/n`, so
/// `n = ⌈1.6/h⌉`; ring `h = 2 sin(π/n)` with n even, so the smallest even
/// `n ≥ π / asin(h/2)` (at least 6); the 3D scenes: the smallest level whose `mesh_size` is
/// at most `h`.
pub fn n_for_h(name: &str, h: f64, params: &BTreeMap<String, f64>) -> Result<usize> {
    if !(h.is_finite() && h > 0.0) {
        bail!("h = {h}: a mesh size must be finite and > 0");
    }
    let n = match name {
        "balloons" => {
            let mut n = (1.6 / h).ceil().max(1.0) as usize;
            // guard the rounding of 1.6/h
            while n > 1 && 1.6 / ((n - 1) as f64) <= h {
                n -= 1;
            }
            n
        }
        "ring" => {
            if h >= 2.0 {
                6
            } else {
                let mut n = ((std::f64::consts::PI / (h / 2.0).asin()).ceil() as usize).max(6);
                n += n % 2;
                while n > 6 && ring::mesh_size(n - 2) <= h {
                    n -= 2;
                }
                while ring::mesh_size(n) > h {
                    n += 2;
                }
                n
            }
        }
        "sheets" => {
            let base = sheets_params(1, None, params)?;
            first_level(h, 1000, |n| {
                sheets::mesh_size(&SheetsParams { n, ..base.clone() })
            })?
        }
        "rod" => {
            let base = rod_params(1, None, params)?;
            first_level(h, 100_000, |n| {
                rod::mesh_size(&RodParams { n, ..base.clone() })
            })?
        }
        "solids" => {
            let base = solids_params(1, None, params)?;
            first_level(h, 200, |n| {
                solids::mesh_size(&SolidsParams { n, ..base.clone() })
            })?
        }
        "balloons3d" => {
            let base = balloons3d_params(1, None, params)?;
            first_level(h, 7, |n| {
                balloons3d::mesh_size(&Balloons3dParams { n, ..base.clone() })
            })?
        }
        other => bail!("unknown scene {other:?} (available: {})", SCENES.join(", ")),
    };
    if n > 10_000_000 {
        bail!("h = {h} needs n = {n} elements: too fine");
    }
    Ok(n)
}

/// Parses `NAME=VALUE` scene parameters (`--param`, repeatable); the error names the argument.
pub fn parse_params(args: &[String]) -> Result<BTreeMap<String, f64>> {
    let mut params = BTreeMap::new();
    for p in args {
        let Some((k, v)) = p.split_once('=') else {
            bail!("--param {p:?}: expected NAME=VALUE");
        };
        let Ok(v) = v.trim().parse::<f64>() else {
            bail!("--param {p:?}: value {v:?} is not a number");
        };
        params.insert(k.trim().to_string(), v);
    }
    Ok(params)
}

/// The dynamic scenes (§6; `contactlab run NAME --dynamic`): 2D `drop`, `collide`; 3D
/// `drop3d`. The static scenes of [`SCENES`] also run with `--dynamic`, with density 1 per
/// body, zero initial velocity and no default Δt or number of steps.
pub const DYNAMIC_SCENES: [&str; 3] = ["drop", "collide", "drop3d"];

/// A dynamic scene by name: the dynamic scenes with their parameters (`--param`), or a static
/// scene of [`SCENES`] wrapped with density 1 per body and zero velocity (its Δt and steps
/// then have no default: 0 and 0, which [`DynamicSettings::validate`] refuses).
pub fn build_dynamic_scene(
    name: &str,
    n: Option<usize>,
    eps: Option<f64>,
    params: &BTreeMap<String, f64>,
) -> Result<DynamicScene> {
    Ok(build_dynamic_scene_json(name, n, eps, params)?.0)
}

/// [`build_dynamic_scene`], and the scene's full parameter set as JSON (summary.json): the
/// dynamic scenes' parameter structs, or `{n, eps, params}` for a wrapped static scene.
pub fn build_dynamic_scene_json(
    name: &str,
    n: Option<usize>,
    eps: Option<f64>,
    params: &BTreeMap<String, f64>,
) -> Result<(DynamicScene, serde_json::Value)> {
    match name {
        "drop" => {
            let mut p = DropParams {
                eps,
                ..Default::default()
            };
            if let Some(n) = n {
                p.ring.n = n;
            }
            let mut layers = p.ring.layers as f64;
            let mut floor_edges = p.floor_edges as f64;
            set_fields(
                "drop",
                &mut (&mut p, &mut layers, &mut floor_edges),
                params,
                &[
                    ("mu", |p| &mut p.0.ring.mu),
                    ("lambda", |p| &mut p.0.ring.lambda),
                    ("radius", |p| &mut p.0.ring.radius),
                    ("inner", |p| &mut p.0.ring.inner),
                    ("layers", |p| &mut *p.1),
                    ("density", |p| &mut p.0.density),
                    ("g", |p| &mut p.0.g),
                    ("height", |p| &mut p.0.height),
                    ("floor_half_width", |p| &mut p.0.floor_half_width),
                    ("floor_edges", |p| &mut *p.2),
                ],
                &[],
            )?;
            p.ring.layers = count("drop", "layers", layers)?;
            p.floor_edges = count("drop", "floor_edges", floor_edges)?;
            Ok((dynamic::drop(&p)?, serde_json::to_value(&p)?))
        }
        "collide" => {
            let mut p = CollideParams {
                eps,
                ..Default::default()
            };
            if let Some(n) = n {
                p.ring.n = n;
            }
            let mut layers = p.ring.layers as f64;
            set_fields(
                "collide",
                &mut (&mut p, &mut layers),
                params,
                &[
                    ("mu", |p| &mut p.0.ring.mu),
                    ("lambda", |p| &mut p.0.ring.lambda),
                    ("radius", |p| &mut p.0.ring.radius),
                    ("inner", |p| &mut p.0.ring.inner),
                    ("layers", |p| &mut *p.1),
                    ("density", |p| &mut p.0.density),
                    ("density_ratio", |p| &mut p.0.density_ratio),
                    ("gap", |p| &mut p.0.gap),
                    ("speed", |p| &mut p.0.speed),
                    ("offset_cells", |p| &mut p.0.offset_cells),
                ],
                &[],
            )?;
            p.ring.layers = count("collide", "layers", layers)?;
            Ok((dynamic::collide(&p)?, serde_json::to_value(&p)?))
        }
        "drop3d" => {
            let mut p = Drop3dParams {
                eps,
                ..Default::default()
            };
            if let Some(n) = n {
                p.n = n;
            }
            set_fields(
                "drop3d",
                &mut p,
                params,
                &[
                    ("half_size", |p| &mut p.half_size),
                    ("angle_deg", |p| &mut p.angle_deg),
                    ("tilt_deg", |p| &mut p.tilt_deg),
                    ("height", |p| &mut p.height),
                    ("obstacle_half_size", |p| &mut p.obstacle_half_size),
                    ("mu", |p| &mut p.mu),
                    ("lambda", |p| &mut p.lambda),
                    ("density", |p| &mut p.density),
                    ("g", |p| &mut p.g),
                ],
                &[],
            )?;
            Ok((dynamic::drop3d(&p)?, serde_json::to_value(&p)?))
        }
        other if SCENES.contains(&other) => {
            let n = n.unwrap_or_else(|| default_n(other));
            let scene = build_scene(other, n, eps, params)?;
            let density = vec![1.0; scene.mesh.bodies.len()];
            let v0 = vec![0.0; scene.x0.len()];
            let json = match params_json(other, n, eps, params)? {
                Some(j) => j,
                None => serde_json::json!({ "n": n, "eps": eps, "params": params }),
            };
            Ok((
                DynamicScene {
                    scene,
                    density,
                    v0,
                    dt: 0.0,
                    steps: 0,
                },
                json,
            ))
        }
        other => bail!(
            "unknown scene {other:?} (dynamic: {}; static, with --dynamic: {})",
            DYNAMIC_SCENES.join(", "),
            SCENES.join(", ")
        ),
    }
}

/// A non-negative integer parameter given as a number.
fn count(scene: &str, name: &str, v: f64) -> Result<usize> {
    if v >= 0.0 && v.fract() == 0.0 && v <= 1e9 {
        Ok(v as usize)
    } else {
        bail!("scene {scene}: parameter {name:?} = {v} must be a non-negative integer")
    }
}

/// The smallest mesh level of dynamic scene `name` whose h is at most `h` (drop, collide: the
/// ring's cells around; drop3d: its level; the static scenes: [`n_for_h`]).
pub fn dynamic_n_for_h(name: &str, h: f64, params: &BTreeMap<String, f64>) -> Result<usize> {
    if !DYNAMIC_SCENES.contains(&name) {
        return n_for_h(name, h, params);
    }
    if !(h.is_finite() && h > 0.0) {
        bail!("h = {h}: a mesh size must be finite and > 0");
    }
    let size =
        |n: usize| -> Result<f64> { Ok(build_dynamic_scene(name, Some(n), None, params)?.scene.h) };
    let start = if name == "drop3d" { 1 } else { 8 };
    for n in start..=400 {
        if size(n)? <= h {
            return Ok(n);
        }
    }
    bail!("h = {h} needs a level above the scene's n ≤ 400")
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn every_scene_builds_by_name_at_its_default_level() {
        for name in SCENES {
            let s = build_scene(name, default_n(name), None, &BTreeMap::new()).unwrap();
            assert_eq!(s.name, name);
            let dim = if ["balloons", "ring"].contains(&name) {
                2
            } else {
                3
            };
            assert_eq!(s.mesh.dim, dim, "{name}");
        }
    }

    #[test]
    fn n_for_h_of_the_3d_scenes_is_the_coarsest_level_fine_enough() {
        let none = BTreeMap::new();
        for name in ["sheets", "rod", "solids", "balloons3d"] {
            for n in 1..=3 {
                let h = build_scene(name, n, None, &none).unwrap().h;
                assert_eq!(n_for_h(name, h, &none).unwrap(), n, "{name} n={n} h={h}");
                // just above h: the same level; just below: a finer one
                assert_eq!(n_for_h(name, h * (1.0 + 1e-9), &none).unwrap(), n);
                assert!(n_for_h(name, h * (1.0 - 1e-9), &none).unwrap() > n);
            }
        }
        // the parameters change h: a sheets stretch makes the elements smaller
        let p: BTreeMap<String, f64> = [("stretch_lower".to_string(), 1.5)].into();
        let h = build_scene("sheets", 2, None, &p).unwrap().h;
        assert!(h < build_scene("sheets", 2, None, &none).unwrap().h);
        assert_eq!(n_for_h("sheets", h, &p).unwrap(), 2);
        assert!(n_for_h("sheets", h, &none).unwrap() > 2);
        let e = n_for_h("balloons3d", 1e-4, &none).unwrap_err().to_string();
        assert!(e.contains("n ≤ 7"), "{e}");
    }

    #[test]
    fn unknown_3d_parameters_and_bad_flags_are_named() {
        let p: BTreeMap<String, f64> = [("weigth".to_string(), 1.0)].into();
        let e = build_scene("sheets", 1, None, &p)
            .err()
            .unwrap()
            .to_string();
        assert!(e.contains("\"weigth\"") && e.contains("weight"), "{e}");
        let p: BTreeMap<String, f64> = [("lower_fixed".to_string(), 0.5)].into();
        let e = build_scene("sheets", 1, None, &p)
            .err()
            .unwrap()
            .to_string();
        assert!(e.contains("lower_fixed") && e.contains("0 or 1"), "{e}");
        let p: BTreeMap<String, f64> = [("lower_fixed".to_string(), 1.0)].into();
        let s = build_scene("sheets", 1, None, &p).unwrap();
        assert!(s.mesh.bodies[0].vertices.iter().all(|&v| s.mesh.fixed[v]));
        let e = n_for_h("rod", 0.1, &[("x".to_string(), 1.0)].into())
            .unwrap_err()
            .to_string();
        assert!(e.contains("\"x\""), "{e}");
    }
}
