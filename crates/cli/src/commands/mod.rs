//! One file per subcommand, each a front-end over the `lodkit` library
//! (or an engine crate); no command file imports another.
pub mod build;
pub mod compare;
pub mod convert;
pub mod generate;
pub mod info;
pub mod lods;
pub mod mco;
pub mod pop;
pub mod render;
pub mod scan;
pub mod serve;
pub mod simplify;
pub mod tiles;

use std::path::Path;

use anyhow::Result;
use lodkit_mesh::Model;

use crate::ui::Ui;

pub use lodkit::input::{Input, describe, holds_scenes};
pub use lodkit::output::{mesh_output, written_as};

/// Loads any supported file ([`lodkit::input::load`]), its reading drawn
/// as a spinner.
pub fn load(ui: &Ui, path: &Path) -> Result<Model> {
    ui.run(|events| lodkit::input::load(events, path))
}

/// Loads a file that must be a triangle mesh ([`lodkit::input::load_mesh`]).
pub fn load_mesh(ui: &Ui, path: &Path) -> Result<lodkit_mesh::TriMesh> {
    ui.run(|events| lodkit::input::load_mesh(events, path))
}

/// Loads a mesh or a scene ([`lodkit::input::load_input`]).
pub fn load_input(ui: &Ui, path: &Path, keeps: bool) -> Result<Input> {
    ui.run(|events| lodkit::input::load_input(events, path, keeps))
}

/// Pretty JSON on stdout.
pub fn print_json(value: &impl serde::Serialize) -> Result<()> {
    crate::outln!("{}", serde_json::to_string_pretty(value)?)?;
    Ok(())
}
