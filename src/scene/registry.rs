//! The scene registry: every built-in scene is one value of a type implementing
//! [`BuiltinScene`], and [`SCENES`] lists them all, static and dynamic alike. A scene is built
//! from `n` (its mesh level), ε and numeric parameters (`--param NAME=VALUE`, sweep `params`);
//! it knows its default level, the level for a mesh size h, its parameters as JSON
//! (summary.json), possibly a classification of an end state, and how it runs dynamically
//! (§6 of the paper; docs/scenes.md): a dynamic scene (`drop`, `collide`, `drop3d`) builds its
//! own densities, velocities, Δt and steps, a static scene runs wrapped with density 1 per
//! body, zero velocity and no default Δt or steps.
//!
//! The free functions ([`build_scene`], [`build_dynamic_scene`], [`default_n`], [`n_for_h`],
//! [`params_json`], …) are lookups by name over [`SCENES`]. Where to add a scene: see the
//! module documentation of [`crate::scene`].

use crate::scene::dynamic::DynamicScene;
use crate::scene::mesh::Mesh;
use crate::scene::Scene;
use anyhow::{bail, Result};
use std::collections::BTreeMap;

/// Numeric scene parameters by name (`--param NAME=VALUE`, a sweep block's `params`).
pub type Params = BTreeMap<String, f64>;

/// One built-in scene: its name, parameters, build, mesh levels, and optional dynamics.
pub trait BuiltinScene: Sync {
    /// The scene's name (`contactlab run NAME`, sweep `scene = "NAME"`).
    fn name(&self) -> &'static str;

    /// True for a scene that only runs dynamically (`--dynamic`); a static run of it is
    /// refused. Default: false (a static scene, which also runs dynamically, wrapped).
    fn dynamic_only(&self) -> bool {
        false
    }

    /// The default mesh level for `contactlab run` (default: 40).
    fn default_n(&self) -> usize {
        40
    }

    /// Builds the static scene at level `n` with ε (`None`: the scene's default) and numeric
    /// parameters; unknown parameter names are errors naming them.
    fn build(&self, n: usize, eps: Option<f64>, params: &Params) -> Result<Scene>;

    /// The full parameter set the scene is built with, for summary.json; `None` where the
    /// run records its own (the 2D static scenes).
    fn params_json(
        &self,
        _n: usize,
        _eps: Option<f64>,
        _params: &Params,
    ) -> Result<Option<serde_json::Value>> {
        Ok(None)
    }

    /// The coarsest level whose mesh size is at most `h` (`h` is finite and > 0).
    fn n_for_h(&self, h: f64, params: &Params) -> Result<usize>;

    /// The state an end configuration `x` reached, where the scene names its states (the
    /// balloons' pattern, the ring's self-contact); `pattern` lists the touching body pairs.
    /// `None`: the generic contact state of the harness.
    fn classify_state(
        &self,
        _mesh: &Mesh,
        _x: &[f64],
        _eps: f64,
        _pattern: &[(usize, usize)],
    ) -> Option<String> {
        None
    }

