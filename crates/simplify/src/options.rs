//! Every knob of the simplifier in one place, with its default and why.
//!
//! The paper (HQMS §4) has two parameters: the output face count (`goal`)
//! and the RS-heap size. Everything else here is what users of a discrete
//! LOD tool need beyond the paper: an error bound, border locking,
//! hole-filling control, attribute weights and component pruning.

/// How far to simplify.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Target {
    /// Stop at this many triangles or fewer (the paper's `goal`).
    Faces(usize),
    /// Stop at `ratio × input triangles` (rounded down), `0 ≤ ratio ≤ 1`.
    Ratio(f32),
}

impl Target {
    /// The face budget for an input of `input_faces` triangles.
    pub fn faces(self, input_faces: usize) -> usize {
        match self {
            Target::Faces(n) => n,
            Target::Ratio(r) => {
                let r = if r.is_finite() {
                    r.clamp(0.0, 1.0)
                } else {
                    1.0
                };
                (input_faces as f64 * r as f64).floor() as usize
            }
        }
    }
}

/// Weights of the vertex attributes in the collapse cost (the attribute part
/// of Garland–Heckbert 1998 / Hoppe 1999 extended quadrics). Attribute
/// coordinates are multiplied by `weight × extent` (the largest side of the
/// input's bounding box), so a weight means the same on a 1 mm part and on
/// a 100 m terrain. `0` ignores that attribute in the cost (it is still
/// interpolated). Attributes the mesh does not have are ignored.
#[derive(Debug, Clone, Copy, PartialEq)]
#[cfg_attr(
    feature = "serde",
    derive(serde::Serialize, serde::Deserialize),
    serde(deny_unknown_fields)
)]
pub struct AttributeWeights {
    /// Unit normals (components in [-1, 1]).
    pub normal: f32,
    /// RGBA colours, each channel scaled to [0, 1].
    pub color: f32,
    /// Texture coordinates (one UV unit = the whole texture).
    pub uv: f32,
}

impl AttributeWeights {
    /// A normal difference of 1 (60°) costs like a 5% extent offset; a full
    /// colour swing like 5%; one whole UV unit like 10%, so a chart boundary
    /// slides before geometry is lost but not for free.
    pub const DEFAULT: AttributeWeights = AttributeWeights {
        normal: 0.05,
        color: 0.05,
        uv: 0.1,
    };
    /// Geometry only.
    pub const NONE: AttributeWeights = AttributeWeights {
        normal: 0.0,
        color: 0.0,
        uv: 0.0,
    };
}

impl Default for AttributeWeights {
    fn default() -> Self {
        Self::DEFAULT
    }
}

/// Options of [`simplify`](crate::simplify) and [`lod_chain`](crate::lod_chain).
#[derive(Debug, Clone, PartialEq)]
pub struct Options {
    /// Face budget. Default: half the input.
    pub target: Target,
    /// Stop before any collapse whose estimated object-space error (the
    /// distance, accumulated over collapses and levels, between the new
    /// surface and the input) would exceed this. `None`: no bound.
    pub max_error: Option<f32>,
    /// Keep border vertices (edges with one face) where they are: for
    /// crack-free parts and material subsets.
    pub lock_border: bool,
    /// The paper's hole filling (§4.3.2): rings on a border are forced to
    /// collapse along a border edge, and two border edges may merge, so
    /// small holes close. `false` keeps every border loop (terrain rims).
    pub fill_holes: bool,
    /// Records in the replacement-selection heap (§3.5); the paper uses
    /// 512 and also shows 1,023 (our default is 1: no heap, see
    /// [`DEFAULT_HEAP_SIZE`](Self::DEFAULT_HEAP_SIZE)). More = closer to a
    /// global greedy order, but more records whose target goes dirty while
    /// they wait.
    pub heap_size: usize,
    /// Attribute weights in the cost.
    pub weights: AttributeWeights,
    /// Remove connected components whose bounding-box diagonal is below
    /// this fraction of the whole mesh's diagonal before simplifying
    /// (scanner debris). `None`: keep everything.
    pub prune: Option<f32>,
    /// Safety stop: at most this many passes per call.
    pub max_passes: u32,
}

impl Options {
    /// Departure: the paper's heap holds 512 records (§5). A record then
    /// waits about 512 ring costings before it comes out, and in that time
    /// its target often becomes dirty (a dependency rejection, re-costed).
    /// Since each pass admits only records under its error threshold
    /// (`pass.rs`), that threshold already orders the collapses globally,
    /// and the heap's local order does not lower the errors (`lodkit bench
    /// simplify` keeps them below meshoptimizer's with one record). A
    /// one-record heap cannot reorder anything, so the pass collapses each
    /// admitted record as soon as it is costed: no dependency rejections,
    /// no second costing, no heap work, and the collapse reuses the cost
    /// stage's read of the ring.
    pub const DEFAULT_HEAP_SIZE: usize = 1;
    /// Each pass halves the vertex count at best (Strategy I, eq. 6), so
    /// 64 passes cover any input that fits in memory many times over.
    pub const DEFAULT_MAX_PASSES: u32 = 64;

    /// Half the input, no error bound, borders free, holes filled, the
    /// default heap and attribute weights, no pruning.
    pub const DEFAULT: Options = Options {
        target: Target::Ratio(0.5),
        max_error: None,
        lock_border: false,
        fill_holes: true,
        heap_size: Self::DEFAULT_HEAP_SIZE,
        weights: AttributeWeights::DEFAULT,
        prune: None,
        max_passes: Self::DEFAULT_MAX_PASSES,
    };

    /// Defaults with a face budget.
    pub fn faces(n: usize) -> Options {
        Options {
            target: Target::Faces(n),
            ..Self::DEFAULT
        }
    }

    /// Defaults with a ratio of the input's faces.
    pub fn ratio(r: f32) -> Options {
        Options {
            target: Target::Ratio(r),
            ..Self::DEFAULT
        }
    }
}

impl Default for Options {
    fn default() -> Self {
        Self::DEFAULT
    }
}
