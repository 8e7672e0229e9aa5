//! Encode a surface as a progressive `.pop` stream, then decode it as a
//! viewer receiving it would: from prefixes of growing length, each giving
//! the finest complete level and its oriented mesh.
//!
//! `cargo run --release -p lodkit-particles --example stream_prefix [MESH]`
//! (the built-in icosphere without an argument).
use lodkit_mesh::Model;
use lodkit_particles::{DecodeOptions, EncodeOptions, TriangulateOptions, decode_prefix, encode};

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let model = match std::env::args().nth(1) {
        Some(path) => lodkit_mesh::io::load(std::path::Path::new(&path))?,
        None => Model::Mesh(lodkit_mesh::shapes::icosphere(5)),
    };
    let stream = encode(&model, &EncodeOptions::DEFAULT)?.bytes;
    println!("stream: {} bytes", stream.len());
    for percent in [5, 10, 25, 50, 100] {
        let arrived = &stream[..stream.len() * percent / 100];
        let d = match decode_prefix(arrived, &DecodeOptions::default()) {
            Ok(d) => d,
            Err(e) => {
                println!("{percent:>3} %: nothing to show yet ({e})");
                continue;
            }
        };
        let level = d.finest_level();
        let mesh = d.triangulate(level, &TriangulateOptions::DEFAULT)?.mesh;
        println!(
            "{percent:>3} %: level {level}, {} particles at {} bits, {} triangles; {} of {} bytes used",
            mesh.positions.len(),
            d.precision,
            mesh.faces.len(),
            d.bytes_read,
            arrived.len()
        );
    }
    Ok(())
}
