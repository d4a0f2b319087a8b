//! The material of a solid body (docs/materials.md): the model (`neo-hookean`,
//! `linear-elastic`), its constants (`mu` and `lambda`, or `E` and `nu`) and, in 2D, plane
//! strain or plane stress (`plane`).

use super::schema::MaterialSpec;
use super::{Ctx, Loaded, SceneFileError};
use crate::energy::{Elasticity, Plane};
use crate::scene::physics::Material;

impl Ctx<'_> {
    /// A solid's material, checked: the model (`neo-hookean`, `linear-elastic`), its
    /// constants and, in 2D, plane strain or stress.
    pub(super) fn solid_material(
        &self,
        dim: usize,
        l: &Loaded,
        m: &MaterialSpec,
    ) -> Result<Material, SceneFileError> {
        let line = l.line;
        let mk = format!("{}.material", l.key);
        let linear = match m.model.as_str() {
            "neo-hookean" => false,
            "linear-elastic" => true,
            other => {
                return Err(self.invalid(
                    line,
                    format!("{mk}.model"),
                    format!("{other:?}"),
                    "a solid body takes model = \"neo-hookean\" or \"linear-elastic\" (models: string for curves, stvk-membrane for 3D surfaces, neo-hookean or linear-elastic for solids)",
                ));
            }
        };
        let c = self.elastic_constants(line, &mk, m)?;
        let plane = match (&m.plane, dim) {
            (None, _) => Plane::Strain,
            (Some(p), 2) => match p.as_str() {
                "strain" => Plane::Strain,
                "stress" => Plane::Stress,
                _ => {
                    return Err(self.invalid(
                        line,
                        format!("{mk}.plane"),
                        format!("{p:?}"),
                        "expected \"strain\" or \"stress\"",
                    ))
                }
            },
            (Some(p), _) => {
                return Err(self.invalid(
                    line,
                    format!("{mk}.plane"),
                    format!("{p:?}"),
                    "plane strain or stress is a choice of 2D solids; a 3D solid has neither",
                ))
            }
        };
        let (mu, lambda) = (c.mu, c.lambda);
        Ok(match (linear, plane) {
            (true, plane) => Material::LinearElastic { mu, lambda, plane },
            (false, Plane::Strain) => Material::NeoHookean { mu, lambda },
            (false, Plane::Stress) => Material::NeoHookeanPlaneStress { mu, lambda },
        })
    }

    /// `mu` and `lambda`, or `E` and `nu` (not both pairs): `μ > 0`, `λ ≥ 0` (so `ν ≥ 0`:
    /// with `λ < 0` the neo-Hookean `W` is unbounded below as `det F → 0`). Also the
    /// constants of a 3D surface's membrane (`E` and `nu` are refused before, on non-solids).
    pub(super) fn elastic_constants(
        &self,
        line: usize,
        mk: &str,
        m: &MaterialSpec,
    ) -> Result<Elasticity, SceneFileError> {
        let lame = m.mu.is_some() || m.lambda.is_some();
        let young = m.young.is_some() || m.nu.is_some();
        if lame && young {
            let given: Vec<String> = [
                ("mu", m.mu),
                ("lambda", m.lambda),
                ("E", m.young),
                ("nu", m.nu),
            ]
            .iter()
            .filter_map(|(k, v)| v.map(|v| format!("{k} = {v}")))
            .collect();
            return Err(self.invalid(
                line,
                mk,
                format!("{{ {} }}", given.join(", ")),
                "give either mu and lambda, or E and nu, not both",
            ));
        }
        if young {
            let e = m.young.ok_or_else(|| {
                self.invalid(line, format!("{mk}.E"), "(missing)", "required with nu")
            })?;
            let nu = m.nu.ok_or_else(|| {
                self.invalid(line, format!("{mk}.nu"), "(missing)", "required with E")
            })?;
            if !(e > 0.0 && e.is_finite()) {
                return Err(self.invalid(line, format!("{mk}.E"), e, "must be finite and > 0"));
            }
            if !(0.0..0.5).contains(&nu) {
                return Err(self.invalid(
                    line,
                    format!("{mk}.nu"),
                    nu,
                    "must lie in [0, 0.5) (0.5 is incompressible; nu < 0 makes lambda < 0)",
                ));
            }
            return Elasticity::from_young_poisson(e, nu).map_err(|err| {
                self.invalid(line, mk, format!("E = {e}, nu = {nu}"), err.to_string())
            });
        }
        let mu = m.mu.ok_or_else(|| {
            self.invalid(
                line,
                format!("{mk}.mu"),
                "(missing)",
                "required (or give E and nu)",
            )
        })?;
        if !(mu > 0.0 && mu.is_finite()) {
            return Err(self.invalid(line, format!("{mk}.mu"), mu, "must be finite and > 0"));
        }
        let lambda = m
            .lambda
            .ok_or_else(|| self.invalid(line, format!("{mk}.lambda"), "(missing)", "required"))?;
        if !(lambda >= 0.0 && lambda.is_finite()) {
            return Err(self.invalid(
                line,
                format!("{mk}.lambda"),
                lambda,
                "must be finite and ≥ 0",
            ));
        }
        Ok(Elasticity { mu, lambda })
    }
}
