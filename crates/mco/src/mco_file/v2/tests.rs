use super::*;
use crate::Camera;
use crate::pipeline::{Options, build_from_mesh};

/// Largest error, per axis, of a quantised position inside the lattice box
/// (half a quantisation step), in object units: `cube / 2^(b - depth + 1)`,
/// at most `cube / 1024` (plus the `f32` rounding of the coordinate).
fn position_error(grid: &Grid) -> f32 {
    let b = position_bits(grid.depth);
    grid.cube / (1u64 << (b - grid.depth + 1)) as f32
}

fn build(mesh: &lodkit_mesh::TriMesh, resolution: u32) -> McoModel {
    build_from_mesh(
        mesh,
        &Options {
            resolution: Some(resolution),
        },
    )
    .unwrap()
}

fn small() -> McoModel {
    build(&lodkit_mesh::shapes::icosphere(3), 12)
}

fn sorted(idx: &[u32]) -> Vec<[u32; 3]> {
    let mut t: Vec<[u32; 3]> = idx.chunks_exact(3).map(|t| [t[0], t[1], t[2]]).collect();
    t.sort_unstable();
    t
}

fn cameras(m: &McoModel) -> Vec<(Camera, f32)> {
    let (lo, hi) = m.node_box(0);
    let (c, r) = ((lo + hi) * 0.5, (hi - lo).length());
    let mut out = Vec::new();
    for (i, d) in [Vec3::Z, Vec3::X, Vec3::new(1.0, 1.0, -1.0), Vec3::NEG_Y]
        .into_iter()
        .enumerate()
    {
        for (dist, tol) in [(0.6, 1.0), (1.5, 4.0), (4.0, 30.0), (20.0, 200.0)] {
            let cam = Camera::looking_at(
                c + d.normalize() * r * dist,
                c + Vec3::splat(0.1 * i as f32),
            );
            out.push((cam, tol));
        }
    }
    out
}

/// The whole file extracts the in-memory model's triangles (renumbered) at
/// every LOD number, budget and view; positions within the stated error.
fn check_round_trip(m: &McoModel) {
    let (bytes, map) = encode_numbered(m);
    assert_eq!(bytes, encode(m), "deterministic");
    let back = decode(&bytes).unwrap();
    let again = encode(&back);
    let diffs: Vec<usize> = (0..again.len().min(bytes.len()))
        .filter(|&i| again[i] != bytes[i])
        .take(12)
        .collect();
    let first_diff = (!diffs.is_empty()).then_some(diffs);
    assert!(
        again.len() == bytes.len() && first_diff.is_none(),
        "a read file writes back other bytes: {} vs {}, first difference at {first_diff:?}",
        again.len(),
        bytes.len()
    );
    assert_eq!(back.acc, m.acc);
    assert_eq!(back.max_lod(), m.max_lod());
    assert_eq!(back.has_colors, m.has_colors);
    let err = position_error(&m.grid);
    let extent = m.grid.origin.abs().max_element() + m.grid.cube * (1u32 << m.grid.depth) as f32;
    let slack = err + 2.0 * f32::EPSILON * extent;
    let mut worst_angle = 0f32;
    for (v, &n) in map.iter().enumerate() {
        if n == u32::MAX {
            continue;
        }
        let d = (back.vertices.positions[n as usize] - m.vertices.positions[v]).abs();
        assert!(d.max_element() <= slack, "vertex {v}: {d} > {slack}");
        let a = m.vertices.normals[v];
        if a.length() > 0.5 {
            let (a, b) = (a.normalize(), back.vertices.normals[n as usize]);
            // atan2 of sine and cosine: exact for small angles (acos is not).
            let angle = a.cross(b).length().atan2(a.dot(b));
            worst_angle = worst_angle.max(angle.to_degrees());
        }
        if m.has_colors {
            assert_eq!(back.vertices.colors[n as usize], m.vertices.colors[v]);
        }
    }
    assert!(worst_angle < 0.01, "normal error {worst_angle}°");
    let remap = |a: &[u32]| -> Vec<u32> { a.iter().map(|&v| map[v as usize]).collect() };
    let (mut a, mut b) = (Vec::new(), Vec::new());
    for k in 0..=m.max_lod() {
        m.extract_lod(k, &mut a);
        back.extract_lod(k, &mut b);
        assert!(a.iter().all(|&v| map[v as usize] != u32::MAX));
        assert_eq!(sorted(&remap(&a)), sorted(&b), "LOD {k}");
        back.extract_lod_traversal(k, &mut a);
        assert_eq!(sorted(&a), sorted(&b), "LOD {k}, traversal");
    }
    let full = m.full_triangles();
    for t in [0, 1, 10, 100, full / 3, full / 2, full, 10 * full] {
        let ka = m.extract_triangles(t, &mut a);
        let kb = back.extract_triangles(t, &mut b);
        assert_eq!(ka, kb, "budget {t}");
        assert_eq!(sorted(&remap(&a)), sorted(&b), "budget {t}");
    }
    for (cam, tol) in cameras(m) {
        let na = m.extract_view(&cam, tol, &mut a);
        let nb = back.extract_view(&cam, tol, &mut b);
        assert_eq!(na, nb);
        assert_eq!(sorted(&remap(&a)), sorted(&b), "view {cam:?} {tol}");
    }
}

