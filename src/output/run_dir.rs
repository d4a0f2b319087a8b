//! The run directory's per-iteration writers (`docs/run-directory.md`) as observers of the
//! outer loop ([`OuterLoop`], `contactlab run`) and of time stepping ([`DynamicLoop`],
//! `contactlab run --dynamic`):
//!
//! - [`History`]: `history.csv`, one row per record ([`IterationRecord`] / [`StepRecord`]),
//!   flushed after every row;
//! - [`Contacts`]: `contacts.csv`, per step the active pairs;
//! - [`Frames`]: `frames/frame_NNNNN.vtu` and `frames.pvd` (static: timestep = the outer
//!   iteration, and the returned state as the last frame; dynamic: timestep = the step's time,
//!   point data `speed`), to be thinned by an [`EveryK`];
//! - [`StaticProgress`] / [`DynamicProgress`]: the progress line on stderr, rewritten in place
//!   (`\r`), ended by a newline.
//!
//! The file writers are [`Writer`]s: [`RunDir`] runs them in order on every event, stops the
//! event at the first error and keeps the first error of the run ([`RunDir::into_result`]);
//! the run itself goes on.

use crate::contact::PairRows;
use crate::output::vtk::{write_vtu_with, OwnedVtuFields, PvdSeries, VtuFields};
use crate::scene::mesh::Mesh;
use crate::solve::dynamics::{DynamicLoop, StepEvent, StepRecord};
use crate::solve::observer::{EveryK, Loop, Observer};
use crate::solve::outer::{IterationRecord, OuterEvent, OuterLoop};
use anyhow::{Context, Result};
use std::fs::File;
use std::io::Write;
use std::path::{Path, PathBuf};

/// A fallible observer: a file of the run directory.
pub trait Writer<L: Loop> {
    /// Writes one event.
    fn write(&mut self, event: &L::Event<'_>) -> Result<()>;
    /// After the last event.
    fn finish(&mut self, _outcome: &L::Outcome) -> Result<()> {
        Ok(())
    }
}

/// Writers run in order as one observer, keeping the first error.
pub struct RunDir<'w, L: Loop> {
    writers: Vec<&'w mut dyn Writer<L>>,
    error: Option<anyhow::Error>,
    finish_error: Option<anyhow::Error>,
}

impl<'w, L: Loop> RunDir<'w, L> {
    /// The writers, called in this order.
    pub fn new(writers: Vec<&'w mut dyn Writer<L>>) -> Self {
        Self {
            writers,
            error: None,
            finish_error: None,
        }
    }

    /// The first error of an event, with the context "writing the run directory", else the
    /// error of the finish (as it is).
    pub fn into_result(self) -> Result<()> {
        match (self.error, self.finish_error) {
            (Some(e), _) => Err(e.context("writing the run directory")),
            (None, Some(e)) => Err(e),
            (None, None) => Ok(()),
        }
    }
}

impl<L: Loop> Observer<L> for RunDir<'_, L> {
    fn iteration(&mut self, event: &L::Event<'_>) {
        let r = self.writers.iter_mut().try_for_each(|w| w.write(event));
        if let Err(e) = r {
            self.error.get_or_insert(e);
        }
    }
    fn finish(&mut self, outcome: &L::Outcome) {
        if self.error.is_some() {
            return;
        }
        if let Err(e) = self.writers.iter_mut().try_for_each(|w| w.finish(outcome)) {
            self.finish_error = Some(e);
        }
    }
}

/// The events of index a multiple of `k` or `last`; the finish always.
impl<L: Loop, W: Writer<L>> Writer<L> for EveryK<W> {
    fn write(&mut self, event: &L::Event<'_>) -> Result<()> {
        if self.passes(L::index(event)) {
            self.inner.write(event)?;
        }
        Ok(())
    }
    fn finish(&mut self, outcome: &L::Outcome) -> Result<()> {
        self.inner.finish(outcome)
    }
}

/// `history.csv`: one row per record.
pub struct History(csv::Writer<File>);

impl History {
    /// Creates `path`.
    pub fn create(path: &Path) -> Result<Self> {
        Ok(Self(csv::Writer::from_path(path)?))
    }

