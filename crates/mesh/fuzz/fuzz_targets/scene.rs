//! Fuzzes the scene readers — glTF / GLB materials, textures, samplers and
//! images (`io::gltf::read_scene`), and OBJ + MTL (`io::mtl`, the bytes
//! after the first NUL read as every `mtllib`), chosen by the first byte —
//! and writes back what they accept: any bytes must give `Ok` or a
//! `ParseError`, never a panic, an abort or a runaway allocation, and a
//! scene that reads must write a GLB that reads back (no factor written as
//! JSON `null`). No folder is given, so no file is ever opened.
#![no_main]

use libfuzzer_sys::fuzz_target;
use lodkit_mesh::io::{gltf, mtl};

fuzz_target!(|data: &[u8]| {
    let Some((&kind, rest)) = data.split_first() else {
        return;
    };
    let scene = if kind % 2 == 0 {
        gltf::read_scene(rest, None)
    } else {
        let (obj, lib) = match rest.iter().position(|&b| b == 0) {
            Some(i) => (&rest[..i], &rest[i + 1..]),
            None => (rest, &[][..]),
        };
        mtl::read_scene_for_fuzzing(obj, lib)
    };
    if let Ok(scene) = scene
        && let Ok(glb) = gltf::write_scene_glb(&scene)
    {
        let back = gltf::read_scene(&glb, None);
        assert!(back.is_ok(), "a written scene does not read back: {back:?}");
    }
});