#[test]
fn round_trip_gives_the_same_triangles() {
    check_round_trip(&small());
    check_round_trip(&build(&lodkit_mesh::shapes::torus(1.0, 0.3, 48, 24), 30));
}

#[test]
fn colours_are_kept_when_meaningful() {
    let mut mesh = lodkit_mesh::shapes::icosphere(3);
    mesh.colors = Some(
        (0..mesh.positions.len())
            .map(|i| [(i * 7) as u8, (i * 13) as u8, 200, 255])
            .collect(),
    );
    let m = build(&mesh, 12);
    assert!(m.has_colors);
    check_round_trip(&m);
    let plain = small();
    let with = encode(&m).len() as f64;
    assert!(with > encode(&plain).len() as f64, "colours cost bytes");
}

#[test]
fn every_prefix_serves_the_lod_numbers_it_claims() {
    let m = build(&lodkit_mesh::shapes::torus(1.0, 0.3, 64, 32), 48);
    let bytes = encode(&m);
    let full = decode(&bytes).unwrap();
    let table = chunk_table(&bytes).unwrap();
    assert!(table.len() >= 3, "{} chunks", table.len());
    assert_eq!(table[0].offset, HEADER_BYTES as u64);
    assert_eq!(table[0].first_lod, 0);
    assert!(
        table[0].bytes <= 2 * FIRST_CHUNK_BYTES as u64,
        "{:?}",
        table[0]
    );
    for w in table.windows(2) {
        assert_eq!(w[1].offset, w[0].offset + w[0].bytes);
        assert_eq!(w[1].first_lod, w[0].last_lod + 1);
    }
    for (c, ch) in table.iter().enumerate().take(table.len() - 1) {
        let target = (FIRST_CHUNK_BYTES << c).min(MAX_CHUNK_TARGET) as u64;
        assert!(ch.payload_bytes >= target, "chunk {c}: {ch:?}");
    }
    let last = table.last().unwrap();
    assert_eq!(last.offset + last.bytes, bytes.len() as u64);
    assert_eq!(last.last_lod as usize, full.max_lod());
    let (mut a, mut b) = (Vec::new(), Vec::new());
    let mut views_compared = 0;
    for (c, ch) in table.iter().enumerate() {
        let end = (ch.offset + ch.bytes) as usize;
        let p = decode_prefix(&bytes[..end]).unwrap();
        assert_eq!(p.max_lod, ch.last_lod as usize);
        assert_eq!(p.chunks, c + 1);
        assert_eq!(p.complete, c + 1 == table.len());
        let step = (p.max_lod / 60).max(1);
        for k in (0..=p.max_lod).step_by(step).chain([p.max_lod]) {
            full.extract_lod(k, &mut a);
            p.model.extract_lod(k, &mut b);
            assert_eq!(sorted(&a), sorted(&b), "chunk {c}, LOD {k}");
            assert_eq!(p.model.acc[k], full.acc[k]);
        }
        // By budget: the closest LOD number among those served.
        for t in [1, 50, 500, 5000] {
            let k = p.model.extract_triangles(t, &mut b);
            assert!(k <= p.max_lod);
            full.extract_lod(k, &mut a);
            assert_eq!(sorted(&a), sorted(&b));
        }
        // A view cut that expands only served LOD numbers is the whole
        // file's cut.
        for (cam, tol) in cameras(&full) {
            let flags = crate::view_dependent_cut::select(&full, &cam, tol);
            let top = (0..full.nodes.len())
                .filter(|&n| flags[n])
                .map(|n| full.prio[n])
                .max()
                .unwrap_or(0);
            if top as usize <= p.max_lod {
                full.extract_view(&cam, tol, &mut a);
                p.model.extract_view(&cam, tol, &mut b);
                assert_eq!(sorted(&a), sorted(&b), "chunk {c}, view");
                views_compared += (c + 1 < table.len()) as usize;
            } else {
                // Otherwise it still draws a valid cut of what is served.
                p.model.extract_view(&cam, tol, &mut b);
                assert!(!b.is_empty() || full.acc.iter().all(|&x| x == 0));
            }
        }
        // Cut inside the next chunk: only the complete ones count.
        if let Some(next) = table.get(c + 1) {
            for cut in [
                end + 1,
                end + 8,
                end + next.bytes as usize / 2,
                end + next.bytes as usize - 1,
            ] {
                let q = decode_prefix(&bytes[..cut]).unwrap();
                assert_eq!(q.max_lod, p.max_lod);
                assert!(!q.complete);
            }
        }
    }
    assert!(views_compared > 0);
    // Streamed in small pieces: a model after each chunk, then the whole.
    let mut s = McoStream::new();
    let mut seen = Vec::new();
    for piece in bytes.chunks(777) {
        if s.push(piece).unwrap() {
            seen.push(s.max_lod().unwrap());
        }
    }
    assert!(s.is_complete());
    assert_eq!(s.bytes_read(), bytes.len() as u64);
    assert_eq!(seen.last(), Some(&full.max_lod()));
    assert!(seen.windows(2).all(|w| w[0] < w[1]));
    assert_eq!(s.model().unwrap(), full);
    assert!(
        s.push(&[0])
            .unwrap_err()
            .to_string()
            .contains("after the last chunk")
    );
    // The header alone serves nothing yet.
    assert!(
        decode_prefix(&bytes[..HEADER_BYTES + 3])
            .unwrap_err()
            .to_string()
            .contains("no complete chunk")
    );
    assert!(decode_prefix(&bytes[..50]).unwrap_err().contains("shorter"));
}

