//! `lodkit info FILE`: a model's figures; for a `.mco` octree or a `.pop`
//! stream, what `lodkit mco info` / `lodkit pop stats` print; for a
//! calibration (`transforms.json`, COLMAP `cameras.txt` / `images.txt`),
//! the image set ([`lodkit::info`]).
use std::path::Path;

use anyhow::Result;
use lodkit::info::Info;

use crate::ui::Ui;

pub fn run(ui: &Ui, file: &Path, json: bool) -> Result<()> {
    let info = ui.run(|events| lodkit::info::run(file, events))?;
    match (&info, json) {
        (Info::Model { info, .. }, true) => super::print_json(info),
        (Info::Mco(i), true) => super::print_json(i),
        (Info::Pop(i), true) => super::print_json(i),
        (Info::ImageSet(i), true) => super::print_json(i),
        (Info::Model { file, info }, false) => {
            crate::outln!("file: {file}")?;
            crate::out!("{}", info.to_text())?;
            Ok(())
        }
        (Info::Mco(i), false) => Ok(crate::out!("{i}")?),
        (Info::Pop(i), false) => Ok(crate::out!("{i}")?),
        (Info::ImageSet(i), false) => Ok(crate::out!("{i}")?),
    }
}
