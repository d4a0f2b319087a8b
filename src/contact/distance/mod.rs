//! Geometry kernels, one file per primitive pair, named as the pairs of every other layer:
//! `point_edge` (2D), `point_triangle` (3D), `edge_edge` (3D segments, and 2D crossings).
//! Each returns the distance (never squared) and the closest points' barycentric coordinates.

pub mod edge_edge;
pub mod point_edge;
pub mod point_triangle;

pub use edge_edge::{edge_edge_distance, edge_edge_distance_2d, EdgeEdge};
pub use point_edge::{point_edge_distance, PointEdge};
pub use point_triangle::{point_triangle_distance, PointTriangle};