#[test]
fn errors_are_one_line_and_version_1_still_reads() {
    let m = small();
    let v1 = crate::mco_file::v1::encode(&m);
    assert_eq!(crate::mco_file::decode(&v1).unwrap(), m);
    let bytes = encode(&m);
    assert_eq!(
        crate::mco_file::decode(&bytes).unwrap(),
        decode(&bytes).unwrap()
    );
    assert_eq!(file_version(&bytes), Some(2));
    assert_eq!(file_version(&v1), Some(1));
    for cut in [
        0,
        7,
        12,
        HEADER_BYTES - 1,
        HEADER_BYTES,
        bytes.len() / 2,
        bytes.len() - 1,
    ] {
        let e = crate::mco_file::decode(&bytes[..cut]).unwrap_err();
        assert!(!e.contains('\n'));
        assert!(
            e.contains("shorter") || e.contains("size mismatch"),
            "{cut}: {e}"
        );
    }
    let mut v3 = bytes.clone();
    v3[8] = 3;
    let e = crate::mco_file::decode(&v3).unwrap_err();
    assert!(e.contains("version 3"), "{e}");
    assert!(
        McoStream::new()
            .push(&v3[..20])
            .unwrap_err()
            .to_string()
            .contains("version 3")
    );
    let e = crate::mco_file::decode(&v3[..20]).unwrap_err();
    assert!(e.contains("version 3"), "{e}");
    let mut flipped = bytes.clone();
    flipped[HEADER_BYTES + 20] ^= 0x10;
    assert!(decode(&flipped).unwrap_err().contains("checksum"));
    let mut head = bytes.clone();
    head[40] ^= 1;
    assert!(decode(&head).unwrap_err().contains("header checksum"));
    let mut sig = bytes.clone();
    sig[0] = b'X';
    assert!(
        McoStream::new()
            .push(&sig)
            .unwrap_err()
            .to_string()
            .contains("signature")
    );
    let mut padded = bytes.clone();
    padded.push(0);
    assert!(decode(&padded).unwrap_err().contains("size mismatch"));
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("cut.mco");
    std::fs::write(&path, &bytes[..bytes.len() - 3]).unwrap();
    let msg = McoModel::load(&path).unwrap_err().to_string();
    assert!(
        msg.starts_with(&path.display().to_string()) && !msg.contains('\n'),
        "{msg}"
    );
}

