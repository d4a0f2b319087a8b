//! Assembly of a scene file: the loaded bodies become one [`Mesh`] (vertices numbered body by
//! body, welded vertices merged; each body's contact edges and faces) through the mesh
//! assembler of every scene ([`crate::scene::assemble`]) and one energy
//! `J = Σ_bodies (material + gas + pressure) + gravity` (docs/method.md, docs/scene-files.md)
//! through its energy assembler ([`crate::scene::physics`]), each key checked, with its line,
//! just before the step that uses it; then the assembled scene is checked: the contact filter,
//! boundedness under gravity and under dead loads, ε against the rest shapes, the
//! admissibility of the start (displaced by the supports), and the initial velocities. The
//! supports and dead loads are read in `loads`, the solids' materials in `solid`.

use super::contact::describe;
use super::schema::{
    BodySpec, ContactSpec, DynamicsSpec, GasSpec, MaterialSpec, SolverSpec, WeldSpec,
};
use super::{fmt_list, Ctx, Loaded, SceneFile, SceneFileError};
use crate::contact::min_distance;
use crate::energy::DeadLoad;
use crate::energy::TotalEnergy;
use crate::scene::assemble::{assemble_mesh, file_order, BodyPart};
use crate::scene::mesh::{Body, BodyKind, ContactFilter, Mesh};
use crate::scene::physics::{EnergyAssembler, Material};
use crate::scene::Scene;
use std::path::Path;
use toml::Spanned;

/// The scene-level keys assembly needs besides the bodies (checked in `validate`).
pub(super) struct Header {
    /// The scene's name.
    pub(super) name: String,
    /// 2 or 3.
    pub(super) dim: usize,
    /// ε.
    pub(super) eps: f64,
    /// The line of `eps`.
    pub(super) eps_line: usize,
    /// A non-zero `gravity` and its line.
    pub(super) gravity: Option<(Vec<f64>, usize)>,
    /// `[contact]`.
    pub(super) contact: Option<Spanned<ContactSpec>>,
    /// `weld`.
    pub(super) welds: Vec<Spanned<WeldSpec>>,
    /// `[solver]`.
    pub(super) solver: SolverSpec,
    /// `[dynamics]`.
    pub(super) dynamics: DynamicsSpec,
}

