//! (in progress)
/// placeholder
pub struct Gravity;
