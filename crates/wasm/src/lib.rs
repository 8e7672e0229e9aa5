//! lodkit's decoders for the browser: the `.pop` progressive stream and the
//! `.mco` continuous model, behind plain `extern "C"` exports for
//! `wasm32-unknown-unknown`. No wasm-bindgen: the JavaScript side
//! (`web/src/worker.js`) instantiates the module with no imports and reads
//! results straight out of its `memory`.
//!
//! # The ABI
//!
//! All sizes are in bytes or elements as named; pointers are offsets into
//! the module's memory. Every object is a *handle* (a `u32`, never 0).
//!
//! * `lk_alloc(len) -> ptr` / `lk_free(ptr, len)`: scratch buffers for
//!   passing bytes in (`lk_alloc(0)` returns a dangling, non-null pointer).
//! * `lk_error_ptr()` / `lk_error_len()`: the UTF-8 message of the last
//!   call that returned a failure (`0` handle or a negative count).
//! * `.pop`: `lk_pop_new() -> h`; `lk_pop_push(h, len) -> ptr` grows the
//!   stream by `len` bytes and returns where to write them;
//!   `lk_pop_usable(h)` decodes the chunks received since the last call
//!   (each chunk once) and returns the bytes usable now; `lk_pop_decode(h)
//!   -> levels` does the same and takes a copy of the usable levels for
//!   `lk_pop_mesh` when they grew, `-1` on a damaged stream;
//!   `lk_pop_depth`, `lk_pop_precision`, `lk_pop_bytes_used` describe the
//!   decoded prefix; `lk_pop_mesh(h, level) -> triangles` triangulates and
//!   orients a decoded level into the handle's mesh.
//! * `.mco`: `lk_mco_open(ptr, len) -> h` loads a whole file (the bytes are
//!   copied; free them after); `lk_mco_vertices(h) -> vertices` puts the
//!   model's whole vertex buffer in the handle's mesh (every cut indexes
//!   into it); `lk_mco_extract_lod`, `lk_mco_extract_triangles` and
//!   `lk_mco_extract_view` replace the mesh's index buffer and return the
//!   LOD number (or the expanded node count for a view); `lk_mco_max_lod`,
//!   `lk_mco_full_triangles`, `lk_mco_bounds(h) -> ptr to 6 f32`.
//!   Streamed (version 2): `lk_mco_stream_new() -> h`;
//!   `lk_mco_stream_push(h, ptr, len) -> 1|0|-1` feeds the next bytes and
//!   says whether a chunk completed (the model then serves more LOD
//!   numbers: re-read the vertices, re-cut); `lk_mco_complete(h)`;
//!   `lk_mco_file_version(ptr, len)` (a version-1 file is read whole).
//!   Before a stream's first chunk the model calls return -1.
//! * The mesh of a handle: `lk_mesh_vertex_count`, `lk_mesh_positions`
//!   (f32 × 3 per vertex), `lk_mesh_normals` (f32 × 3, 0 when absent),
//!   `lk_mesh_colors` (u8 × 4, 0 when absent), `lk_mesh_index_count`,
//!   `lk_mesh_indices` (u32), `lk_mesh_digest` (see [`digest`]). The
//!   pointers stay valid until the next call on that handle; memory growth
//!   detaches JavaScript views, so views are made after each call.
//! * `lk_close(h)` frees a handle; `lk_warm_up()` runs a built-in small
//!   stream through the decoder once (call it when a worker starts).
//!
//! Cost: a stream's chunks are decoded once in all, however many reads it
//! arrives in; `lk_pop_decode` copies the decoded levels when they grew
//! (the viewer calls it once per newly completed chunk run).

pub mod engine;

use std::cell::RefCell;

use engine::{Camera, MeshOut, PopPrefix, PopStream};
use glam::Vec3;
use lodkit_mco::{McoModel, McoStream, ViewCut};