impl Ctx<'_> {
    /// The scene of the loaded bodies (`specs` their `[[body]]` tables, in file order).
    pub(super) fn assemble(
        &self,
        header: Header,
        loaded: Vec<Loaded>,
        specs: Vec<BodySpec>,
        path: &Path,
    ) -> Result<SceneFile, SceneFileError> {
        let Header {
            name,
            dim,
            eps,
            eps_line,
            gravity,
            contact,
            welds,
            solver,
            dynamics,
        } = header;
        let nb = loaded.len();
        let (global, welded) = self.resolve_welds(&welds, &loaded)?;
        let (x_ref, fixed, mut x0) = place_vertices(dim, &loaded, &global);
        let parts = body_parts(&loaded, &global);
        let mut mesh = assemble_mesh(dim, x_ref, fixed, &parts, &file_order(nb));
        let body_elements: Vec<Vec<[usize; 4]>> = parts.into_iter().map(|p| p.elements).collect();
        let displaced = self.apply_supports(&mut mesh, &mut x0, &loaded, &specs, &global)?;
        let (h, body_all_fixed) = mesh_size(&mesh);
        let dead_load = self.dead_loads(&mesh, &loaded, &specs, &global, &body_elements)?;
        let energy = self.energy_terms(
            &mesh,
            &x0,
            &loaded,
            &specs,
            &body_all_fixed,
            gravity.as_ref(),
            dead_load.as_ref(),
        )?;

        // contact filter
        let names: Vec<String> = loaded.iter().map(|l| l.name.clone()).collect();
        let allowed = self.contact_mask(contact, &names)?;
        if allowed.iter().any(|&a| !a) {
            mesh.contact_filter = Some(ContactFilter::new(&mesh, |i, j| allowed[i * nb + j]));
        }
        if let Err(e) = mesh.validate() {
            // the per-body checks above catch every case first; kept as a safety net
            return Err(self.invalid(1, "body", "(assembled mesh)", e.to_string()));
        }
        if let Some(g) = &gravity {
            self.check_bounded(&mesh, g, &specs, &allowed, &welded, &names)?;
        }
        if let Some(load) = &dead_load {
            self.check_dead_loads_bounded(
                &mesh, &loaded, &specs, &global, load, &allowed, &welded,
            )?;
        }
        self.check_rest_shapes(&mesh, eps, eps_line, &allowed, &names)?;
        if displaced {
            self.check_displaced_start(&mesh, &x0, eps, &loaded, &global, &names)?;
        }
        self.check_start(&mesh, &x0, eps, &energy, &names)?;
        let v0 = self.initial_velocities(&mesh, &loaded, &specs, &names)?;
        Ok(SceneFile {
            scene: Scene {
                name,
                mesh,
                energy,
                eps,
                h,
                x0,
            },
            solver,
            dynamics,
            path: path.to_path_buf(),
            body_names: names,
            densities: specs.iter().map(|s| s.density).collect(),
            v0,
            gravity: gravity.map(|(g, _)| g),
            dead_load,
            body_lines: loaded.iter().map(|l| l.line).collect(),
        })
    }

    /// The energy terms, body by body: material, then gas, then pressure; gravity, then the
    /// dead loads last (the order of [`crate::scene::physics::assemble_energy`]), each key
    /// checked before its step.
    #[allow(clippy::too_many_arguments)]
    fn energy_terms(
        &self,
        mesh: &Mesh,
        x0: &[f64],
        loaded: &[Loaded],
        specs: &[BodySpec],
        body_all_fixed: &[bool],
        gravity: Option<&(Vec<f64>, usize)>,
        dead_load: Option<&DeadLoad>,
    ) -> Result<TotalEnergy, SceneFileError> {
        let mut terms = EnergyAssembler::new(mesh, x0);
        for (bi, (l, s)) in loaded.iter().zip(specs).enumerate() {
            let all_fixed = body_all_fixed[bi];
            match &s.material {
                None if all_fixed => {}
                None => {
                    return Err(self.invalid(l.line, format!("{}.material", l.key), "(missing)", "a body with a free vertex needs a material (only a body with `fixed.all = true` may have none)"));
                }
                Some(m) => {
                    let material = self.material(mesh.dim, l, m)?;
                    terms.material(&[bi], material).map_err(|e| {
                        self.invalid(
                            l.line,
                            l.key.clone(),
                            format!("{:?}", l.name),
                            e.to_string(),
                        )
                    })?;
                }
            }
            if let Some(g) = &s.gas {
                self.gas_term(&mut terms, bi, mesh.dim, l, g)?;
            }
            if let Some(p) = &s.pressure {
                let pk = format!("{}.pressure.p", l.key);
                if !p.p.is_finite() {
                    return Err(self.invalid(l.line, pk, p.p, "must be finite"));
                }
                terms
                    .pressure(bi, p.p)
                    .map_err(|e| self.invalid(l.line, pk, p.p, e.to_string()))?;
            }
            self.body_load(&mut terms, bi, l, s, all_fixed, gravity)?;
        }
        if let Some(load) = dead_load {
            terms.dead_load(load.clone());
        }
        Ok(terms.finish(gravity.map(|(g, _)| g.as_slice())))
    }

    /// A body's `material`, checked: the model its kind takes (string for curves,
    /// St Venant–Kirchhoff membrane for 3D surfaces; solids in [`Ctx::solid_material`]:
    /// neo-Hookean or linear elastic) and its coefficients.
    fn material(
        &self,
        dim: usize,
        l: &Loaded,
        m: &MaterialSpec,
    ) -> Result<Material, SceneFileError> {
        if l.kind == BodyKind::Solid {
            return self.solid_material(dim, l, m);
        }
        let line = l.line;
        let mk = format!("{}.material", l.key);
        if let Some((k, v)) = [("E", m.young), ("nu", m.nu)]
            .into_iter()
            .find_map(|(k, v)| v.map(|v| (k, v.to_string())))
            .or(m.plane.as_ref().map(|p| ("plane", format!("{p:?}"))))
        {
            return Err(self.invalid(
                line,
                format!("{mk}.{k}"),
                v,
                "E, nu and plane are keys of solids' materials",
            ));
        }
        let expect = Material::model_for(l.kind);
        if m.model != expect {
            return Err(self.invalid(line, format!("{mk}.model"), format!("{:?}", m.model), format!("a {:?} body takes model = {expect:?} (models: string for curves, stvk-membrane for 3D surfaces, neo-hookean or linear-elastic for solids)", l.kind).to_lowercase()));
        }
        let (mu, lambda) = if expect == "string" {
            if let Some(v) = m.lambda {
                return Err(self.invalid(
                    line,
                    format!("{mk}.lambda"),
                    v,
                    "the string model has no lambda",
                ));
            }
            let mu = m
                .mu
                .ok_or_else(|| self.invalid(line, format!("{mk}.mu"), "(missing)", "required"))?;
            if !(mu > 0.0 && mu.is_finite()) {
                return Err(self.invalid(line, format!("{mk}.mu"), mu, "must be finite and > 0"));
            }
            (mu, 0.0)
        } else {
            let c = self.elastic_constants(line, &mk, m)?;
            (c.mu, c.lambda)
        };
        Ok(Material::of_kind(l.kind, mu, lambda))
    }

    /// A body's `gas`: `−C ln V`, V the area of a 2D curve (closed, or closed by its chord)
    /// or the volume of a closed 3D surface, positive at the start.
    fn gas_term(
        &self,
        terms: &mut EnergyAssembler,
        bi: usize,
        dim: usize,
        l: &Loaded,
        g: &GasSpec,
    ) -> Result<(), SceneFileError> {
        let line = l.line;
        let gk = format!("{}.gas.c", l.key);
        if !(g.c > 0.0 && g.c.is_finite()) {
            return Err(self.invalid(line, gk, g.c, "must be finite and > 0"));
        }
        let v0 = terms
            .gas(bi, g.c)
            .map_err(|e| self.invalid(line, &gk, g.c, e.to_string()))?;
        if v0.is_nan() || v0 <= 0.0 {
            let what = if dim == 2 {
                "the curve encloses zero area in the initial configuration"
            } else {
                "the surface encloses zero volume in the initial configuration"
            };
            return Err(self.invalid(line, gk, g.c, what));
        }
        Ok(())
    }

    /// A body's `density`: its lumped masses added to gravity's load. A free body under a
    /// non-zero gravity needs one.
    fn body_load(
        &self,
        terms: &mut EnergyAssembler,
        bi: usize,
        l: &Loaded,
        s: &BodySpec,
        all_fixed: bool,
        gravity: Option<&(Vec<f64>, usize)>,
    ) -> Result<(), SceneFileError> {
        let key = &l.key;
        if let Some(rho) = s.density {
            if !(rho >= 0.0 && rho.is_finite()) {
                return Err(self.invalid(
                    l.line,
                    format!("{key}.density"),
                    rho,
                    "must be finite and ≥ 0",
                ));
            }
            terms.load(bi, rho);
        } else if let Some((g, gl)) = gravity.filter(|_| !all_fixed) {
            return Err(self.invalid(*gl, "gravity", fmt_list(g), format!("body {:?} ({key}) has a free vertex but no density: give {key}.density (0 for no load)", l.name)));
        }
        Ok(())
    }

    /// Unbounded: a free body with a gravity load must be able to touch an anchored body
    /// (directly, through other bodies, or through welds).
    fn check_bounded(
        &self,
        mesh: &Mesh,
        (g, gl): &(Vec<f64>, usize),
        specs: &[BodySpec],
        allowed: &[bool],
        welded: &[bool],
        names: &[String],
    ) -> Result<(), SceneFileError> {
        let nb = mesh.bodies.len();
        let has_load: Vec<bool> = specs
            .iter()
            .map(|s| s.density.unwrap_or(0.0) > 0.0)
            .collect();
        let supported = supported_closure(
            nb,
            mesh.bodies
                .iter()
                .map(|b| b.vertices.iter().any(|&v| mesh.fixed[v]))
                .collect(),
            allowed,
            welded,
        );
        for i in 0..nb {
            if !supported[i] && has_load[i] {
                return Err(self.invalid(
                    *gl,
                    "gravity",
                    fmt_list(g),
                    format!(
                        "the problem is unbounded: body {:?} has no fixed vertex, carries a \
                         gravity load, and may touch no body that holds a fixed vertex \
                         (directly or through other bodies; see [contact] and weld), so translating \
                         it along gravity lowers J without bound",
                        names[i]
                    ),
                ));
            }
        }
        Ok(())
    }

    /// ε against the rest shapes: each self-touching body's reference must be admissible.
    fn check_rest_shapes(
        &self,
        mesh: &Mesh,
        eps: f64,
        eps_line: usize,
        allowed: &[bool],
        names: &[String],
    ) -> Result<(), SceneFileError> {
        let nb = mesh.bodies.len();
        let self_mask: Vec<bool> = (0..nb).map(|i| allowed[i * nb + i]).collect();
        if self_mask.iter().any(|&a| a) {
            let mut rest = mesh.clone();
            rest.contact_filter = Some(ContactFilter::new(&rest, |i, j| i == j && self_mask[i]));
            let md = min_distance(&rest, &rest.x_ref, eps, false);
            if md.distance < eps {
                return Err(self.invalid(
                    eps_line,
                    "eps",
                    eps,
                    format!(
                        "larger than the scene can hold: in the reference (rest) configuration \
                         {} are at distance {:.6e} < eps, so that body's rest shape is not \
                         admissible (refine nothing: lower eps below {:.6e}, or exclude the \
                         body's self-contact in [contact])",
                        describe(mesh, names, &md.pair),
                        md.distance,
                        md.distance
                    ),
                ));
            }
        }
        Ok(())
    }

    /// The start: every allowed pair of disjoint elements at least ε apart, and J finite.
    fn check_start(
        &self,
        mesh: &Mesh,
        x0: &[f64],
        eps: f64,
        energy: &TotalEnergy,
        names: &[String],
    ) -> Result<(), SceneFileError> {
        let md0 = min_distance(mesh, x0, 2.0 * eps, false);
        if md0.distance < eps {
            return Err(SceneFileError::InadmissibleStart {
                path: self.path.clone(),
                pair: describe(mesh, names, &md0.pair),
                distance: md0.distance,
                eps,
            });
        }
        if !energy.value(x0).is_finite() {
            return Err(self.invalid(
                1,
                "body",
                "(initial configuration)",
                "the initial energy is not finite",
            ));
        }
        Ok(())
    }

    /// Initial velocities: uniform per body; a free vertex shared by bodies must get the
    /// same velocity from each (no `velocity`: zero).
    fn initial_velocities(
        &self,
        mesh: &Mesh,
        loaded: &[Loaded],
        specs: &[BodySpec],
        names: &[String],
    ) -> Result<Vec<f64>, SceneFileError> {
        let dim = mesh.dim;
        let mut v0 = vec![0.0; dim * mesh.nv()];
        let mut v_from: Vec<Option<usize>> = vec![None; mesh.nv()];
        for (bi, (l, s)) in loaded.iter().zip(specs).enumerate() {
            let vel = match &s.velocity {
                None => vec![0.0; dim],
                Some(v) => {
                    if v.len() != dim || v.iter().any(|c| !c.is_finite()) {
                        return Err(self.invalid(
                            l.line,
                            format!("{}.velocity", l.key),
                            fmt_list(v),
                            format!("must be {dim} finite numbers"),
                        ));
                    }
                    v.clone()
                }
            };
            for (k, &v) in mesh.bodies[bi].vertices.iter().enumerate() {
                if mesh.fixed[v] {
                    continue;
                }
                let cur = &mut v0[dim * v..dim * v + dim];
                if let Some(first) = v_from[v] {
                    if cur != vel.as_slice() {
                        return Err(self.invalid(
                            l.line,
                            format!("{}.velocity", l.key),
                            fmt_list(&vel),
                            format!(
                                "vertex {k} of body {:?} is welded to body {:?}, whose velocity is \
                                 {:?}: a free welded vertex needs the same velocity in every body \
                                 holding it",
                                l.name, names[first], cur
                            ),
                        ));
                    }
                } else {
                    cur.copy_from_slice(&vel);
                    v_from[v] = Some(bi);
                }
            }
        }
        Ok(v0)
    }
}

