//! Geometry kernels, one file per primitive pair.