/// FNV-1a (64 bit) over a mesh's index buffer then its positions' bit
/// patterns, little-endian: equal digests mean identical buffers. The native
/// side (`examples/digest.rs`) prints the same digest for the CLI's outputs.
pub fn digest(indices: &[u32], positions: &[Vec3]) -> u64 {
    let mut h: u64 = 0xcbf2_9ce4_8422_2325;
    let mut eat = |w: u32| {
        for b in w.to_le_bytes() {
            h ^= u64::from(b);
            h = h.wrapping_mul(0x0000_0100_0000_01b3);
        }
    };
    for &i in indices {
        eat(i);
    }
    for p in positions {
        eat(p.x.to_bits());
        eat(p.y.to_bits());
        eat(p.z.to_bits());
    }
    h
}

enum Slot {
    Pop {
        stream: Box<PopStream>,
        /// Bytes usable at the last `lk_pop_decode` (0: none yet).
        decoded_to: usize,
        prefix: Option<Box<PopPrefix>>,
        mesh: MeshOut,
    },
    Mco {
        /// `None` until a streamed file's first chunk is in.
        model: Option<Box<McoModel>>,
        /// The reader of a file opened with `lk_mco_stream_new`.
        stream: Option<Box<McoStream>>,
        mesh: MeshOut,
        bounds: [f32; 6],
        /// The view-dependent cut's scratch state, kept between frames.
        cut: Box<ViewCut>,
        /// The last cut was a view cut: the index buffer is the cut
        /// state's own ([`ViewCut::indices`], kept there for the next cut
        /// to copy from, so not copied again), not `mesh.indices`.
        view_cut: bool,
    },
}

impl Slot {
    fn mesh(&self) -> &MeshOut {
        match self {
            Slot::Pop { mesh, .. } | Slot::Mco { mesh, .. } => mesh,
        }
    }

    /// The index buffer of the handle's mesh.
    fn indices(&self) -> &[u32] {
        match self {
            Slot::Mco {
                cut,
                view_cut: true,
                ..
            } => cut.indices(),
            _ => &self.mesh().indices,
        }
    }
}

#[derive(Default)]
struct State {
    slots: Vec<Option<Slot>>,
    error: String,
}

thread_local! {
    // wasm32-unknown-unknown runs on one thread: this is the module's state.
    static STATE: RefCell<State> = RefCell::new(State::default());
}

fn with_state<T>(f: impl FnOnce(&mut State) -> T) -> T {
    STATE.with(|s| f(&mut s.borrow_mut()))
}

fn insert(slot: Slot) -> u32 {
    with_state(|s| {
        if let Some(i) = s.slots.iter().position(Option::is_none) {
            s.slots[i] = Some(slot);
            i as u32 + 1
        } else {
            s.slots.push(Some(slot));
            s.slots.len() as u32
        }
    })
}

fn fail(msg: impl Into<String>) {
    with_state(|s| s.error = msg.into());
}

/// An export's return value from a slot call: the count on success, -1
/// with the error message recorded on failure, -1 for a closed handle
/// (whose message `with_slot` recorded).
fn status(r: Option<Result<i32, String>>) -> i32 {
    match r {
        Some(Ok(n)) => n,
        Some(Err(e)) => {
            fail(e);
            -1
        }
        None => -1,
    }
}

/// Runs `f` on handle `h`'s slot; `None` (and an error message) when the
/// handle is not open.
fn with_slot<T>(h: u32, f: impl FnOnce(&mut Slot) -> T) -> Option<T> {
    let r = with_state(|s| {
        s.slots
            .get_mut((h as usize).wrapping_sub(1))
            .and_then(Option::as_mut)
            .map(f)
    });
    if r.is_none() {
        fail(format!("handle {h} is not open"));
    }
    r
}

/// Allocates `len` bytes (alignment 8) for the caller to fill.
#[unsafe(no_mangle)]
pub extern "C" fn lk_alloc(len: usize) -> *mut u8 {
    let mut v: Vec<u64> = Vec::with_capacity(len.div_ceil(8));
    let p = v.as_mut_ptr().cast::<u8>();
    std::mem::forget(v);
    p
}

/// Frees a buffer from [`lk_alloc`] of the same `len`.
///
/// # Safety
/// `ptr` must come from `lk_alloc(len)` and not be freed twice.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn lk_free(ptr: *mut u8, len: usize) {
    if !ptr.is_null() {
        let cap = len.div_ceil(8);
        // SAFETY: the caller passes back what lk_alloc(len) returned.
        drop(unsafe { Vec::<u64>::from_raw_parts(ptr.cast::<u64>(), 0, cap) });
    }
}

