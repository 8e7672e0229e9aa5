//! A level too big for memory, from its block soups to one binary PLY,
//! in memory bounded by one block and the blocks' shared vertices.
//!
//! Blocks share only the vertices on their cuts, which each block keeps
//! locked, bit for bit, and which lie on its border (an edge of one face
//! in the block). So each block is welded on its own, and only its border
//! vertices go through a map shared by all blocks: a vertex is numbered
//! where it first appears in block order. The PLY header needs the counts
//! first and the vertices come before the faces, so the blocks are read
//! three times: count, write the vertices, write the faces (each pass
//! numbers the vertices the same way).

use std::io::{BufWriter, Write};
use std::path::{Path, PathBuf};

use lodkit_mesh::TriMesh;
use rustc_hash::FxHashMap;

use crate::block::border_flags;
use crate::soup::{self, Corner, Layout, Welder, corner};

/// The global numbering of the vertices, block after block.
struct Numbering {
    layout: Layout,
    shared: FxHashMap<[u32; 9], u32>,
    next: u64,
}

impl Numbering {
    fn new(layout: Layout) -> Numbering {
        Numbering {
            layout,
            shared: FxHashMap::default(),
            next: 0,
        }
    }

    /// Numbers the vertices of one welded block (`border`: its border
    /// flags), calling `new` with each vertex the first time it appears;
    /// returns the block's local-to-global map.
    fn block(
        &mut self,
        mesh: &TriMesh,
        border: &[bool],
        mut new: impl FnMut(&Corner) -> std::io::Result<()>,
    ) -> std::io::Result<Vec<u32>> {
        let mut global = Vec::with_capacity(mesh.positions.len());
        for (v, &on_border) in border.iter().enumerate() {
            let c = corner(mesh, v as u32);
            if on_border {
                let key = self.layout.key(&c);
                if let Some(&g) = self.shared.get(&key) {
                    global.push(g);
                    continue;
                }
                self.shared.insert(key, self.next as u32);
            }
            if self.next >= u32::MAX as u64 {
                return Err(std::io::Error::other(
                    "the level has more vertices than 32-bit indices address",
                ));
            }
            global.push(self.next as u32);
            self.next += 1;
            new(&c)?;
        }
        Ok(global)
    }
}

fn weld(path: &Path, layout: Layout) -> std::io::Result<(TriMesh, Vec<bool>)> {
    let mut w = Welder::new(layout);
    soup::for_each(path, layout, |t| w.add(t))
        .map_err(|e| std::io::Error::other(format!("{}: {e}", path.display())))?;
    let mesh = w.finish();
    let border = border_flags(&mesh);
    Ok((mesh, border))
}

/// Writes the soup files `files` (in this order) as one welded binary
/// little-endian PLY at `out`, atomically (a failed write leaves no
/// file); returns its (faces, vertices). Vertices equal bit for bit on the
/// blocks' borders are one vertex; inside a block, as the block's weld.
/// Deterministic. Errors: I/O (naming the file), over 2^32 − 1 vertices.
/// Memory: one welded block, plus the shared border vertices (about 24 B
/// each). Cost: each file read and welded three times.
pub fn write_soups_ply(
    files: &[PathBuf],
    layout: Layout,
    out: &Path,
) -> Result<(u64, u64), String> {
    let mut faces = 0u64;
    let mut count = Numbering::new(layout);
    for f in files {
        let (mesh, border) = weld(f, layout).map_err(|e| e.to_string())?;
        count
            .block(&mesh, &border, |_| Ok(()))
            .map_err(|e| format!("{}: {e}", out.display()))?;
        faces += mesh.faces.len() as u64;
    }
    let vertices = count.next;
    drop(count);
    lodkit_mesh::io::write_atomic_with(out, |file| {
        let mut w = BufWriter::with_capacity(1 << 20, file);
        let mut props = String::from("property float x\nproperty float y\nproperty float z\n");
        if layout.normals {
            props.push_str("property float nx\nproperty float ny\nproperty float nz\n");
        }
        if layout.colors {
            props.push_str(
                "property uchar red\nproperty uchar green\nproperty uchar blue\nproperty uchar alpha\n",
            );
        }
        if layout.uvs {
            props.push_str("property float u\nproperty float v\n");
        }
        write!(
            w,
            "ply\nformat binary_little_endian 1.0\ncomment lodkit out-of-core level\n\
             element vertex {vertices}\n{props}\
             element face {faces}\nproperty list uchar uint vertex_indices\nend_header\n"
        )?;
        let mut numbering = Numbering::new(layout);
        for f in files {
            let (mesh, border) = weld(f, layout)?;
            numbering.block(&mesh, &border, |c| {
                let mut rec = Vec::with_capacity(36);
                for x in c.position.to_array() {
                    rec.extend_from_slice(&x.to_le_bytes());
                }
                if layout.normals {
                    for x in c.normal.to_array() {
                        rec.extend_from_slice(&x.to_le_bytes());
                    }
                }
                if layout.colors {
                    rec.extend_from_slice(&c.color);
                }
                if layout.uvs {
                    for x in c.uv.to_array() {
                        rec.extend_from_slice(&x.to_le_bytes());
                    }
                }
                w.write_all(&rec)
            })?;
        }
        let mut numbering = Numbering::new(layout);
        for f in files {
            let (mesh, border) = weld(f, layout)?;
            let global = numbering.block(&mesh, &border, |_| Ok(()))?;
            for t in &mesh.faces {
                let mut rec = [3u8; 13];
                for (k, &i) in t.iter().enumerate() {
                    rec[1 + 4 * k..5 + 4 * k].copy_from_slice(&global[i as usize].to_le_bytes());
                }
                w.write_all(&rec)?;
            }
        }
        w.flush()
    })
    .map_err(|e| format!("{}: {e}", out.display()))?;
    Ok((faces, vertices))
}
