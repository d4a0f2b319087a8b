//! (in progress)
/// placeholder
pub struct GasEnergy;