#[unsafe(no_mangle)]
pub extern "C" fn lk_error_ptr() -> *const u8 {
    STATE.with(|s| s.borrow().error.as_ptr())
}

#[unsafe(no_mangle)]
pub extern "C" fn lk_error_len() -> usize {
    STATE.with(|s| s.borrow().error.len())
}

#[unsafe(no_mangle)]
pub extern "C" fn lk_close(h: u32) {
    with_state(|s| {
        if let Some(slot) = s.slots.get_mut((h as usize).wrapping_sub(1)) {
            *slot = None;
        }
    });
}

// ---- .pop -----------------------------------------------------------------

/// A small stream (a 2,000-triangle blob, `R = 5`) run through decode and
/// triangulation once when a worker starts, so that the engine has compiled
/// those functions before the first real level arrives.
const WARM_UP_STREAM: &[u8] = include_bytes!("warm_up.pop");

/// Decodes and triangulates [`WARM_UP_STREAM`]; returns its triangle count
/// (-1 if that failed, which would be a bug).
#[unsafe(no_mangle)]
pub extern "C" fn lk_warm_up() -> i32 {
    let run = || -> Result<usize, String> {
        let p = engine::pop_decode_prefix(WARM_UP_STREAM)?.ok_or("no level")?;
        let r = engine::pop_depth(&p.decoded);
        Ok(engine::pop_level_mesh(&p.decoded, r)?.indices.len() / 3)
    };
    match run() {
        Ok(n) => n as i32,
        Err(e) => {
            fail(e);
            -1
        }
    }
}

#[unsafe(no_mangle)]
pub extern "C" fn lk_pop_new() -> u32 {
    insert(Slot::Pop {
        stream: Box::new(engine::pop_stream_new()),
        decoded_to: 0,
        prefix: None,
        mesh: MeshOut::default(),
    })
}

/// Grows stream `h` by `len` bytes (zeroed) and returns where the caller
/// writes them; null when `h` is not a `.pop` handle.
#[unsafe(no_mangle)]
pub extern "C" fn lk_pop_push(h: u32, len: usize) -> *mut u8 {
    with_slot(h, |slot| match slot {
        Slot::Pop { stream, .. } => {
            let bytes = &mut stream.bytes;
            let at = bytes.len();
            bytes.resize(at + len, 0);
            bytes[at..].as_mut_ptr()
        }
        Slot::Mco { .. } => std::ptr::null_mut(),
    })
    .unwrap_or(std::ptr::null_mut())
}

/// Decodes the chunks of stream `h` received since the last call (each
/// chunk is decoded once) and, when they made more of the stream usable,
/// takes a new copy of what is decoded for `lk_pop_mesh`. Returns the
/// number of usable levels (0: not even the first level yet), or -1 with
/// an error message.
#[unsafe(no_mangle)]
pub extern "C" fn lk_pop_decode(h: u32) -> i32 {
    let r = with_slot(h, |slot| match slot {
        Slot::Pop {
            stream,
            decoded_to,
            prefix,
            ..
        } => {
            let usable = engine::pop_stream_read(stream)?;
            if usable > *decoded_to {
                *decoded_to = usable;
                if let Some(p) = engine::pop_stream_decoded(stream)? {
                    *prefix = Some(Box::new(p));
                }
            }
            Ok(prefix.as_ref().map_or(0, |p| p.levels) as i32)
        }
        Slot::Mco { .. } => Err("not a .pop handle".to_string()),
    });
    status(r)
}

fn pop_query(h: u32, f: impl FnOnce(&PopPrefix) -> usize) -> i32 {
    with_slot(h, |slot| match slot {
        Slot::Pop {
            prefix: Some(p), ..
        } => f(p) as i32,
        _ => -1,
    })
    .unwrap_or(-1)
}

