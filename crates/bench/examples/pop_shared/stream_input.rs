//! The input the profiling examples share: a `.pop` file, or
//! `MODEL:R:N[:baseline]` encoded first (`MODEL` = `icosphereL` for the
//! icosphere of level `L` the criterion bench uses; depth `R`, precision
//! `N`, entropy mode unless `baseline`), so a format change needs no
//! rebuilt CLI.
use lodkit_particles::{EncodeOptions, Mode, encode};

/// The stream `input` names (see the module docs).
pub fn load(input: &str) -> Vec<u8> {
    let parts: Vec<&str> = input.split(':').collect();
    if parts.len() < 3 {
        return std::fs::read(input).unwrap_or_else(|e| panic!("{input}: {e}"));
    }
    let model = if let Some(level) = parts[0].strip_prefix("icosphere") {
        lodkit_mesh::Model::Mesh(lodkit_mesh::shapes::icosphere(
            level.parse().expect("level"),
        ))
    } else {
        lodkit_mesh::io::load(std::path::Path::new(parts[0]))
            .unwrap_or_else(|e| panic!("{input}: {e}"))
    };
    let opts = EncodeOptions {
        depth: Some(parts[1].parse().expect("depth")),
        precision: parts[2].parse().expect("precision"),
        mode: if parts.get(3) == Some(&"baseline") {
            Mode::Baseline
        } else {
            Mode::Entropy
        },
        ..EncodeOptions::DEFAULT
    };
    encode(&model, &opts).expect("encodes").bytes
}
