//! lodkit's product as a library: the jobs that the `lodkit` command, the
//! `pylodkit` Python package and a server all call, over the engine crates
//! (`lodkit-mesh`, `lodkit-simplify`, `lodkit-scale`, `lodkit-mco`,
//! `lodkit-particles`, `lodkit-render`).
//!
//! # A job
//!
//! A job is a function taking its options and a [`Progress`], returning a
//! report:
//!
//! ```text
//! pub fn run(job: &XJob, events: &Progress) -> anyhow::Result<XReport>
//! ```
//!
//! - `XJob` holds everything the job reads (paths, option values within
//!   the ranges of [`limits`]); it is a plain struct, so any front-end can
//!   fill it (clap arguments, Python keywords, a request's JSON).
//! - [`Progress`] wraps the caller's `Fn(&Event)` callback: stages,
//!   phases with their sizes, notes and warnings arrive as [`Event`]s
//!   while the job runs. The job never prints.
//! - `XReport` says what was done (serde-serialisable where a front-end
//!   prints it as JSON), with the one-line summary a terminal shows.
//! - Errors are one `anyhow::Error` naming the file and what is wrong;
//!   a request these options cannot serve carries a [`usage::Usage`]
//!   (the CLI's exit 2).
//!
//! A new capability is one more module of this shape (one file per
//! stage), and one thin call in each front-end.
//!
//! # Modules
//!
//! - [`input`]: loading any input (meshes, scenes, clouds, range images,
//!   scan sets, image sets) and the built-in bunny;
//! - [`limits`]: every range and default of every option;
//! - [`plan`]: in core or out of core;
//! - jobs: [`simplify`], [`lod_chain`], [`build_all`], [`compare`], [`info`],
//!   [`render`], [`mco_build`], [`stream_encode`];
//! - [`report`]: the serde types front-ends print (one definition each);
//! - [`output`], [`materials`], [`measure`]: what the jobs share.

#![forbid(unsafe_code)]

pub mod build_all;
pub mod compare;
pub mod info;
pub mod input;
pub mod limits;
pub mod lod_chain;
pub mod materials;
pub mod mco_build;
pub mod measure;
pub mod output;
pub mod plan;
pub mod progress;
pub mod render;
pub mod report;
pub mod simplify;
pub mod stream_encode;
pub mod tiles;
pub mod usage;

pub use progress::{Event, Progress};