/// Rewrites the header's and every chunk's checksum so that mutations
/// reach the structural checks.
fn fix_checksums(b: &mut [u8]) {
    if b.len() < HEADER_BYTES {
        return;
    }
    let crc = crc32fast::hash(&b[..HEADER_BYTES - 4]);
    b[HEADER_BYTES - 4..HEADER_BYTES].copy_from_slice(&crc.to_le_bytes());
    let mut at = HEADER_BYTES;
    while at + CHUNK_HEAD_BYTES <= b.len() {
        let len = le32(b, at) as usize;
        let Some(end) = (at + CHUNK_HEAD_BYTES)
            .checked_add(len)
            .filter(|&e| e <= b.len())
        else {
            break;
        };
        let crc = crc32fast::hash(&b[at + CHUNK_HEAD_BYTES..end]);
        b[at + 4..at + 8].copy_from_slice(&crc.to_le_bytes());
        at = end;
    }
}

/// Mutated files (checksums fixed up) never panic, and whatever they
/// decode to extracts safely, by LOD number, budget and view, whole or as
/// a prefix.
#[test]
fn mutated_files_never_panic() {
    let m = small();
    let bytes = encode(&m);
    let mut seed = 0x9e37_79b9_7f4a_7c15u64;
    let mut next = || {
        seed ^= seed << 13;
        seed ^= seed >> 7;
        seed ^= seed << 17;
        seed
    };
    let cam = Camera::looking_at(Vec3::new(0.0, 0.0, 3.0), Vec3::ZERO);
    let mut idx = Vec::new();
    let mut accepted = 0;
    for i in 0..3000 {
        let mut b = bytes.clone();
        for _ in 0..1 + next() % 4 {
            let at = (next() as usize) % b.len();
            b[at] = match next() % 4 {
                0 => b[at] ^ (1 << (next() % 8)),
                1 => b[at].wrapping_add(1),
                2 => 0xFF,
                _ => next() as u8,
            };
        }
        if i % 10 == 0 {
            b.truncate((next() as usize) % b.len());
        }
        fix_checksums(&mut b);
        let models = [decode(&b).ok(), decode_prefix(&b).ok().map(|p| p.model)];
        for back in models.into_iter().flatten() {
            accepted += 1;
            for k in [0, 1, back.max_lod() / 2, back.max_lod(), usize::MAX] {
                back.extract_lod(k, &mut idx);
                assert!(idx.len() <= back.tris.len() + 3 * back.subs.len() + 3);
                back.extract_lod_traversal(k, &mut idx);
            }
            back.extract_triangles(100, &mut idx);
            back.extract_view(&cam, 1.0, &mut idx);
            let _ = back.mesh_from_indices(&idx);
        }
    }
    assert!(accepted > 100, "{accepted} mutated files accepted");
}

#[test]
fn quantisation_error_is_at_most_a_1024th_of_a_leaf_cube() {
    for depth in 0..KEY_BITS {
        let grid = Grid {
            origin: Vec3::ZERO,
            cube: 1.0,
            depth,
            resolution: 1,
        };
        let b = position_bits(depth);
        assert!((16..=28).contains(&b));
        assert!(position_error(&grid) <= 1.0 / 1024.0);
        // Corners of the box and a leaf cube's interior round-trip.
        let p = Vec3::new(0.3, 0.7123, 0.5) * (1u32 << depth) as f32;
        let q = dequantise(&grid, b, quantise(&grid, b, p));
        assert!(
            (q - p).abs().max_element() <= position_error(&grid) * 1.001 + 1e-6 * p.max_element()
        );
    }
    for n in [
        Vec3::X,
        Vec3::NEG_Z,
        Vec3::new(0.3, -0.5, -0.8),
        Vec3::new(-1.0, 1.0, 1.0),
    ] {
        let n = n.normalize();
        let d = oct_decode(oct_encode(n));
        let angle = n.cross(d).length().atan2(n.dot(d)).to_degrees();
        assert!(angle < 0.01, "{n} → {d}: {angle}°");
    }
}

