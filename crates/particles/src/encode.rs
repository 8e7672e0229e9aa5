//! The encoder pipeline: octree (§4.1) → thinning (§4.3) → ordering (§4.4)
//! → attributes (§5.5) → hierarchical coding (§7.1) in the chosen bit
//! layer → precision layers (§7.2) → `.pop` chunks.
use lodkit_mesh::Model;

use crate::attributes::{self, Averaged, Channel};
use crate::coding::bit_coder::BitCoder;
use crate::coding::levels::{self as hc, LevelInput, Truth};
use crate::coding::precision_layers;
use crate::coding::range_coder::EntropyWriter;
use crate::coding::raw_bits::BitWriter;
use crate::container::{ChunkKind, Header, Mode, write_chunk, write_header};
use crate::error::{Error, Result};
use crate::octree::{BuildOptions, Octree, QBITS, Sidedness, unmorton};
use crate::ordering::Hierarchy;
use crate::thinning::{ThinningOptions, thin_choosing};

/// Default precision `N`: §7.2 finds 12 bits enough for most models.
pub const DEFAULT_PRECISION: u8 = 12;

/// Where the entropy mode puts each particle's vertex inside its leaf.
#[derive(Debug, Clone, Copy, PartialEq, Eq, serde::Serialize)]
pub enum Placement {
    /// The mean of the leaf's samples (§5.5), as the baseline always does.
    Mean,
    /// On the plane of the leaf's samples (through their mean, across
    /// their mean normal), where the leaf's middle column along the
    /// [`precision_layers::normal_axis`] the decoder infers from the
    /// neighbours meets it — or, where that crossing leaves the leaf, the
    /// quarter or eighth column under the mean. The two tangential
    /// coordinates then cost nothing, or one or two bits (see
    /// [`precision_layers::code_precision`]), and the error across the
    /// surface is the plane's. Falls back to the mean
    /// where the input has no normals, the plane is steeper than
    /// [`MIN_NORMAL_COSINE`] against that axis, or every column's crossing
    /// leaves the leaf.
    SurfaceColumn,
}

/// Smallest `|n · axis|` for which [`Placement::SurfaceColumn`] moves a
/// vertex: steeper planes would slide far along the column for a small
/// tangential move (`tan ≤ 1.73` at 0.5).
pub const MIN_NORMAL_COSINE: f32 = 0.5;

/// Options of [`encode`].
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct EncodeOptions {
    /// Octree resolution `R`; `None` picks it from the sampling density.
    pub depth: Option<u8>,
    /// Highest precision `N` coded (raised to `R` when below it, at most 16).
    pub precision: u8,
    /// How the chunks are coded.
    pub mode: Mode,
    /// §4.3 thinning of the octree before ordering.
    pub thinning: ThinningOptions,
    /// IN/OUT labelling; `None` chooses (see [`BuildOptions`]).
    pub sidedness: Option<Sidedness>,
    /// Code the input's colours when it has some.
    pub colours: bool,
    /// Code normals (§5.5); off by default, as §6.2 lets the coder drop them.
    pub normals: bool,
    /// Vertex placement of the entropy mode (the baseline codes means).
    pub placement: Placement,
}

impl EncodeOptions {
    /// Entropy mode, automatic depth, `N = 12`, inner thinning, colours
    /// kept, vertices on surface columns.
    pub const DEFAULT: EncodeOptions = EncodeOptions {
        depth: None,
        precision: DEFAULT_PRECISION,
        mode: Mode::Entropy,
        thinning: ThinningOptions::DEFAULT,
        sidedness: None,
        colours: true,
        normals: false,
        placement: Placement::SurfaceColumn,
    };
}

impl Default for EncodeOptions {
    fn default() -> Self {
        EncodeOptions::DEFAULT
    }
}

/// Per-level figures of an encoding.
#[derive(Debug, Clone, Default, PartialEq, serde::Serialize)]
pub struct LevelReport {
    /// Octree level `r`.
    pub level: u8,
    /// ON nodes after thinning, `k_r`.
    pub kept: usize,
    /// Cubes eliminated by thinning at this level.
    pub eliminated: usize,
    /// Phantom nodes, `m_r`.
    pub phantoms: usize,
    /// New particles, `n_r = |P^r|`.
    pub new_particles: usize,
    /// Bits of the structure chunk (exact for the baseline, whole bytes for
    /// the entropy mode).
    pub structure_bits: u64,
    /// Bytes of the attribute chunk payload.
    pub attribute_bytes: usize,
    /// Stream size once this level (and its attributes) is read.
    pub bytes_so_far: usize,
}