    /// The scene for a dynamic run at level `n` (`None`: the default level) and its full
    /// parameter set as JSON. Default: the static scene wrapped with density 1 per body and
    /// zero velocity (Δt and steps 0, which a dynamic run refuses, so the run must give
    /// them), its JSON the scene's parameters or
    /// `{n, eps, params}`.
    fn dynamic(
        &self,
        n: Option<usize>,
        eps: Option<f64>,
        params: &Params,
    ) -> Result<(DynamicScene, serde_json::Value)> {
        let n = n.unwrap_or_else(|| self.default_n());
        let scene = self.build(n, eps, params)?;
        let density = vec![1.0; scene.mesh.bodies.len()];
        let v0 = vec![0.0; scene.x0.len()];
        let json = match self.params_json(n, eps, params)? {
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
}

/// A built-in scene given by a parameter struct with a mesh level `n` (the 3D scenes): its
/// parameters are the struct's fields set by name, its level for a mesh size h the coarsest
/// level up to [`LevelScene::MAX_LEVEL`] whose mesh size is at most h. Every such type is a
/// [`BuiltinScene`] through the implementation below.
pub trait LevelScene: Sync {
    /// The parameter struct.
    type P: Clone + Default + serde::Serialize;
    /// The scene's name.
    const NAME: &'static str;
    /// The finest level [`BuiltinScene::n_for_h`] tries.
    const MAX_LEVEL: usize;
    /// The parameters at level `n` with ε (`None`: the scene's default) and `NAME=VALUE`
    /// pairs, unknown names an error naming them.
    fn params(n: usize, eps: Option<f64>, params: &Params) -> Result<Self::P>;
    /// The level of `p`.
    fn level(p: &Self::P) -> usize;
    /// `p` at level `n`.
    fn at_level(p: &Self::P, n: usize) -> Self::P;
    /// The scene of `p`.
    fn build_scene(p: &Self::P) -> Result<Scene>;
    /// The mesh size h of `p`.
    fn mesh_size(p: &Self::P) -> f64;
}

impl<T: LevelScene> BuiltinScene for T {
    fn name(&self) -> &'static str {
        T::NAME
    }

    fn default_n(&self) -> usize {
        T::level(&T::P::default())
    }

    fn build(&self, n: usize, eps: Option<f64>, params: &Params) -> Result<Scene> {
        T::build_scene(&T::params(n, eps, params)?)
    }

    fn params_json(
        &self,
        n: usize,
        eps: Option<f64>,
        params: &Params,
    ) -> Result<Option<serde_json::Value>> {
        Ok(Some(serde_json::to_value(T::params(n, eps, params)?)?))
    }

    fn n_for_h(&self, h: f64, params: &Params) -> Result<usize> {
        let base = T::params(1, None, params)?;
        first_level(h, T::MAX_LEVEL, |n| T::mesh_size(&T::at_level(&base, n)))
    }
}

/// Every built-in scene: 2D `balloons`, `ring`; 3D `sheets`, `rod`, `solids`, `balloons3d`;
/// dynamic only: 2D `drop`, `collide`, 3D `drop3d`. The order is the order of the error
/// messages' lists.
pub static SCENES: &[&dyn BuiltinScene] = &[
    &crate::scene::balloons::Balloons,
    &crate::scene::ring::Ring,
    &crate::scene::sheets::Sheets,
    &crate::scene::rod::Rod,
    &crate::scene::solids::Solids,
    &crate::scene::balloons3d::Balloons3d,
    &crate::scene::dynamic::Drop,
    &crate::scene::dynamic::Collide,
    &crate::scene::dynamic::Drop3d,
];

/// The scene named `name`, static or dynamic.
pub fn scene(name: &str) -> Option<&'static dyn BuiltinScene> {
    SCENES.iter().copied().find(|s| s.name() == name)
}

/// The static scenes (those a static run accepts).
fn static_scene(name: &str) -> Option<&'static dyn BuiltinScene> {
    scene(name).filter(|s| !s.dynamic_only())
}

/// The names of the static scenes (`balloons, ring, …`), or of the dynamic-only ones.
pub fn names(dynamic_only: bool) -> Vec<&'static str> {
    SCENES
        .iter()
        .filter(|s| s.dynamic_only() == dynamic_only)
        .map(|s| s.name())
        .collect()
}

/// True when `name` is a dynamic-only scene (`drop`, `collide`, `drop3d`).
pub fn is_dynamic_only(name: &str) -> bool {
    scene(name).is_some_and(|s| s.dynamic_only())
}

fn unknown_static(name: &str) -> anyhow::Error {
    anyhow::anyhow!(
        "unknown scene {name:?} (available: {})",
        names(false).join(", ")
    )
}

