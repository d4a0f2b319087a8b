//! placeholder
use crate::backend::*;
/// placeholder
pub struct ClarabelBackend(QpSettings);
impl ClarabelBackend { /// new
 pub fn new(s: QpSettings) -> Self { Self(s) } }
impl QpBackend for ClarabelBackend { fn name(&self) -> &'static str { "clarabel" } fn solve(&mut self, _qp: &crate::Qp, _w: Option<&WarmStart>) -> Result<QpSolution, QpError> { unimplemented!() } }