    fn row<R: serde::Serialize>(&mut self, record: &R) -> Result<()> {
        self.0.serialize(record)?;
        self.0.flush()?;
        Ok(())
    }
}

impl Writer<OuterLoop> for History {
    fn write(&mut self, event: &OuterEvent<'_>) -> Result<()> {
        self.row::<IterationRecord>(event.record)
    }
    fn finish(&mut self, _outcome: &crate::solve::outer::RunResult) -> Result<()> {
        Ok(self.0.flush()?)
    }
}

impl Writer<DynamicLoop> for History {
    fn write(&mut self, event: &StepEvent<'_>) -> Result<()> {
        self.row::<StepRecord>(event.record)
    }
    fn finish(&mut self, _outcome: &crate::solve::dynamics::DynamicResult) -> Result<()> {
        Ok(self.0.flush()?)
    }
}

/// One row of `contacts.csv`: an active pair after a step.
#[derive(serde::Serialize)]
struct ContactRow {
    step: usize,
    time: f64,
    kind: &'static str,
    first: usize,
    second: usize,
    force: f64,
    distance: f64,
}

/// `contacts.csv`: per step, the active pairs (step, time, kind, first, second, force,
/// distance).
pub struct Contacts(csv::Writer<File>);

impl Contacts {
    /// Creates `path`.
    pub fn create(path: &Path) -> Result<Self> {
        Ok(Self(csv::Writer::from_path(path)?))
    }
}

impl Writer<DynamicLoop> for Contacts {
    fn write(&mut self, event: &StepEvent<'_>) -> Result<()> {
        let rec = event.record;
        for f in event.forces.iter().filter(|f| f.active) {
            let (first, second) = f.pair.indices();
            self.0.serialize(ContactRow {
                step: rec.step,
                time: rec.time,
                kind: f.pair.kind(),
                first,
                second,
                force: f.force,
                distance: f.distance,
            })?;
        }
        self.0.flush()?;
        Ok(())
    }
    fn finish(&mut self, _outcome: &crate::solve::dynamics::DynamicResult) -> Result<()> {
        Ok(self.0.flush()?)
    }
}

/// The data arrays of a static frame, from its iterate and its step's rows and multipliers
/// (the harness computes them: contact forces, pressures, stresses).
pub type FieldsFn<'m> = Box<dyn FnMut(&[f64], &[PairRows], &[[f64; 4]]) -> OwnedVtuFields + 'm>;

/// `frames/frame_NNNNN.vtu` and `frames.pvd` in the run directory `out`: every event it sees
/// is a frame (thin the events with an [`EveryK`]).
pub struct Frames<'m> {
    out: PathBuf,
    mesh: &'m Mesh,
    pvd: PvdSeries,
    last: usize,
    fields: Option<FieldsFn<'m>>,
}

impl<'m> Frames<'m> {
    /// Creates the directory `out/frames`.
    pub fn create(out: &Path, mesh: &'m Mesh) -> Result<Self> {
        let frames = out.join("frames");
        std::fs::create_dir_all(&frames)
            .with_context(|| format!("cannot create run directory {}", frames.display()))?;
        Ok(Self {
            out: out.to_path_buf(),
            mesh,
            pvd: PvdSeries::default(),
            last: 0,
            fields: None,
        })
    }

    /// Static frames with the data arrays `fields` computes.
    pub fn with_fields(mut self, fields: FieldsFn<'m>) -> Self {
        self.fields = Some(fields);
        self
    }

    /// Writes frame `index` at `time` and rewrites the `.pvd`. The triangles shown: the solid
    /// elements in 2D, the contact faces in 3D (the surfaces' triangles and the solids'
    /// boundary).
    fn frame(&mut self, index: usize, time: f64, x: &[f64], fields: &VtuFields) -> Result<()> {
        let mesh = self.mesh;
        let tris = if mesh.dim == 3 {
            &mesh.faces
        } else {
            &mesh.triangles
        };
        let name = format!("frame_{index:05}.vtu");
        write_vtu_with(
            &self.out.join("frames").join(&name),
            mesh.dim,
            x,
            &mesh.edges,
            tris,
            &mesh.tets,
            fields,
        )?;
        self.pvd.push(time, format!("frames/{name}"));
        self.pvd.write(&self.out.join("frames.pvd"))?;
        self.last = index;
        Ok(())
    }
}