/// The file with every chunk's payload passed through `mutate` (inflated,
/// changed, deflated again) and the header's size and checksum fixed: the
/// mutations reach the record parser.
fn remutate(bytes: &[u8], mutate: &mut dyn FnMut(usize, &mut Vec<u8>)) -> Vec<u8> {
    let mut out = bytes[..HEADER_BYTES].to_vec();
    let mut at = HEADER_BYTES;
    let mut c = 0;
    while at + CHUNK_HEAD_BYTES <= bytes.len() {
        let len = le32(bytes, at) as usize;
        let stored = &bytes[at + CHUNK_HEAD_BYTES..at + CHUNK_HEAD_BYTES + len];
        let mut payload = inflate(stored, le32(bytes, at + 8)).unwrap();
        mutate(c, &mut payload);
        close_chunk(&mut out, &payload);
        at += CHUNK_HEAD_BYTES + len;
        c += 1;
    }
    let size = out.len() as u64;
    out[92..100].copy_from_slice(&size.to_le_bytes());
    fix_checksums(&mut out);
    out
}

/// Mutations of the inflated payloads: the structural checks, not the
/// checksums or the deflate stream, must refuse them or give a model that
/// extracts safely.
#[test]
fn mutated_payloads_never_panic() {
    let m = small();
    let bytes = encode(&m);
    assert_eq!(remutate(&bytes, &mut |_, _| {}), bytes);
    let chunks = chunk_table(&bytes).unwrap().len();
    let mut seed = 0x2545_f491_4f6c_dd1du64;
    let mut next = move || {
        seed ^= seed << 13;
        seed ^= seed >> 7;
        seed ^= seed << 17;
        seed
    };
    let cam = Camera::looking_at(Vec3::new(0.0, 0.0, 3.0), Vec3::ZERO);
    let mut idx = Vec::new();
    let (mut accepted, mut refused) = (0, 0);
    for _ in 0..1500 {
        let target = (next() as usize) % chunks;
        let edits: Vec<(u64, u8)> = (0..1 + next() % 3)
            .map(|_| (next(), next() as u8))
            .collect();
        let b = remutate(&bytes, &mut |c, p| {
            if c == target && !p.is_empty() {
                for &(at, v) in &edits {
                    let n = p.len();
                    p[at as usize % n] = v;
                }
            }
        });
        for r in [
            decode(&b).map(Some),
            decode_prefix(&b).map(|p| Some(p.model)),
        ] {
            match r {
                Ok(Some(back)) => {
                    accepted += 1;
                    for k in [0, 1, back.max_lod() / 2, back.max_lod(), usize::MAX] {
                        back.extract_lod(k, &mut idx);
                        back.extract_lod_traversal(k, &mut idx);
                    }
                    back.extract_triangles(100, &mut idx);
                    back.extract_view(&cam, 1.0, &mut idx);
                }
                Ok(None) => {}
                Err(e) => {
                    assert!(!e.contains('\n'));
                    refused += 1;
                }
            }
        }
    }
    assert!(
        accepted > 50 && refused > 50,
        "{accepted} accepted, {refused} refused"
    );
}

/// Positions read back bit for bit, wherever they lie: on the grid, off
/// it, outside the lattice box (clamped when quantised), signed zeros.
#[test]
fn positions_read_back_exactly() {
    for x in [0.0f32, -0.0, 1.0, -1.0, 1e-30, -3.5e7, f32::MAX, f32::MIN] {
        assert_eq!(unordered(ordered(x)).to_bits(), x.to_bits(), "{x}");
    }
    assert!(ordered(-1.0) < ordered(-0.0) && ordered(-0.0) < ordered(0.0));
    assert!(ordered(0.0) < ordered(1e-30) && ordered(1e-30) < ordered(1.0));
    let mut m = small();
    let n = m.vertices.positions.len();
    let far = m.grid.origin - Vec3::splat(1e3 * m.grid.cube);
    m.vertices.positions[n - 1] = far;
    m.vertices.positions[n - 2] += Vec3::new(1e-7, -3e-8, 0.0);
    m.vertices.positions[n - 3] = Vec3::new(-0.0, 0.0, -0.0);
    let (bytes, map) = encode_numbered(&m);
    let back = decode(&bytes).unwrap();
    for (v, &k) in map.iter().enumerate() {
        if k != u32::MAX {
            let (a, b) = (m.vertices.positions[v], back.vertices.positions[k as usize]);
            assert_eq!(
                a.to_array().map(f32::to_bits),
                b.to_array().map(f32::to_bits)
            );
        }
    }
    assert_eq!(encode(&back), bytes);
}
