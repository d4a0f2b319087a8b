//! placeholder
use crate::backend::*;
/// placeholder
pub struct UzawaBackend(QpSettings);
impl UzawaBackend { /// new
 pub fn new(s: QpSettings) -> Self { Self(s) } }
impl QpBackend for UzawaBackend { fn name(&self) -> &'static str { "uzawa" } fn solve(&mut self, _qp: &crate::Qp, _w: Option<&WarmStart>) -> Result<QpSolution, QpError> { unimplemented!() } }
