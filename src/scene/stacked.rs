//! What the two stacked 3D scenes ([`super::sheets`], [`super::solids`]) share: a `lower`
//! body (body 0) and an `upper` body (body 1) made from copies of one unit mesh of `np`
//! vertices (the upper's vertices `np..2np` after the lower's), the upper one rotated about the
//! z axis; the footprint test of the rotated upper body, the two body parts, and the
//! assembled, validated mesh with the check that the start is admissible. Each scene keeps its
//! own geometry (where the copies go), energies and error type.

use crate::contact::broad_phase::min_distance_3d;
use crate::scene::assemble::{assemble_mesh, file_order, BodyPart};
use crate::scene::mesh::{BodyKind, Mesh, MeshError};

/// `(sin θ, cos θ)` of the rotation angle `angle_deg` (degrees).
pub(crate) fn sin_cos(angle_deg: f64) -> (f64, f64) {
    angle_deg.to_radians().sin_cos()
}

/// The half-width, along x and y, of a square of half side `size` rotated by `angle_deg` about
/// z: `size · (|cos θ| + |sin θ|)` (it stands inside the unit square centred at the origin when
/// this is < 1).
pub(crate) fn rotated_extent(size: f64, angle_deg: f64) -> f64 {
    let (s, c) = sin_cos(angle_deg);
    size * (s.abs() + c.abs())
}

/// `(u, v)` rotated about z by the angle whose `(sin θ, cos θ)` is `(s, c)`.
pub(crate) fn rotate_z((s, c): (f64, f64), u: f64, v: f64) -> (f64, f64) {
    (c * u - s * v, s * u + c * v)
}

/// One of the two bodies: its elements (global vertex indices, `arity` entries used), its
/// largest reference edge, and its contact faces if given (else the assembler's boundary).
pub(crate) struct Block {
    pub(crate) elements: Vec<[usize; 4]>,
    pub(crate) h: f64,
    pub(crate) faces: Option<Vec<[usize; 3]>>,
}

/// Why [`assemble`] refuses: an invalid mesh, or a start closer than ε.
pub(crate) enum StackError {
    Mesh(MeshError),
    InadmissibleStart {
        pair: String,
        distance: f64,
        eps: f64,
    },
}

/// The mesh of `lower` (body 0, vertices `0..np`) and `upper` (body 1, vertices `np..2np`),
/// both of `kind` with elements of `arity` vertices, in scene-file order; validated, and `x0`
/// checked to keep every pair of disjoint contact elements at least `eps` apart.
#[allow(clippy::too_many_arguments)]
pub(crate) fn assemble(
    kind: BodyKind,
    arity: usize,
    np: usize,
    [lower, upper]: [Block; 2],
    x_ref: Vec<f64>,
    fixed: Vec<bool>,
    x0: &[f64],
    eps: f64,
) -> Result<Mesh, StackError> {
    let part = |name: &str, b: usize, block: Block| BodyPart {
        name: name.into(),
        kind,
        vertices: (b * np..(b + 1) * np).collect(),
        elements: block.elements,
        arity,
        h: Some(block.h),
        edges: None,
        faces: block.faces,
    };
    let parts = [part("lower", 0, lower), part("upper", 1, upper)];
    let mesh = assemble_mesh(3, x_ref, fixed, &parts, &file_order(2));
    mesh.validate().map_err(StackError::Mesh)?;
    let (distance, pair) = min_distance_3d(&mesh, x0, eps);
    if distance < eps {
        return Err(StackError::InadmissibleStart {
            pair: format!("{pair:?}"),
            distance,
            eps,
        });
    }
    Ok(mesh)
}
