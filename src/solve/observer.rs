//! Observers of the iterative loops: the outer loop of §3 ([`super::outer::run_observed`]) and
//! time stepping of §6 ([`super::dynamics::simulate_observed`]) never print or write; they
//! report to an [`Observer`]: [`Observer::init`] once before the first event,
//! [`Observer::iteration`] once per event (the outer loop: iteration 0, the start, then one per
//! outer step; time stepping: step 0, then one per step) and [`Observer::finish`] with the
//! loop's outcome when it returns normally (not on an error). The run-directory writers
//! (`output::run_dir`, `docs/run-directory.md`) are observers; [`EveryK`] thins the events
//! one of them sees, [`Fanout`] hands every event to several in order.

/// A loop that reports to observers: the type of its events and of its outcome.
pub trait Loop {
    /// What one iteration reports.
    type Event<'a>;
    /// What the loop returns on a normal end.
    type Outcome;
    /// The event's index (the outer iteration, the time step).
    fn index(event: &Self::Event<'_>) -> usize;
}

/// Watches a [`Loop`]. Every method but [`Observer::iteration`] defaults to nothing.
pub trait Observer<L: Loop> {
    /// Before the first event.
    fn init(&mut self) {}
    /// One event.
    fn iteration(&mut self, event: &L::Event<'_>);
    /// After the last event, when the loop ends without an error.
    fn finish(&mut self, _outcome: &L::Outcome) {}
}

/// Watches nothing.
impl<L: Loop> Observer<L> for () {
    fn iteration(&mut self, _event: &L::Event<'_>) {}
}

/// Passes `inner` the events whose index is a multiple of `k` (`k = 0` counts as 1) or equals
/// `last`; [`Observer::init`] and [`Observer::finish`] always.
pub struct EveryK<O> {
    /// The period.
    pub k: usize,
    /// An index always passed on (e.g. the last time step).
    pub last: Option<usize>,
    /// The observer that sees the passed events.
    pub inner: O,
}

impl<O> EveryK<O> {
    /// Whether the event of index `i` is passed on.
    pub fn passes(&self, i: usize) -> bool {
        i.is_multiple_of(self.k.max(1)) || Some(i) == self.last
    }
}

impl<L: Loop, O: Observer<L>> Observer<L> for EveryK<O> {
    fn init(&mut self) {
        self.inner.init();
    }
    fn iteration(&mut self, event: &L::Event<'_>) {
        if self.passes(L::index(event)) {
            self.inner.iteration(event);
        }
    }
    fn finish(&mut self, outcome: &L::Outcome) {
        self.inner.finish(outcome);
    }
}

/// Hands every call to each observer in turn, in order.
pub struct Fanout<'o, L: Loop>(pub Vec<&'o mut dyn Observer<L>>);

impl<L: Loop> Observer<L> for Fanout<'_, L> {
    fn init(&mut self) {
        for o in &mut self.0 {
            o.init();
        }
    }
    fn iteration(&mut self, event: &L::Event<'_>) {
        for o in &mut self.0 {
            o.iteration(event);
        }
    }
    fn finish(&mut self, outcome: &L::Outcome) {
        for o in &mut self.0 {
            o.finish(outcome);
        }
    }
}
