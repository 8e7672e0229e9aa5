//! The encoder pipeline: octree (§4.1) → thinning (§4.3) → ordering (§4.4)
//! → attributes (§5.5) → hierarchical coding (§7.1) in the chosen bit
//! layer → precision layers (§7.2) → `.pop` chunks.
use lodkit_mesh::Model;

use crate::attributes::{self, Averaged, Channel};
use crate::container::{ChunkKind, Header, Mode, write_chunk, write_header};
use crate::encode_baseline::BitWriter;
use crate::encode_entropy::EntropyWriter;
use crate::error::{Error, Result};
use crate::hierarchical_coding::{self as hc, BitCoder, LevelInput, Truth};
use crate::octree::{BuildOptions, Octree, QBITS, Sidedness, unmorton};
use crate::ordering::Hierarchy;
use crate::thinning::{ThinningOptions, thin};

/// Default precision `N`: §7.2 finds 12 bits enough for most models.
pub const DEFAULT_PRECISION: u8 = 12;

/// Options of [`encode`].
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct EncodeOptions {
    /// Octree resolution `R`; `None` picks it from the sampling density.
    pub depth: Option<u8>,
    /// Highest precision `N` coded (raised to `R` when below it, at most 16).
    pub precision: u8,
    pub mode: Mode,
    pub thinning: ThinningOptions,
    /// IN/OUT labelling; `None` chooses (see [`BuildOptions`]).
    pub sidedness: Option<Sidedness>,
    /// Code the input's colours when it has some.
    pub colours: bool,
    /// Code normals (§5.5); off by default, as §6.2 lets the coder drop them.
    pub normals: bool,
}

impl EncodeOptions {
    /// Entropy mode, automatic depth, `N = 12`, inner thinning, colours kept.
    pub const DEFAULT: EncodeOptions = EncodeOptions {
        depth: None,
        precision: DEFAULT_PRECISION,
        mode: Mode::Entropy,
        thinning: ThinningOptions::DEFAULT,
        sidedness: None,
        colours: true,
        normals: false,
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
    pub mode: String,
    pub depth: u8,
    pub precision: u8,
    pub particles: usize,
    pub levels: Vec<LevelReport>,
    /// Bits of each precision layer `R+1..=N`.
    pub precision_bits: Vec<u64>,
    pub total_bytes: usize,
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
    pub bytes: Vec<u8>,
    pub report: EncodeReport,
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

/// Encodes a mesh, point cloud or range image.
pub fn encode(model: &Model, opts: &EncodeOptions) -> Result<Encoded> {
    let mut tree = Octree::build(
        model,
        &BuildOptions {
            depth: opts.depth,
            sidedness: opts.sidedness,
        },
    )?;
    let eliminated = thin(&mut tree, &opts.thinning);
    encode_thinned(&tree, &eliminated, opts)
}

/// Encodes an octree already thinned (`eliminated` from [`thin`]).
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
    let mut links = hc::Links::root();
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
    for b in (u32::from(depth) + 1)..=u32::from(precision) {
        let mut w = W::open();
        hc::code_precision(&mut w, b, &mut q)?;
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
    Ok(Encoded { bytes: out, report })
}