/// The bodies supported directly (`supported`) or through a body they may touch (`allowed`,
/// the `nb × nb` contact mask) or are welded to (`welded`), transitively.
pub(super) fn supported_closure(
    nb: usize,
    mut supported: Vec<bool>,
    allowed: &[bool],
    welded: &[bool],
) -> Vec<bool> {
    loop {
        let mut changed = false;
        for i in 0..nb {
            if !supported[i]
                && (0..nb)
                    .any(|j| j != i && supported[j] && (allowed[i * nb + j] || welded[i * nb + j]))
            {
                supported[i] = true;
                changed = true;
            }
        }
        if !changed {
            return supported;
        }
    }
}

/// The vertices in mesh numbering (`global[b][k]`: vertex `k` of body `b`): reference
/// positions, fixed flags (fixed in any body that holds it), start positions. A welded vertex
/// takes the positions of the first body that holds it.
fn place_vertices(
    dim: usize,
    loaded: &[Loaded],
    global: &[Vec<usize>],
) -> (Vec<f64>, Vec<bool>, Vec<f64>) {
    let nv = global.iter().flatten().copied().max().map_or(0, |m| m + 1);
    let mut x0 = vec![0.0; dim * nv];
    let mut x_ref = vec![0.0; dim * nv];
    let mut fixed = vec![false; nv];
    let mut seen = vec![false; nv];
    for (l, map) in loaded.iter().zip(global) {
        for (k, &v) in map.iter().enumerate() {
            if !seen[v] {
                seen[v] = true;
                x_ref[dim * v..dim * v + dim].copy_from_slice(&l.x_ref[k][..dim]);
                x0[dim * v..dim * v + dim].copy_from_slice(&l.x0[k][..dim]);
            }
            fixed[v] |= l.fixed[k];
        }
    }
    (x_ref, fixed, x0)
}