/// Decodes the chunks of stream `h` received since the last call and
/// returns the bytes usable now (the end of its last usable chunk: never
/// between a level chunk and its attribute chunk), -1 on a damaged stream.
/// The worker calls `lk_pop_decode` only when this grew.
#[unsafe(no_mangle)]
pub extern "C" fn lk_pop_usable(h: u32) -> i32 {
    let r = with_slot(h, |slot| match slot {
        Slot::Pop { stream, .. } => engine::pop_stream_read(stream),
        Slot::Mco { .. } => Err("not a .pop handle".to_string()),
    });
    status(r.map(|r| r.map(|n| n as i32)))
}

/// Octree depth `R` (the finest level's number), -1 before the first level.
#[unsafe(no_mangle)]
pub extern "C" fn lk_pop_depth(h: u32) -> i32 {
    pop_query(h, |p| engine::pop_depth(&p.decoded) as usize)
}

/// Bits of precision of the decoded positions, -1 before the first level.
#[unsafe(no_mangle)]
pub extern "C" fn lk_pop_precision(h: u32) -> i32 {
    pop_query(h, |p| engine::pop_precision(&p.decoded) as usize)
}

/// Stream bytes the last decode used.
#[unsafe(no_mangle)]
pub extern "C" fn lk_pop_bytes_used(h: u32) -> i32 {
    pop_query(h, |p| p.bytes_used)
}

/// Triangulates and orients decoded level `level` into the handle's mesh;
/// returns its triangle count, -1 with an error message.
#[unsafe(no_mangle)]
pub extern "C" fn lk_pop_mesh(h: u32, level: u32) -> i32 {
    let r = with_slot(h, |slot| match slot {
        Slot::Pop {
            prefix: Some(p),
            mesh,
            ..
        } => {
            if level as usize >= p.levels {
                return Err(format!(
                    "level {level} has not arrived ({} levels)",
                    p.levels
                ));
            }
            let level = level as u8;
            *mesh = engine::pop_level_mesh(&p.decoded, level)?;
            Ok((mesh.indices.len() / 3) as i32)
        }
        Slot::Pop { .. } => Err("no level decoded yet".to_string()),
        Slot::Mco { .. } => Err("not a .pop handle".to_string()),
    });
    status(r)
}

// ---- .mco -----------------------------------------------------------------

/// Loads a whole `.mco` file from `len` bytes at `ptr`; returns a handle,
/// 0 with an error message.
///
/// # Safety
/// `ptr..ptr + len` must be readable (a buffer from [`lk_alloc`]).
#[unsafe(no_mangle)]
pub unsafe extern "C" fn lk_mco_open(ptr: *const u8, len: usize) -> u32 {
    let bytes = if len == 0 {
        &[][..]
    } else {
        // SAFETY: the caller passes a buffer of `len` bytes it wrote.
        unsafe { std::slice::from_raw_parts(ptr, len) }
    };
    match engine::mco_load(bytes) {
        Ok(model) => insert(Slot::Mco {
            bounds: bounds_of(&model),
            model: Some(Box::new(model)),
            stream: None,
            mesh: MeshOut::default(),
            cut: Box::default(),
            view_cut: false,
        }),
        Err(e) => {
            fail(e);
            0
        }
    }
}

fn bounds_of(m: &McoModel) -> [f32; 6] {
    let (lo, hi) = engine::mco_bounds(m);
    [lo.x, lo.y, lo.z, hi.x, hi.y, hi.z]
}

/// A `.mco` handle that reads the file as it arrives (version 2); no model
/// until its first chunk is in ([`lk_mco_stream_push`]).
#[unsafe(no_mangle)]
pub extern "C" fn lk_mco_stream_new() -> u32 {
    insert(Slot::Mco {
        model: None,
        stream: Some(Box::new(engine::mco_stream_new())),
        mesh: MeshOut::default(),
        bounds: [0.0; 6],
        cut: Box::default(),
        view_cut: false,
    })
}

