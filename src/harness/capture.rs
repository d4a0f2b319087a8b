//! A backend wrapper that hands every QP of a run to a callback before solving it: QP export
//! (`contactlab export-qp`) and the captured-QP benches use it. The wrapper is transparent:
//! the wrapped backend sees the same calls in the same order, so the run is unchanged.

use contactlab_solvers::{Qp, QpBackend, QpError, QpSolution, WarmStart};

/// The callback of [`Capture`]: `(k, qp, what the backend returned)`.
pub type Sink<'a> = &'a mut (dyn FnMut(usize, &Qp, &Result<QpSolution, QpError>) + Send);

/// Wraps `inner`; `sink(k, qp, solution)` is called after the `k`-th solve (0-based) with the
/// QP and what the backend returned.
pub struct Capture<'a> {
    inner: &'a mut dyn QpBackend,
    sink: Sink<'a>,
    count: usize,
}

impl<'a> Capture<'a> {
    /// A wrapper around `inner` reporting to `sink`.
    pub fn new(inner: &'a mut dyn QpBackend, sink: Sink<'a>) -> Self {
        Capture {
            inner,
            sink,
            count: 0,
        }
    }

    /// Number of QPs seen so far.
    pub fn count(&self) -> usize {
        self.count
    }
}

impl QpBackend for Capture<'_> {
    fn name(&self) -> &'static str {
        self.inner.name()
    }

    fn tolerance(&self) -> Option<f64> {
        self.inner.tolerance()
    }

    fn set_tolerance(&mut self, tol: f64) {
        self.inner.set_tolerance(tol);
    }

    fn solve(&mut self, qp: &Qp, warm: Option<&WarmStart>) -> Result<QpSolution, QpError> {
        let r = self.inner.solve(qp, warm);
        (self.sink)(self.count, qp, &r);
        self.count += 1;
        r
    }
}