/// The loaded bodies in mesh numbering, for the shared assembler ([`assemble_mesh`]): each
/// body's elements, its h the longest reference edge of its elements.
fn body_parts(loaded: &[Loaded], global: &[Vec<usize>]) -> Vec<BodyPart> {
    loaded
        .iter()
        .zip(global)
        .map(|(l, map)| BodyPart {
            name: l.name.clone(),
            kind: l.kind,
            vertices: map.clone(),
            elements: l
                .elems
                .iter()
                .map(|e| std::array::from_fn(|k| if k < l.arity { map[e[k]] } else { 0 }))
                .collect(),
            arity: l.arity,
            h: None,
            edges: None,
            faces: None,
        })
        .collect()
}

/// h: the mesh size of the bodies that deform (a body whose vertices are all fixed is an
/// obstacle, its edges may be long); of all bodies if every vertex is fixed. Also returns
/// which bodies have every vertex fixed.
fn mesh_size(mesh: &Mesh) -> (f64, Vec<bool>) {
    let deforms = |b: &Body| b.vertices.iter().any(|&v| !mesh.fixed[v]);
    let h = if mesh.bodies.iter().any(deforms) {
        mesh.bodies
            .iter()
            .filter(|b| deforms(b))
            .map(|b| b.h)
            .fold(0.0, f64::max)
    } else {
        mesh.bodies.iter().map(|b| b.h).fold(0.0, f64::max)
    };
    let body_all_fixed: Vec<bool> = mesh.bodies.iter().map(|b| !deforms(b)).collect();
    (h, body_all_fixed)
}