/// Feeds the next `len` bytes of the file (at `ptr`) to stream `h`.
/// Returns 1 when they completed a chunk (the handle's model now serves
/// more LOD numbers: re-read its vertices and re-cut), 0 when not, -1 with
/// an error message (a bad header or chunk; the stream stays failed).
///
/// # Safety
/// `ptr..ptr + len` must be readable (a buffer from [`lk_alloc`]).
#[unsafe(no_mangle)]
pub unsafe extern "C" fn lk_mco_stream_push(h: u32, ptr: *const u8, len: usize) -> i32 {
    let bytes = if len == 0 {
        &[][..]
    } else {
        // SAFETY: the caller passes a buffer of `len` bytes it wrote.
        unsafe { std::slice::from_raw_parts(ptr, len) }
    };
    let r = with_slot(h, |slot| match slot {
        Slot::Mco {
            model,
            stream: Some(s),
            bounds,
            ..
        } => {
            let Some(m) = engine::mco_stream_push(s, bytes)? else {
                return Ok(0);
            };
            *bounds = bounds_of(&m);
            *model = Some(Box::new(m));
            Ok(1)
        }
        _ => Err("not a streamed .mco handle".to_string()),
    });
    status(r)
}

/// 1 when every chunk of stream `h` has been read (or `h` was opened
/// whole), 0 while chunks are missing, -1 when `h` is not a `.mco` handle.
#[unsafe(no_mangle)]
pub extern "C" fn lk_mco_complete(h: u32) -> i32 {
    with_slot(h, |slot| match slot {
        Slot::Mco {
            stream: Some(s), ..
        } => i32::from(engine::mco_stream_complete(s)),
        Slot::Mco { .. } => 1,
        Slot::Pop { .. } => -1,
    })
    .unwrap_or(-1)
}

/// The `.mco` version `len` bytes at `ptr` declare (1 or 2), 0 when they
/// are too short or lack the signature (a version-1 file does not stream:
/// the caller reads it whole and opens it with [`lk_mco_open`]).
///
/// # Safety
/// `ptr..ptr + len` must be readable (a buffer from [`lk_alloc`]).
#[unsafe(no_mangle)]
pub unsafe extern "C" fn lk_mco_file_version(ptr: *const u8, len: usize) -> u32 {
    if len == 0 {
        return 0;
    }
    // SAFETY: the caller passes a buffer of `len` bytes it wrote.
    let bytes = unsafe { std::slice::from_raw_parts(ptr, len) };
    engine::mco_file_version(bytes).unwrap_or(0)
}

fn mco_do(h: u32, f: impl FnOnce(&McoModel, &mut MeshOut) -> usize) -> i32 {
    with_slot(h, |slot| match slot {
        Slot::Mco {
            model: Some(model),
            mesh,
            ..
        } => f(model, mesh) as i32,
        _ => -1,
    })
    .unwrap_or(-1)
}

/// Puts the model's whole vertex buffer in the handle's mesh (indices kept);
/// returns the vertex count.
#[unsafe(no_mangle)]
pub extern "C" fn lk_mco_vertices(h: u32) -> i32 {
    mco_do(h, |m, mesh| {
        let v = engine::mco_vertices(m);
        mesh.positions = v.positions;
        mesh.normals = v.normals;
        mesh.colors = v.colors;
        mesh.positions.len()
    })
}

#[unsafe(no_mangle)]
pub extern "C" fn lk_mco_max_lod(h: u32) -> i32 {
    mco_do(h, |m, _| engine::mco_max_lod(m))
}

#[unsafe(no_mangle)]
pub extern "C" fn lk_mco_full_triangles(h: u32) -> i32 {
    mco_do(h, |m, _| engine::mco_full_triangles(m))
}

/// The model's bounding cube: min x, y, z then max x, y, z (6 f32).
#[unsafe(no_mangle)]
pub extern "C" fn lk_mco_bounds(h: u32) -> *const f32 {
    with_slot(h, |slot| match slot {
        Slot::Mco { bounds, .. } => bounds.as_ptr(),
        Slot::Pop { .. } => std::ptr::null(),
    })
    .unwrap_or(std::ptr::null())
}

/// Index buffer at LOD number `k` (clamped); returns the LOD number used.
#[unsafe(no_mangle)]
pub extern "C" fn lk_mco_extract_lod(h: u32, k: u32) -> i32 {
    mco_cut(h, |m, indices| {
        engine::mco_extract_lod(m, k as usize, indices)
    })
}

/// Index buffer closest to `triangles` triangles; returns the LOD number.
#[unsafe(no_mangle)]
pub extern "C" fn lk_mco_extract_triangles(h: u32, triangles: u32) -> i32 {
    mco_cut(h, |m, indices| {
        engine::mco_extract_triangles(m, triangles as usize, indices)
    })
}