/// Figures of an encoding.
#[derive(Debug, Clone, Default, PartialEq, serde::Serialize)]
pub struct EncodeReport {
    /// Coding mode name (`baseline`, `entropy`).
    pub mode: String,
    /// Octree resolution `R`.
    pub depth: u8,
    /// Vertex precision `N` (bits per coordinate).
    pub precision: u8,
    /// Particles (ON leaves at level `R`).
    pub particles: usize,
    /// Per level, coarsest first.
    pub levels: Vec<LevelReport>,
    /// Bits of each precision layer `R+1..=N`.
    pub precision_bits: Vec<u64>,
    /// Stream size in bytes.
    pub total_bytes: usize,
    /// Level below which outer thinning was relaxed (`None`: inner
    /// thinning only, or an octree thinned before [`encode_thinned`]).
    pub relax_below: Option<u8>,
}

impl EncodeReport {
    /// Structure bits per particle at `N = R` (the §7.1 figure).
    pub fn structure_bits_per_particle(&self) -> f64 {
        let bits: u64 = self.levels.iter().map(|l| l.structure_bits).sum();
        bits as f64 / self.particles.max(1) as f64
    }
    /// The §7.1/appendix estimate `61/12 + 3(N − R)` for this stream.
    pub fn paper_estimate(&self) -> f64 {
        61.0 / 12.0 + 3.0 * f64::from(self.precision - self.depth)
    }
}

/// A `.pop` stream and its figures.
#[derive(Debug, Clone)]
pub struct Encoded {
    /// The `.pop` stream.
    pub bytes: Vec<u8>,
    /// What went into it.
    pub report: EncodeReport,
    /// The 16-bit grid vertex of every particle (stream order) as a
    /// decoder at full precision `N` reads it (bits below `N` zero).
    pub vertices: Vec<[u32; 3]>,
}

/// A bit layer that writes chunks.
trait ChunkWriter: BitCoder {
    fn open() -> Self;
    /// Payload bytes and the number of bits that count (exact for raw bits).
    fn close(self) -> (Vec<u8>, u64);
}

impl ChunkWriter for BitWriter {
    fn open() -> Self {
        BitWriter::new()
    }
    fn close(self) -> (Vec<u8>, u64) {
        let bits = self.bit_len();
        (self.finish(), bits)
    }
}

impl ChunkWriter for EntropyWriter {
    fn open() -> Self {
        EntropyWriter::new()
    }
    fn close(self) -> (Vec<u8>, u64) {
        let b = self.finish();
        let bits = b.len() as u64 * 8;
        (b, bits)
    }
}

/// Encodes a mesh, point cloud or range image as a progressive `.pop`
/// stream.
///
/// - **Input**: `model` in any units (the octree's cube is fitted around
///   it); a mesh is sampled on its faces, points and range samples are
///   used as they are. `opts`: octree depth `R` (`None`: chosen from the
///   sample count), vertex precision `N` (`R ≤ N ≤ 16` bits per
///   coordinate), coding mode, thinning, attributes.
/// - **Output**: [`Encoded::bytes`], the stream (header, then one chunk
///   per level, attribute set and precision layer, coarsest first: any
///   prefix of whole chunks decodes); [`Encoded::report`], the bits spent
///   per level.
/// - **Guarantees**: deterministic (the same model and options give the
///   same bytes); [`decode`](crate::decode) of the bytes gives back
///   [`Encoded::vertices`] exactly.
/// - **Errors**: [`Error::Input`](crate::Error::Input) for an empty or
///   non-finite model or an option out of range.
/// - **Cost**: about linear in the samples and in the surface cells of the
///   finest level (some `4^R` for a closed surface); memory a few dozen
///   bytes per cell.
pub fn encode(model: &Model, opts: &EncodeOptions) -> Result<Encoded> {
    let mut tree = Octree::build(
        model,
        &BuildOptions {
            depth: opts.depth,
            sidedness: opts.sidedness,
        },
    )?;
    let (eliminated, relax_below) = thin_choosing(&mut tree, &opts.thinning);
    let mut e = encode_thinned(&tree, &eliminated, opts)?;
    e.report.relax_below = opts.thinning.outer.then_some(relax_below);
    Ok(e)
}

