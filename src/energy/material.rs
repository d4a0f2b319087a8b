//! Elastic constants of the solid models (docs/materials.md): Lamé's `μ`, `λ` from Young's
//! modulus and Poisson's ratio, the plane-stress `λ*`, and the plane modulus of Hertz contact.
//!
//! ```text
//! μ = E / (2(1 + ν)),   λ = E ν / ((1 + ν)(1 − 2ν)),
//! E = μ (3λ + 2μ)/(λ + μ),   ν = λ / (2(λ + μ)),
//! λ* = 2μλ/(λ + 2μ) = E ν/(1 − ν²)      (plane stress),
//! E' = E/(1 − ν²) (plane strain, 3D),   E' = E (plane stress).
//! ```

use thiserror::Error;

/// Plane strain or plane stress: how a 2D solid stands for a 3D one (ignored in 3D).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, serde::Serialize, serde::Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum Plane {
    /// `ε_zz = 0`: a long body (the default, and what the 2D neo-Hookean solid always was).
    #[default]
    Strain,
    /// `σ_zz = 0`: a thin plate.
    Stress,
}

/// Out-of-range elastic constants.
#[derive(Debug, Error, Clone, PartialEq)]
pub enum MaterialError {
    /// `E ≤ 0` or not finite.
    #[error("Young's modulus E = {0} must be finite and > 0")]
    Young(f64),
    /// `ν` outside `(−1, 1/2)`.
    #[error("Poisson's ratio nu = {0} must lie in (-1, 0.5) (0.5 is incompressible: λ = ∞)")]
    Poisson(f64),
}

/// Lamé's constants of an isotropic elastic material.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Elasticity {
    /// Shear modulus `μ`.
    pub mu: f64,
    /// Lamé's first parameter `λ`.
    pub lambda: f64,
}

impl Elasticity {
    /// From Young's modulus `E > 0` and Poisson's ratio `−1 < ν < 1/2`.
    pub fn from_young_poisson(e: f64, nu: f64) -> Result<Self, MaterialError> {
        if !(e > 0.0 && e.is_finite()) {
            return Err(MaterialError::Young(e));
        }
        if !(nu > -1.0 && nu < 0.5) {
            return Err(MaterialError::Poisson(nu));
        }
        Ok(Elasticity {
            mu: e / (2.0 * (1.0 + nu)),
            lambda: e * nu / ((1.0 + nu) * (1.0 - 2.0 * nu)),
        })
    }

    /// Young's modulus `E = μ(3λ + 2μ)/(λ + μ)`.
    pub fn young(&self) -> f64 {
        self.mu * (3.0 * self.lambda + 2.0 * self.mu) / (self.lambda + self.mu)
    }

    /// Poisson's ratio `ν = λ/(2(λ + μ))`.
    pub fn poisson(&self) -> f64 {
        self.lambda / (2.0 * (self.lambda + self.mu))
    }

    /// The in-plane Lamé constant of plane stress, `λ* = 2μλ/(λ + 2μ)`.
    pub fn plane_stress_lambda(&self) -> f64 {
        2.0 * self.mu * self.lambda / (self.lambda + 2.0 * self.mu)
    }

    /// The plane modulus `E'` of Hertz contact: `E/(1 − ν²)` in plane strain (and 3D), `E` in
    /// plane stress; `1/E* = 1/E'_1 + 1/E'_2` for two bodies.
    pub fn plane_modulus(&self, plane: Plane) -> f64 {
        let (e, nu) = (self.young(), self.poisson());
        match plane {
            Plane::Strain => e / (1.0 - nu * nu),
            Plane::Stress => e,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn material_young_poisson_round_trip_and_plane_constants() {
        for (e, nu) in [
            (1.0, 0.3),
            (2.1e11, 0.29),
            (5.0, 0.0),
            (1.0, -0.5),
            (3.0, 0.49),
        ] {
            let m = Elasticity::from_young_poisson(e, nu).unwrap();
            assert!((m.young() - e).abs() <= 1e-13 * e, "{e} {nu}");
            assert!((m.poisson() - nu).abs() <= 1e-13, "{e} {nu}");
            // λ* = Eν/(1 − ν²)
            let ls = e * nu / (1.0 - nu * nu);
            assert!(
                (m.plane_stress_lambda() - ls).abs() <= 1e-12 * e,
                "{e} {nu}"
            );
            assert!((m.plane_modulus(Plane::Strain) - e / (1.0 - nu * nu)).abs() <= 1e-12 * e);
            assert_eq!(m.plane_modulus(Plane::Stress), m.young());
        }
        assert_eq!(
            Elasticity::from_young_poisson(0.0, 0.3),
            Err(MaterialError::Young(0.0))
        );
        assert_eq!(
            Elasticity::from_young_poisson(1.0, 0.5),
            Err(MaterialError::Poisson(0.5))
        );
        assert!(Elasticity::from_young_poisson(f64::NAN, 0.3).is_err());
        assert!(Elasticity::from_young_poisson(1.0, -1.0).is_err());
    }
}
