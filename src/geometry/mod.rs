//! Geometry kernels, one file per primitive pair (2D: point–edge, edge–edge; 3D: point–triangle,
//! segment–segment).

pub mod edge_edge;
pub mod point_edge;

pub use edge_edge::edge_edge_distance_2d;
pub use point_edge::{point_edge_distance, PointEdge};
pub mod point_triangle;
pub mod segment_segment;

pub use point_triangle::{point_triangle_distance, PointTriangle};
pub use segment_segment::{segment_segment_distance, SegmentSegment};
