//! placeholder
use crate::backend::*;
/// placeholder
pub struct OsqpBackend(QpSettings);
impl OsqpBackend { /// new
 pub fn new(s: QpSettings) -> Self { Self(s) } }
impl QpBackend for OsqpBackend { fn name(&self) -> &'static str { "osqp" } fn solve(&mut self, _qp: &crate::Qp, _w: Option<&WarmStart>) -> Result<QpSolution, QpError> { unimplemented!() } }
