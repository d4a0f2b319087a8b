//! (in progress)
/// placeholder
pub struct NeoHookean2d;