/// A named numeric field of a parameter struct.
pub type Field<P> = (&'static str, fn(&mut P) -> &mut f64);
/// A named boolean field of a parameter struct.
pub type Flag<P> = (&'static str, fn(&mut P) -> &mut bool);

/// Sets the fields of a scene's parameters from `NAME=VALUE` pairs: `fields` lists the
/// numeric fields by name, `flags` the boolean ones (value 0 or 1). Unknown names and
/// non-0/1 flags are errors naming them.
pub fn set_fields<P>(
    scene: &str,
    p: &mut P,
    params: &Params,
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

/// A non-negative integer parameter given as a number.
pub fn count(scene: &str, name: &str, v: f64) -> Result<usize> {
    if v >= 0.0 && v.fract() == 0.0 && v <= 1e9 {
        Ok(v as usize)
    } else {
        bail!("scene {scene}: parameter {name:?} = {v} must be a non-negative integer")
    }
}

/// The smallest `n` in `1..=max_n` with `size(n) ≤ h` (the sizes decrease with n).
pub fn first_level(h: f64, max_n: usize, size: impl Fn(usize) -> f64) -> Result<usize> {
    (1..=max_n)
        .find(|&n| size(n) <= h)
        .ok_or_else(|| anyhow::anyhow!("h = {h} needs a level above the scene's n ≤ {max_n}"))
}

/// Builds static scene `name` at mesh level `n` with ε (`None`: the scene's default, h/10)
/// and numeric parameters. Unknown scene or parameter names are errors naming them.
pub fn build_scene(name: &str, n: usize, eps: Option<f64>, params: &Params) -> Result<Scene> {
    static_scene(name)
        .ok_or_else(|| unknown_static(name))?
        .build(n, eps, params)
}

/// The default mesh level of scene `name` for `contactlab run` (40 for the 2D scenes, the
/// scene's own default in 3D).
pub fn default_n(name: &str) -> usize {
    scene(name).map_or(40, |s| s.default_n())
}

/// The full parameter set of a static scene built by [`build_scene`] (for summary.json), or
/// `None` for the 2D scenes (whose runs record their own) and unknown names.
pub fn params_json(
    name: &str,
    n: usize,
    eps: Option<f64>,
    params: &Params,
) -> Result<Option<serde_json::Value>> {
    match static_scene(name) {
        Some(s) => s.params_json(n, eps, params),
        None => Ok(None),
    }
}

/// The coarsest mesh level `n` of static scene `name` (with parameters `params`, which the
/// 3D scenes' mesh sizes depend on) whose mesh size is at most `h` (each scene's
/// [`BuiltinScene::n_for_h`]).
pub fn n_for_h(name: &str, h: f64, params: &Params) -> Result<usize> {
    if !(h.is_finite() && h > 0.0) {
        bail!("h = {h}: a mesh size must be finite and > 0");
    }
    let n = static_scene(name)
        .ok_or_else(|| unknown_static(name))?
        .n_for_h(h, params)?;
    if n > 10_000_000 {
        bail!("h = {h} needs n = {n} elements: too fine");
    }
    Ok(n)
}

/// The state an end configuration reached, where scene `name` names its states (see
/// [`BuiltinScene::classify_state`]); a scene file named like a built-in scene is classified
/// as that scene.
pub fn classify_state(
    name: &str,
    mesh: &Mesh,
    x: &[f64],
    eps: f64,
    pattern: &[(usize, usize)],
) -> Option<String> {
    static_scene(name)?.classify_state(mesh, x, eps, pattern)
}

/// Parses `NAME=VALUE` scene parameters (`--param`, repeatable); the error names the argument.
pub fn parse_params(args: &[String]) -> Result<Params> {
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

/// A dynamic scene by name: the dynamic scenes with their parameters (`--param`), or a static
/// scene wrapped with density 1 per body and zero velocity (its Δt and steps then have no
/// default: 0 and 0, which the dynamic settings refuse).
pub fn build_dynamic_scene(
    name: &str,
    n: Option<usize>,
    eps: Option<f64>,
    params: &Params,
) -> Result<DynamicScene> {
    Ok(build_dynamic_scene_json(name, n, eps, params)?.0)
}

/// [`build_dynamic_scene`], and the scene's full parameter set as JSON (summary.json): the
/// dynamic scenes' parameter structs, or the static scene's ([`BuiltinScene::dynamic`]).
pub fn build_dynamic_scene_json(
    name: &str,
    n: Option<usize>,
    eps: Option<f64>,
    params: &Params,
) -> Result<(DynamicScene, serde_json::Value)> {
    match scene(name) {
        Some(s) => s.dynamic(n, eps, params),
        None => bail!(
            "unknown scene {name:?} (dynamic: {}; static, with --dynamic: {})",
            names(true).join(", "),
            names(false).join(", ")
        ),
    }
}

/// The smallest mesh level of scene `name` for a dynamic run whose h is at most `h` (the
/// dynamic-only scenes: their [`BuiltinScene::n_for_h`]; the static scenes: [`n_for_h`]).
pub fn dynamic_n_for_h(name: &str, h: f64, params: &Params) -> Result<usize> {
    let Some(s) = scene(name).filter(|s| s.dynamic_only()) else {
        return n_for_h(name, h, params);
    };
    if !(h.is_finite() && h > 0.0) {
        bail!("h = {h}: a mesh size must be finite and > 0");
    }
    s.n_for_h(h, params)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn every_scene_builds_by_name_at_its_default_level() {
        for name in names(false) {
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
    fn the_registry_lists_todays_scenes_in_order() {
        assert_eq!(
            names(false),
            ["balloons", "ring", "sheets", "rod", "solids", "balloons3d"]
        );
        assert_eq!(names(true), ["drop", "collide", "drop3d"]);
        let e = build_scene("drop", 10, None, &BTreeMap::new())
            .err()
            .unwrap()
            .to_string();
        assert_eq!(
            e,
            "unknown scene \"drop\" (available: balloons, ring, sheets, rod, solids, balloons3d)"
        );
        let e = build_dynamic_scene("nope", None, None, &BTreeMap::new())
            .err()
            .unwrap()
            .to_string();
        assert_eq!(
            e,
            "unknown scene \"nope\" (dynamic: drop, collide, drop3d; static, with --dynamic: balloons, ring, sheets, rod, solids, balloons3d)"
        );
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
