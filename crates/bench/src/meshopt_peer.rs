//! meshoptimizer, the peer of `lodkit-bench simplify`, behind the `peers`
//! feature (it compiles meshoptimizer's C++). Without the feature this
//! module is absent and [`crate::PEERS`] is false.

use std::alloc::Layout;

use lodkit_mesh::TriMesh;

// meshoptimizer's temporary allocations, routed through Rust's global
// allocator (so `CountingAlloc` sees them). A 16-byte header keeps the size
// for `dealloc`.
const HEADER: usize = 16;

unsafe extern "C" fn meshopt_alloc(size: usize) -> *mut std::ffi::c_void {
    let Ok(layout) = Layout::from_size_align(size + HEADER, HEADER) else {
        return std::ptr::null_mut();
    };
    // SAFETY: the layout has a non-zero size (≥ HEADER).
    let base = unsafe { std::alloc::alloc(layout) };
    if base.is_null() {
        return std::ptr::null_mut();
    }
    // SAFETY: `base` is valid for `size + HEADER` bytes and 16-aligned, so
    // the header write and the offset pointer stay inside the block.
    unsafe {
        (base as *mut usize).write(size);
        base.add(HEADER) as *mut std::ffi::c_void
    }
}

unsafe extern "C" fn meshopt_dealloc(p: *mut std::ffi::c_void) {
    if p.is_null() {
        return;
    }
    // SAFETY: `p` came from `meshopt_alloc`, so the block starts HEADER
    // bytes earlier and holds its size there, and was allocated with this
    // layout.
    unsafe {
        let base = (p as *mut u8).sub(HEADER);
        let size = (base as *const usize).read();
        std::alloc::dealloc(
            base,
            Layout::from_size_align_unchecked(size + HEADER, HEADER),
        );
    }
}

/// Routes meshopt's temporary allocations through Rust's global allocator.
pub fn route_meshopt_allocations() {
    // SAFETY: called before any other meshopt function in this process
    // (and again only with the same callbacks); the callbacks follow the
    // malloc/free contract meshopt expects.
    unsafe { meshopt::ffi::meshopt_setAllocator(Some(meshopt_alloc), Some(meshopt_dealloc)) };
}

/// meshopt_simplify on a `TriMesh`: returns the output as a `TriMesh` over
/// the input's vertices (the vertex array is shared, not simplified —
/// meshopt returns indices only).
pub fn meshopt_simplify(mesh: &TriMesh, positions_bytes: &[u8], target_faces: usize) -> Vec<u32> {
    let adapter = meshopt::VertexDataAdapter::new(positions_bytes, 12, 0)
        .expect("12-byte stride over 12-byte positions");
    let indices: &[u32] = mesh.faces.as_flattened();
    meshopt::simplify(
        indices,
        &adapter,
        target_faces * 3,
        1.0,
        meshopt::SimplifyOptions::None,
        None,
    )
}
