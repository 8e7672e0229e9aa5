//! A job's [`lodkit::Event`]s as calls of a Python function: the bridge
//! between the library's one progress callback and `progress=` of every
//! pylodkit job.
//!
//! Contract:
//! - **Events** arrive as one dict each, in the order the job sends them:
//!   `{"event": "note" | "warning", "message"}`, `{"event":
//!   "stage_started", "name", "long"}`, `{"event": "stage_finished",
//!   "name", "seconds"}`, `{"event": "phase", "name", "len"}`, `{"event":
//!   "advance", "n", "done", "len"}` (`done`: the phase's units so far,
//!   never decreasing), `{"event": "phases_finished"}`, `{"event":
//!   "timing", "name", "seconds"}`, `{"event": "level", "level": {...}}`
//!   (a level of a chain as `lods.json` has it).
//! - **The GIL** is taken only to make the dict and call the function;
//!   the job runs without it. Calls never overlap (an out-of-core phase
//!   advances from worker threads; they are serialised here).
//! - **An exception** raised by the function stops further calls; the job
//!   runs to its end and the exception is raised when it returns (a job
//!   is not interrupted halfway, so its outputs stay whole).

use std::sync::Mutex;

use lodkit::{Event, Progress};
use pyo3::prelude::*;
use pyo3::types::PyDict;

use crate::convert::json_to_py;

/// What the bridge remembers between events.
#[derive(Default)]
struct State {
    /// The current phase's size and the units done so far.
    len: u64,
    done: u64,
    /// The first exception the function raised.
    error: Option<PyErr>,
}

/// The Python function and the bridge's state; [`Bridge::run`] runs a job
/// with it.
pub struct Bridge {
    callback: Option<Py<PyAny>>,
    state: Mutex<State>,
}

impl Bridge {
    /// A bridge to `callback` (`None`: events are dropped). Errors: a
    /// `callback` that cannot be called (`TypeError`).
    pub fn new(callback: Option<Bound<'_, PyAny>>) -> PyResult<Bridge> {
        if let Some(c) = &callback
            && !c.is_callable()
        {
            return Err(pyo3::exceptions::PyTypeError::new_err(
                "progress: expected a function taking one dict, or None",
            ));
        }
        Ok(Bridge {
            callback: callback.map(Bound::unbind),
            state: Mutex::new(State::default()),
        })
    }

    /// Runs `job` with the GIL released, reporting to the function; then
    /// raises what the function raised, if anything.
    pub fn run<T: Send>(
        &self,
        py: Python<'_>,
        job: impl FnOnce(&Progress) -> T + Send,
    ) -> PyResult<T> {
        let out = match &self.callback {
            None => py.detach(|| job(&Progress::silent())),
            Some(_) => {
                let sink = |e: &Event<'_>| self.send(e);
                py.detach(|| job(&Progress::new(&sink)))
            }
        };
        let mut state = self.state.lock().unwrap_or_else(|e| e.into_inner());
        match state.error.take() {
            Some(e) => Err(e),
            None => Ok(out),
        }
    }

    fn send(&self, e: &Event<'_>) {
        let Some(callback) = &self.callback else {
            return;
        };
        // Held across the call: calls never overlap, and `done` grows in
        // the order the function sees it.
        let mut state = self.state.lock().unwrap_or_else(|e| e.into_inner());
        if state.error.is_some() {
            return;
        }
        match e {
            Event::Phase { len, .. } => {
                state.len = *len;
                state.done = 0;
            }
            Event::Advance(n) => state.done = state.done.saturating_add(*n),
            _ => {}
        }
        let (len, done) = (state.len, state.done);
        let r = Python::attach(|py| -> PyResult<()> {
            let d = event_dict(py, e, len, done)?;
            callback.call1(py, (d,))?;
            Ok(())
        });
        if let Err(err) = r {
            state.error = Some(err);
        }
    }
}

/// One event as the dict the function receives (see the module's contract).
fn event_dict<'py>(
    py: Python<'py>,
    e: &Event<'_>,
    len: u64,
    done: u64,
) -> PyResult<Bound<'py, PyDict>> {
    let d = PyDict::new(py);
    match e {
        Event::Note(m) => {
            d.set_item("event", "note")?;
            d.set_item("message", *m)?;
        }
        Event::Warning(m) => {
            d.set_item("event", "warning")?;
            d.set_item("message", *m)?;
        }
        Event::StageStarted { name, long } => {
            d.set_item("event", "stage_started")?;
            d.set_item("name", *name)?;
            d.set_item("long", *long)?;
        }
        Event::StageFinished { name, seconds } => {
            d.set_item("event", "stage_finished")?;
            d.set_item("name", *name)?;
            d.set_item("seconds", *seconds)?;
        }
        Event::Phase { name, len } => {
            d.set_item("event", "phase")?;
            d.set_item("name", *name)?;
            d.set_item("len", *len)?;
        }
        Event::Advance(n) => {
            d.set_item("event", "advance")?;
            d.set_item("n", *n)?;
            d.set_item("done", done)?;
            d.set_item("len", len)?;
        }
        Event::PhasesFinished => d.set_item("event", "phases_finished")?,
        Event::Timing { name, seconds } => {
            d.set_item("event", "timing")?;
            d.set_item("name", *name)?;
            d.set_item("seconds", *seconds)?;
        }
        Event::Level(l) => {
            d.set_item("event", "level")?;
            d.set_item("level", json_to_py(py, *l)?)?;
        }
    }
    Ok(d)
}