/// Encodes an octree already thinned (`eliminated` from [`thin`](crate::thinning::thin)).
pub fn encode_thinned(
    tree: &Octree,
    eliminated: &[usize],
    opts: &EncodeOptions,
) -> Result<Encoded> {
    match opts.mode {
        Mode::Baseline => encode_with::<BitWriter>(tree, eliminated, opts),
        Mode::Entropy => encode_with::<EntropyWriter>(tree, eliminated, opts),
    }
}

fn encode_with<W: ChunkWriter>(
    tree: &Octree,
    eliminated: &[usize],
    opts: &EncodeOptions,
) -> Result<Encoded> {
    let (h, leaf_source) = Hierarchy::from_thinned(tree)?;
    let depth = tree.depth;
    let dr = depth as usize;
    let precision = opts.precision.clamp(depth, QBITS as u8);
    let entropy = opts.mode == Mode::Entropy;
    let leaf_cells = &h.levels[dr].cells;
    let leaves: Vec<[u32; 3]> = h
        .particle_leaf
        .iter()
        .map(|&l| unmorton(leaf_cells[l as usize]))
        .collect();
    let mut channels: Vec<(Channel, Averaged)> = Vec::new();
    if opts.colours
        && let Some(c) = &tree.leaves.colour
    {
        let v: Vec<[u32; 3]> = leaf_source
            .iter()
            .map(|&s| c[s as usize].map(u32::from))
            .collect();
        channels.push((Channel::Colour, attributes::average_up(&h, &v)));
    }
    if opts.normals
        && let Some(n) = &tree.leaves.normal
    {
        let v: Vec<[u32; 3]> = leaf_source
            .iter()
            .map(|&s| attributes::quantise_normal(n[s as usize]))
            .collect();
        channels.push((Channel::Normal, attributes::average_up(&h, &v)));
    }
    let header = Header {
        mode: opts.mode,
        depth,
        precision,
        colours: channels.iter().any(|c| c.0 == Channel::Colour),
        normals: channels.iter().any(|c| c.0 == Channel::Normal),
        frame: tree.frame,
        particles: u32::try_from(leaves.len())
            .map_err(|_| Error::Input("too many particles".into()))?,
    };
    let mut out = Vec::new();
    write_header(&header, &mut out);
    let mut report = EncodeReport {
        mode: opts.mode.name().into(),
        depth,
        precision,
        particles: leaves.len(),
        ..Default::default()
    };
    let mut coded: Vec<[u32; 3]> = Vec::with_capacity(leaves.len());
    let mut links = crate::coding::links::Links::root();
    for r in 0..=dr {
        // Structure.
        let mut w = W::open();
        if r == 0 {
            coded.push(hc::code_root(&mut w, depth, Some(leaves[0]))?);
        } else {
            let inp = LevelInput {
                depth,
                r: r as u8,
                entropy,
                parents: &h.levels[r - 1],
                max_nodes: usize::MAX,
            };
            let truth = Truth {
                level: &h.levels[r],
                leaves: &leaves,
            };
            let got = hc::code_level(&mut w, &inp, &mut links, &mut coded, Some(&truth))?;
            if got != h.levels[r] {
                return Err(Error::Input(format!(
                    "internal: level {r} does not re-derive from its code"
                )));
            }
        }
        let (payload, bits) = w.close();
        let lv = &h.levels[r];
        write_chunk(
            ChunkKind::Level,
            r as u8,
            lv.cells.len() as u32,
            eliminated.get(r).copied().unwrap_or(0) as u32,
            &payload,
            &mut out,
        );
        // Attributes.
        let mut attr_bytes = 0;
        if !channels.is_empty() {
            let mut w = W::open();
            for (ch, avg) in &channels {
                if r == 0 {
                    let mut v = avg.values[0][0];
                    attributes::code_root(&mut w, *ch, &mut v)?;
                } else {
                    let mut v = avg.values[r].clone();
                    attributes::code_level(
                        &mut w,
                        *ch,
                        &h.levels[r - 1],
                        &avg.values[r - 1],
                        lv,
                        &mut v,
                        Some(&avg.corrections[r - 1]),
                    )?;
                }
            }
            let (payload, _) = w.close();
            attr_bytes = payload.len();
            write_chunk(
                ChunkKind::Attributes,
                r as u8,
                lv.kept() as u32,
                0,
                &payload,
                &mut out,
            );
        }
        report.levels.push(LevelReport {
            level: r as u8,
            kept: lv.kept(),
            eliminated: eliminated.get(r).copied().unwrap_or(0),
            phantoms: lv.phantoms(),
            new_particles: h.new_particles(r),
            structure_bits: bits,
            attribute_bytes: attr_bytes,
            bytes_so_far: out.len(),
        });
    }
    // Precision layers, particles in stream order.
    let mut q: Vec<[u32; 3]> = h
        .particle_leaf
        .iter()
        .map(|&l| tree.leaves.q[leaf_source[l as usize] as usize])
        .collect();
    let mut neighbours = if entropy {
        precision_layers::particle_faces(&links, &h.levels[dr], q.len())
    } else {
        precision_layers::Faces::default()
    };
    if entropy
        && precision > depth
        && opts.placement == Placement::SurfaceColumn
        && let Some(normals) = &tree.leaves.normal
    {
        for (i, v) in q.iter_mut().enumerate() {
            let n = normals[leaf_source[h.particle_leaf[i] as usize] as usize];
            let g = neighbours.normal_axis(i);
            if let Some((p, k)) = surface_column(*v, leaves[i], n, g, depth, precision) {
                *v = p;
                neighbours.column[i] = 1 + k;
            }
        }
    }
    for b in (u32::from(depth) + 1)..=u32::from(precision) {
        let mut w = W::open();
        precision_layers::code_precision(&mut w, depth, b, &mut q, &mut neighbours)?;
        let (payload, bits) = w.close();
        write_chunk(
            ChunkKind::Precision,
            b as u8,
            q.len() as u32,
            0,
            &payload,
            &mut out,
        );
        report.precision_bits.push(bits);
    }
    report.total_bytes = out.len();
    let low = QBITS - u32::from(precision);
    let vertices = q.iter().map(|v| v.map(|c| (c >> low) << low)).collect();
    Ok(Encoded {
        bytes: out,
        report,
        vertices,
    })
}

