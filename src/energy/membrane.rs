//! (in progress)
/// placeholder
pub struct MembraneEnergy;