/// A cut by LOD number into the handle's `mesh.indices` (no longer the
/// view cut's buffer).
fn mco_cut(h: u32, f: impl FnOnce(&McoModel, &mut Vec<u32>) -> usize) -> i32 {
    with_slot(h, |slot| match slot {
        Slot::Mco {
            model: Some(model),
            mesh,
            view_cut,
            ..
        } => {
            *view_cut = false;
            f(model, &mut mesh.indices) as i32
        }
        _ => -1,
    })
    .unwrap_or(-1)
}

/// View-dependent index buffer: camera at `p`, looking along `d`, up hint
/// `u`, vertical field of view `vfov_deg`, viewport `viewport_h` pixels
/// high and `aspect` = width / height; nodes whose projected error exceeds
/// `tolerance_px` pixels are refined. Returns the expanded node count.
#[unsafe(no_mangle)]
#[allow(clippy::too_many_arguments)]
pub extern "C" fn lk_mco_extract_view(
    h: u32,
    px: f32,
    py: f32,
    pz: f32,
    dx: f32,
    dy: f32,
    dz: f32,
    ux: f32,
    uy: f32,
    uz: f32,
    vfov_deg: f32,
    viewport_h: f32,
    aspect: f32,
    tolerance_px: f32,
) -> i32 {
    let v = Camera {
        position: Vec3::new(px, py, pz),
        direction: Vec3::new(dx, dy, dz),
        up: Vec3::new(ux, uy, uz),
        vfov_deg,
        viewport_height: viewport_h,
        aspect,
    };
    // Non-finite or non-positive camera values would make the selection
    // meaningless; clamp the tolerance instead of trusting the caller.
    let tol = if tolerance_px.is_finite() && tolerance_px > 0.0 {
        tolerance_px
    } else {
        1.0
    };
    with_slot(h, |slot| match slot {
        Slot::Mco {
            model: Some(model),
            cut,
            view_cut,
            ..
        } => {
            *view_cut = true;
            engine::mco_extract_view(model, cut, &v, tol) as i32
        }
        _ => -1,
    })
    .unwrap_or(-1)
}

// ---- meshes ---------------------------------------------------------------

fn mesh_query<T>(h: u32, none: T, f: impl FnOnce(&MeshOut) -> T) -> T {
    with_slot(h, |slot| f(slot.mesh())).unwrap_or(none)
}

#[unsafe(no_mangle)]
pub extern "C" fn lk_mesh_vertex_count(h: u32) -> u32 {
    mesh_query(h, 0, |m| m.positions.len() as u32)
}

#[unsafe(no_mangle)]
pub extern "C" fn lk_mesh_positions(h: u32) -> *const f32 {
    mesh_query(h, std::ptr::null(), |m| m.positions.as_ptr().cast())
}

#[unsafe(no_mangle)]
pub extern "C" fn lk_mesh_normals(h: u32) -> *const f32 {
    mesh_query(h, std::ptr::null(), |m| {
        m.normals
            .as_ref()
            .map_or(std::ptr::null(), |n| n.as_ptr().cast())
    })
}

#[unsafe(no_mangle)]
pub extern "C" fn lk_mesh_colors(h: u32) -> *const u8 {
    mesh_query(h, std::ptr::null(), |m| {
        m.colors
            .as_ref()
            .map_or(std::ptr::null(), |c| c.as_ptr().cast())
    })
}

#[unsafe(no_mangle)]
pub extern "C" fn lk_mesh_index_count(h: u32) -> u32 {
    with_slot(h, |slot| slot.indices().len() as u32).unwrap_or(0)
}

#[unsafe(no_mangle)]
pub extern "C" fn lk_mesh_indices(h: u32) -> *const u32 {
    with_slot(h, |slot| slot.indices().as_ptr()).unwrap_or(std::ptr::null())
}

/// [`digest`] of the handle's index buffer and positions.
#[unsafe(no_mangle)]
pub extern "C" fn lk_mesh_digest(h: u32) -> u64 {
    with_slot(h, |slot| digest(slot.indices(), &slot.mesh().positions)).unwrap_or(0)
}