/// Static: timestep = the outer iteration; on finish the returned state (the last admissible
/// iterate) is the frame of the last iteration unless that one was written.
impl Writer<OuterLoop> for Frames<'_> {
    fn write(&mut self, event: &OuterEvent<'_>) -> Result<()> {
        let k = event.record.iteration;
        let data = self
            .fields
            .as_mut()
            .map(|f| f(event.x, event.rows, event.multipliers))
            .unwrap_or_default();
        self.frame(k, k as f64, event.x, &data.fields())
    }
    fn finish(&mut self, outcome: &crate::solve::outer::RunResult) -> Result<()> {
        if self.last != outcome.outer_iterations {
            let k = outcome.outer_iterations;
            let data = self
                .fields
                .as_mut()
                .map(|f| f(&outcome.x, &outcome.last_rows, &outcome.multipliers))
                .unwrap_or_default();
            self.frame(k, k as f64, &outcome.x, &data.fields())?;
        }
        Ok(())
    }
}

/// Dynamic: timestep = the step's time, point data `speed` (per vertex `|v|`).
impl Writer<DynamicLoop> for Frames<'_> {
    fn write(&mut self, event: &StepEvent<'_>) -> Result<()> {
        let st = event.state;
        let speed: Vec<f64> =
            st.v.chunks(self.mesh.dim)
                .map(|c| c.iter().map(|v| v * v).sum::<f64>().sqrt())
                .collect();
        let fields = VtuFields {
            point_scalars: vec![("speed", &speed)],
            ..Default::default()
        };
        self.frame(event.record.step, event.record.time, &st.x, &fields)
    }
}

/// Writes `line` over the current stderr line.
fn progress(line: std::fmt::Arguments) {
    eprint!("\r{line}   ");
    let _ = std::io::stderr().flush();
}

/// The progress line of a static run: backend, pruning, iteration, energy, distance, rows, QP.
pub struct StaticProgress {
    /// The backend's name.
    pub backend: String,
    /// The pruning's name.
    pub pruning: &'static str,
    /// The scene's ε (the distance is shown relative to it).
    pub eps: f64,
}

impl Observer<OuterLoop> for StaticProgress {
    fn iteration(&mut self, event: &OuterEvent<'_>) {
        let rec = event.record;
        progress(format_args!(
            "[{} {}] outer {:>4}  J = {:.10e}  min dist/eps = {:.6}  rows {:>7} active {:>4}  qp {} it {:>6}",
            self.backend, self.pruning, rec.iteration, rec.energy, rec.min_distance / self.eps, rec.rows, rec.active_rows, rec.qp_status, rec.backend_iterations
        ));
    }
    fn finish(&mut self, _outcome: &crate::solve::outer::RunResult) {
        eprintln!();
    }
}

/// The progress line of a dynamic run: scheme, backend, step, time, energies, distance,
/// contacts, outer iterations and status.
pub struct DynamicProgress {
    /// The scheme's name.
    pub scheme: &'static str,
    /// The backend's name.
    pub backend: String,
    /// The number of steps.
    pub steps: usize,
    /// The scene's ε (the distance is shown relative to it).
    pub eps: f64,
}

impl Observer<DynamicLoop> for DynamicProgress {
    fn iteration(&mut self, event: &StepEvent<'_>) {
        let rec = event.record;
        progress(format_args!(
            "[{} {}] step {:>5}/{} t = {:.4}  E = {:.8e}  K = {:.3e}  min dist/eps = {:.5}  contacts {:>4}  F = {:.4e}  outer {:>4} {}",
            self.scheme, self.backend, rec.step, self.steps, rec.time, rec.total, rec.kinetic, rec.min_distance / self.eps, rec.active_contacts, rec.contact_force, rec.outer_iterations, rec.status
        ));
    }
    fn finish(&mut self, _outcome: &crate::solve::dynamics::DynamicResult) {
        eprintln!();
    }
}