/// [`Placement::SurfaceColumn`] for one particle: `mean` (16-bit grid)
/// and unit `normal` of its samples, `leaf` (`R`-bit), the normal axis
/// `g` the decoder will infer. Tries columns of depth `k = 0, 1, …` (up
/// to [`crate::coding::contexts::MAX_COLUMN_DEPTH`], and below `N`): the tangential
/// coordinates keep the mean's first `k` bits below `R`, then sit at the
/// middle of that sub-cell (the centre of its `N`-bit cell there, what a
/// decoder at full precision draws); the normal one is the plane's height
/// there. The first `k` whose height stays inside the leaf wins; `None`:
/// keep the mean.
fn surface_column(
    mean: [u32; 3],
    leaf: [u32; 3],
    normal: glam::Vec3,
    g: usize,
    depth: u8,
    precision: u8,
) -> Option<([u32; 3], u8)> {
    let s = QBITS - u32::from(depth);
    let n = normal.to_array().map(f64::from);
    if s == 0 || n[g].abs() < f64::from(MIN_NORMAL_COSINE) {
        return None;
    }
    let half_cell = (1u32 << (QBITS - u32::from(precision))) >> 1;
    let max_k = crate::coding::contexts::MAX_COLUMN_DEPTH.min(precision - depth - 1);
    let lo = f64::from(leaf[g] << s);
    let hi = lo + f64::from((1u32 << s) - 1);
    for k in 0..=max_k {
        let sub = s - u32::from(k);
        let mut out = [0u32; 3];
        let mut rise = 0.0;
        for a in 0..3 {
            if a != g {
                out[a] = ((mean[a] >> sub) << sub) + (1 << (sub - 1)) + half_cell;
                rise += n[a] * (f64::from(out[a]) - f64::from(mean[a]));
            }
        }
        let h = (f64::from(mean[g]) - rise / n[g]).round();
        if (lo..=hi).contains(&h) {
            out[g] = h as u32;
            return Some((out, k));
        }
    }
    None
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::decode::{DecodeOptions, decode};

    /// RMS distance of the decoded full-precision vertices from the unit
    /// sphere the icosphere approximates, and the stream size.
    fn sphere_rms(placement: Placement, precision: u8) -> (f64, usize) {
        let model = Model::Mesh(lodkit_mesh::shapes::icosphere(5));
        let opts = EncodeOptions {
            depth: Some(6),
            precision,
            placement,
            ..EncodeOptions::DEFAULT
        };
        let e = encode(&model, &opts).unwrap();
        let d = decode(&e.bytes, &DecodeOptions::default()).unwrap();
        let s = d.surface(6).unwrap();
        let sq: f64 = s
            .positions
            .iter()
            .map(|p| (f64::from(p.length()) - 1.0).powi(2))
            .sum();
        ((sq / s.positions.len() as f64).sqrt(), e.bytes.len())
    }

    #[test]
    fn surface_columns_cost_fewer_bytes_than_means_at_about_the_same_error() {
        for n in [10u8, 12] {
            let (rms_mean, bytes_mean) = sphere_rms(Placement::Mean, n);
            let (rms_col, bytes_col) = sphere_rms(Placement::SurfaceColumn, n);
            assert!(
                bytes_col * 10 < bytes_mean * 8,
                "N = {n}: {bytes_col} B against {bytes_mean} B"
            );
            assert!(
                rms_col < rms_mean * 1.25,
                "N = {n}: RMS {rms_col:.3e} against {rms_mean:.3e}"
            );
        }
    }

    #[test]
    fn decoders_read_the_vertices_the_encoder_placed() {
        let model = Model::Mesh(lodkit_mesh::shapes::icosphere(4));
        for placement in [Placement::Mean, Placement::SurfaceColumn] {
            for mode in [Mode::Baseline, Mode::Entropy] {
                for n in [6u8, 7, 8, 9, 12, 16] {
                    let opts = EncodeOptions {
                        depth: Some(6),
                        precision: n,
                        placement,
                        mode,
                        ..EncodeOptions::DEFAULT
                    };
                    let e = encode(&model, &opts).unwrap();
                    let d = decode(&e.bytes, &DecodeOptions::default()).unwrap();
                    assert_eq!(d.q.len(), e.vertices.len());
                    let bad = d.q.iter().zip(&e.vertices).position(|(a, b)| a != b);
                    assert!(
                        bad.is_none(),
                        "{placement:?} {mode:?} N = {n}: particle {bad:?} decodes to {:?}, placed at {:?}",
                        bad.map(|i| d.q[i]),
                        bad.map(|i| e.vertices[i])
                    );
                }
            }
        }
    }

    #[test]
    fn a_surface_column_lies_on_the_plane_inside_the_leaf() {
        // Leaf (3, 5, 7) at R = 4 (4096 grid units a side), a plane tilted
        // about x with its normal mostly along z.
        let leaf = [3u32, 5, 7];
        let n = glam::Vec3::new(0.0, 0.6, 0.8);
        let mean = [3 * 4096 + 1000, 5 * 4096 + 2500, 7 * 4096 + 2000];
        // Neighbours across x and y: z is the normal axis.
        assert_eq!(precision_layers::normal_axis(0b011_011), 2);
        let (p, k) = surface_column(mean, leaf, n, 2, 4, 12).unwrap();
        assert_eq!(k, 0);
        // Tangential: the 12-bit cell at the leaf's middle, drawn at its centre.
        assert_eq!(p[0], 3 * 4096 + 2048 + 8);
        assert_eq!(p[1], 5 * 4096 + 2048 + 8);
        let off: f64 = (0..3)
            .map(|a| f64::from(n[a]) * (f64::from(p[a]) - f64::from(mean[a])))
            .sum();
        assert!(off.abs() <= 1.0, "{off} grid units off the plane");
        assert_eq!(p[2] >> 12, 7);
        // Steeper than the limit against the inferred axis: keep the mean.
        let steep = glam::Vec3::new(0.0, 0.9, 0.43);
        assert_eq!(surface_column(mean, leaf, steep, 2, 4, 12), None);
        // A mean near the leaf's top: the middle column's crossing leaves
        // the leaf, the quarter column under the mean does not.
        let high = [3 * 4096 + 3500, 5 * 4096 + 3500, 7 * 4096 + 3700];
        let (p, k) = surface_column(high, leaf, n, 2, 4, 12).unwrap();
        assert_eq!(k, 1);
        assert_eq!(p[1], 5 * 4096 + 2048 + 1024 + 8);
        assert_eq!(p[2] >> 12, 7);
    }
}
