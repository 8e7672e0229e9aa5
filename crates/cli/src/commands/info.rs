//! `lodkit info FILE`.
use std::path::Path;

use anyhow::Result;
use lodkit_mesh::info::model_info;

use crate::ui::Ui;

pub fn run(ui: &Ui, file: &Path, json: bool) -> Result<()> {
    let model = super::load(ui, file)?;
    let info = model_info(&model);
    if json {
        super::print_json(&info)
    } else {
        crate::outln!("file: {}", file.display())?;
        crate::out!("{}", info.to_text())?;
        Ok(())
    }
}
