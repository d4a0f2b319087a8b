//! Geometry kernels, one file per primitive pair.

pub mod edge_edge;
pub mod point_edge;

pub use edge_edge::edge_edge_distance_2d;
pub use point_edge::{point_edge_distance, PointEdge};
