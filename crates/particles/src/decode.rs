//! Progressive decoding — §5.4 of Yemez & Schmitt.
//!
//! Any prefix of whole chunks decodes: the structure chunk of level `r`
//! rebuilds `S^r` (kept and phantom nodes, the particles of `P^r` with
//! their leaves, so vertices at precision `N = R`), the attribute chunk
//! recovers colours and normals exactly (eq. 4), and each precision layer
//! adds one bit to every vertex coordinate (§7.2). A reader may stop after
//! any chunk ([`DecodeOptions`]); a damaged or cut chunk is an error that
//! says which.

use crate::attributes::{self, Channel};
use crate::coding::bit_coder::BitCoder;
use crate::coding::levels::{self as hc, LevelInput};
use crate::coding::precision_layers;
use crate::coding::range_coder::EntropyReader;
use crate::coding::raw_bits::BitReader;
use crate::container::{Chunk, ChunkKind, ChunkReader, Header, Mode, read_header};
use crate::error::{Result, stream_err};
use crate::level_surface::LevelSurface;
use crate::octree::QBITS;
use crate::ordering::HLevel;
use crate::triangulate::{TriangulateOptions, Triangulation};

/// Where to stop reading.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct DecodeOptions {
    /// Last octree level to decode (`None`: all present).
    pub max_level: Option<u8>,
    /// Highest vertex precision to decode (`None`: all present).
    pub max_precision: Option<u8>,
}

impl DecodeOptions {
    /// The defaults: every level and precision present.
    pub const DEFAULT: DecodeOptions = DecodeOptions {
        max_level: None,
        max_precision: None,
    };
}

impl Default for DecodeOptions {
    fn default() -> Self {
        DecodeOptions::DEFAULT
    }
}

/// What a prefix of a stream holds.
#[derive(Debug, Clone)]
pub struct Decoded {
    /// The stream header.
    pub header: Header,
    /// Levels `0..levels.len()` decoded.
    pub levels: Vec<HLevel>,
    /// 16-bit grid coordinates of the particles known so far (low bits
    /// beyond `precision` are zero).
    pub q: Vec<[u32; 3]>,
    /// Bits of `q` that are known.
    pub precision: u8,
    /// Colours per level per node (phantoms: zero), if coded and decoded.
    pub colours: Option<Vec<Vec<[u32; 3]>>>,
    /// Quantised normals per level per node.
    pub normals: Option<Vec<Vec<[u32; 3]>>>,
    /// Stream bytes needed for each level (and its attributes).
    pub bytes_per_level: Vec<usize>,
    /// Cubes thinning eliminated at each level (from the level chunks).
    pub eliminated: Vec<u32>,
    /// Bytes of each level's structure chunk payload.
    pub structure_bytes: Vec<usize>,
    /// Stream bytes used in all: the end of the last chunk decoded (a
    /// prefix of the bytes given).
    pub bytes_read: usize,
    /// The chunk the end of the bytes cut short, when [`decode_prefix`]
    /// stopped there; `None` when every chunk up to the options' limits was
    /// whole (and always from [`decode`], which refuses a cut chunk).
    pub cut: Option<Cut>,
}

/// A chunk cut short by the end of the bytes given: where
/// [`decode_prefix`] stopped.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct Cut {
    /// Chunk number in the stream (0: the first after the header).
    pub chunk: usize,
    /// Offset of the cut chunk's first byte (= [`Decoded::bytes_read`]).
    pub offset: usize,
    /// What is missing, in words (as [`decode`]'s error would say).
    pub message: String,
}

trait ChunkRead<'a>: BitCoder + Sized {
    fn open(payload: &'a [u8]) -> Result<Self>;
}

impl<'a> ChunkRead<'a> for BitReader<'a> {
    fn open(payload: &'a [u8]) -> Result<Self> {
        Ok(BitReader::new(payload))
    }
}

impl<'a> ChunkRead<'a> for EntropyReader<'a> {
    fn open(payload: &'a [u8]) -> Result<Self> {
        EntropyReader::new(payload)
    }
}

/// Decodes a whole `.pop` stream, or a prefix of whole chunks, up to the
/// limits of `opts` (strict: a chunk cut short is an error).
///
/// - **Input**: `bytes`, the stream from its first byte (header, then
///   chunks); `opts` stops after a level or a precision layer.
/// - **Output**: every level up to the limit, vertex coordinates at the
///   precision of the last layer read ([`Decoded::precision`] bits), and
///   attributes where the stream has them. Allocation is bounded by the
///   counts the chunks declare, each checked against the bytes present.
/// - **Errors**: [`Error::Stream`](crate::Error::Stream), naming the chunk
///   and what is wrong, for a bad header, a damaged or cut chunk, chunks
///   out of order, or a stream with no level. Never panics on any bytes.
/// - **Cost**: linear in the bytes decoded; about a dozen binary
///   decisions per particle in the entropy mode.
/// - Deterministic: the same bytes and options give the same result.
pub fn decode(bytes: &[u8], opts: &DecodeOptions) -> Result<Decoded> {
    decode_impl(bytes, opts, false)
}

/// Decodes what has arrived of a stream: every complete chunk of the
/// prefix `bytes`, stopping quietly at a chunk the end of `bytes` cuts
/// short ([`Decoded::cut`] says which and where).
///
/// Same contract as [`decode`] otherwise: damage (a checksum mismatch,
/// unknown kinds, chunks out of order) is still an error, and so is a
/// prefix holding no complete level (fewer bytes than the header and the
/// root's chunk). [`Decoded::finest_level`] is then the finest level a
/// viewer can show, and [`Decoded::bytes_read`] the bytes it used; feeding
/// a longer prefix later decodes from the start again.
pub fn decode_prefix(bytes: &[u8], opts: &DecodeOptions) -> Result<Decoded> {
    decode_impl(bytes, opts, true)
}

fn decode_impl(bytes: &[u8], opts: &DecodeOptions, prefix: bool) -> Result<Decoded> {
    let mut p = Progress::new(read_header(bytes)?, opts);
    p.read(bytes, prefix)?;
    p.finish()
}

/// The decoder between two chunks: everything [`decode`] keeps while it
/// reads, so that a stream arriving in pieces ([`crate::PrefixDecoder`])
/// reads each chunk once, and a whole stream is one call of [`read`].
///
/// Invariant: `d` holds the chunks of `bytes[..d.bytes_read]`, `number` of
/// them; `leaves` the particles' leaf coordinates until the first precision
/// layer moves them into `d.q`.
///
/// [`read`]: Progress::read
#[derive(Debug, Clone)]
pub(crate) struct Progress {
    pub(crate) d: Decoded,
    channels: Vec<Channel>,
    max_level: u8,
    max_precision: u8,
    leaves: Vec<[u32; 3]>,
    links: crate::coding::links::Links,
    neighbours: precision_layers::Faces,
    /// The chunk expected next: (kind, index).
    expect: (ChunkKind, u8),
    /// Chunks read so far.
    number: usize,
    /// A limit of the options was reached: later chunks are not read.
    stopped: bool,
}

impl Progress {
    pub(crate) fn new(header: Header, opts: &DecodeOptions) -> Progress {
        let depth = header.depth;
        let mut channels = Vec::new();
        if header.colours {
            channels.push(Channel::Colour);
        }
        if header.normals {
            channels.push(Channel::Normal);
        }
        Progress {
            d: Decoded {
                header,
                levels: Vec::new(),
                q: Vec::new(),
                precision: depth,
                colours: header.colours.then(Vec::new),
                normals: header.normals.then(Vec::new),
                bytes_per_level: Vec::new(),
                eliminated: Vec::new(),
                structure_bytes: Vec::new(),
                bytes_read: crate::container::HEADER_LEN,
                cut: None,
            },
            channels,
            max_level: opts.max_level.unwrap_or(depth).min(depth),
            max_precision: opts
                .max_precision
                .unwrap_or(header.precision)
                .min(header.precision),
            leaves: Vec::new(),
            links: crate::coding::links::Links::root(),
            neighbours: precision_layers::Faces::default(),
            expect: (ChunkKind::Level, 0),
            number: 0,
            stopped: false,
        }
    }

    /// Reads the chunks of `bytes` (the stream from its first byte, a
    /// longer prefix of the same stream than any read before) that follow
    /// the last one read. `prefix`: a chunk cut short by the end of
    /// `bytes` stops quietly ([`Decoded::cut`]); otherwise it is an error.
    pub(crate) fn read(&mut self, bytes: &[u8], prefix: bool) -> Result<()> {
        self.d.cut = None;
        if self.stopped {
            return Ok(());
        }
        let mut reader = ChunkReader::resume(bytes, self.d.bytes_read, self.number);
        while let Some(chunk) = reader.next() {
            let chunk = match chunk {
                Ok(c) => c,
                Err(crate::Error::Stream(message)) if prefix && reader.was_cut() => {
                    self.d.cut = Some(Cut {
                        chunk: self.number,
                        offset: self.d.bytes_read,
                        message,
                    });
                    break;
                }
                Err(e) => return Err(e),
            };
            self.number += 1;
            let end = chunk.end;
            let more = match self.d.header.mode {
                Mode::Baseline => self.chunk::<BitReader>(chunk)?,
                Mode::Entropy => self.chunk::<EntropyReader>(chunk)?,
            };
            if !more {
                self.stopped = true;
                break;
            }
            self.d.bytes_read = end;
        }
        Ok(())
    }

    /// Decodes one chunk; `false` when it is past the options' limits (and
    /// so is everything after it).
    fn chunk<'a, R: ChunkRead<'a>>(&mut self, chunk: Chunk<'a>) -> Result<bool> {
        let depth = self.d.header.depth;
        let entropy = self.d.header.mode == Mode::Entropy;
        let d = &mut self.d;
        if (chunk.kind, chunk.index) != self.expect {
            return stream_err(format!(
                "chunk {:?} {} found where {:?} {} was expected",
                chunk.kind, chunk.index, self.expect.0, self.expect.1
            ));
        }
        match chunk.kind {
            ChunkKind::Level => {
                let r = chunk.index;
                if r > self.max_level {
                    return Ok(false);
                }
                let mut c = R::open(chunk.payload)?;
                let level = if r == 0 {
                    if chunk.count != 1 {
                        return stream_err("level 0 must hold the root alone");
                    }
                    self.leaves.push(hc::code_root(&mut c, depth, None)?);
                    HLevel {
                        cells: vec![0],
                        phantom: vec![false],
                        particle: vec![0],
                    }
                } else {
                    let parents = &d.levels[r as usize - 1];
                    let inp = LevelInput {
                        depth,
                        r,
                        entropy,
                        parents,
                        max_nodes: chunk.count as usize,
                    };
                    let lv = hc::code_level(&mut c, &inp, &mut self.links, &mut self.leaves, None)?;
                    if lv.cells.len() != chunk.count as usize {
                        return stream_err(format!(
                            "level {r} decodes to {} nodes, its chunk declares {}",
                            lv.cells.len(),
                            chunk.count
                        ));
                    }
                    lv
                };
                if self.leaves.len() > d.header.particles as usize {
                    return stream_err("more particles than the header declares");
                }
                d.levels.push(level);
                d.bytes_per_level.push(chunk.end);
                d.eliminated.push(chunk.aux);
                d.structure_bytes.push(chunk.payload.len());
                self.expect = if self.channels.is_empty() {
                    next_structure(r, depth)
                } else {
                    (ChunkKind::Attributes, r)
                };
            }
            ChunkKind::Attributes => {
                let r = chunk.index as usize;
                let mut c = R::open(chunk.payload)?;
                for &ch in &self.channels {
                    let store = match ch {
                        Channel::Colour => d.colours.as_mut(),
                        Channel::Normal => d.normals.as_mut(),
                    }
                    .expect("channel declared in the header");
                    let lv = &d.levels[r];
                    let mut v = vec![[0u32; 3]; lv.cells.len()];
                    if r == 0 {
                        attributes::code_root(&mut c, ch, &mut v[0])?;
                    } else {
                        attributes::code_level(
                            &mut c,
                            ch,
                            &d.levels[r - 1],
                            &store[r - 1],
                            lv,
                            &mut v,
                            None,
                        )?;
                    }
                    store.push(v);
                }
                d.bytes_per_level[r] = chunk.end;
                self.expect = next_structure(r as u8, depth);
            }
            ChunkKind::Precision => {
                let b = chunk.index;
                if b > self.max_precision {
                    return Ok(false);
                }
                if d.q.is_empty() {
                    d.q = to_grid(std::mem::take(&mut self.leaves), depth);
                }
                if chunk.count as usize != d.q.len() {
                    return stream_err(format!(
                        "precision layer {b} declares {} particles",
                        chunk.count
                    ));
                }
                let mut c = R::open(chunk.payload)?;
                if entropy && self.neighbours.is_empty() {
                    self.neighbours = precision_layers::particle_faces(
                        &self.links,
                        &d.levels[depth as usize],
                        d.q.len(),
                    );
                }
                precision_layers::code_precision(
                    &mut c,
                    depth,
                    u32::from(b),
                    &mut d.q,
                    &mut self.neighbours,
                )?;
                d.precision = b;
                self.expect = (ChunkKind::Precision, b.saturating_add(1));
            }
        }
        Ok(true)
    }

    /// Levels whose chunks have all been read: a level's attribute chunk,
    /// where the stream has attributes, is part of it.
    pub(crate) fn whole_levels(&self) -> usize {
        let n = self.d.levels.len();
        let waiting = !self.channels.is_empty()
            && self.expect == (ChunkKind::Attributes, n.wrapping_sub(1) as u8);
        if waiting && n > 0 { n - 1 } else { n }
    }

    /// What has been read, as [`decode`] returns it.
    pub(crate) fn finish(mut self) -> Result<Decoded> {
        if self.d.levels.is_empty() {
            return stream_err("the stream holds no level");
        }
        if self.d.q.is_empty() {
            self.d.q = to_grid(self.leaves, self.d.header.depth);
        }
        // The last level's attribute chunk may be missing from a prefix:
        // `surface` then returns that level without attributes.
        Ok(self.d)
    }

    /// [`finish`](Self::finish) without consuming the state (a copy of
    /// what has been read).
    pub(crate) fn snapshot(&self) -> Result<Decoded> {
        if self.d.levels.is_empty() {
            return stream_err("the stream holds no level");
        }
        let mut d = self.d.clone();
        if d.q.is_empty() {
            d.q = to_grid(self.leaves.clone(), d.header.depth);
        }
        Ok(d)
    }
}

/// Leaf coordinates (`depth` bits) as 16-bit grid coordinates, in place.
fn to_grid(mut leaves: Vec<[u32; 3]>, depth: u8) -> Vec<[u32; 3]> {
    let shift = QBITS - u32::from(depth);
    for l in &mut leaves {
        *l = l.map(|v| v << shift);
    }
    leaves
}

fn next_structure(r: u8, depth: u8) -> (ChunkKind, u8) {
    if r < depth {
        (ChunkKind::Level, r + 1)
    } else {
        (ChunkKind::Precision, depth + 1)
    }
}

impl Decoded {
    /// Number of levels decoded (`r` runs over `0..levels()`).
    pub fn level_count(&self) -> usize {
        self.levels.len()
    }

    /// The finest level decoded (every stream that decodes holds level 0).
    pub fn finest_level(&self) -> u8 {
        (self.levels.len() - 1) as u8
    }

    /// Level `r` triangulated ([`crate::triangulate`] of
    /// [`surface`](Self::surface)): with [`TriangulateOptions::DEFAULT`]
    /// an oriented mesh whose vertices are the level's particles, in
    /// Morton order of their cells.
    ///
    /// Errors: `r` beyond [`finest_level`](Self::finest_level).
    pub fn triangulate(&self, r: u8, opts: &TriangulateOptions) -> Result<Triangulation> {
        Ok(crate::triangulate::triangulate(&self.surface(r)?, opts))
    }

    /// [`surface`](Self::surface), consuming the decoded stream so the
    /// level's cells move into the surface instead of being copied (for a
    /// reader that only wants one level, as the `pop` bench).
    pub fn into_surface(mut self, r: u8) -> Result<LevelSurface> {
        let i = r as usize;
        if i >= self.levels.len() || self.levels[i].phantom.iter().any(|&p| p) {
            return self.surface(r);
        }
        // No phantom: every cell is kept, in order.
        let mut s = self.surface_with(r, false)?;
        s.cells = std::mem::take(&mut self.levels[i].cells);
        Ok(s)
    }

    /// The octree surface `S^r` with its particles.
    pub fn surface(&self, r: u8) -> Result<LevelSurface> {
        self.surface_with(r, true)
    }

    /// [`surface`](Self::surface), its cells left empty unless `copy_cells`.
    fn surface_with(&self, r: u8, copy_cells: bool) -> Result<LevelSurface> {
        let Some(lv) = self.levels.get(r as usize) else {
            return stream_err(format!(
                "level {r} is not in the decoded prefix ({} levels)",
                self.levels.len()
            ));
        };
        let shift = QBITS - u32::from(self.precision);
        let kept = lv.phantom.iter().filter(|&&p| !p).count();
        let mut cells = Vec::with_capacity(if copy_cells { kept } else { 0 });
        let mut positions = Vec::with_capacity(kept);
        // `cell_centre` in f64, with the frame and the cube size hoisted.
        let frame = self.header.frame;
        let cube = f64::from(frame.size) / f64::from(1u32 << self.precision);
        let origin = frame.origin.as_dvec3();
        for (i, &c) in lv.cells.iter().enumerate() {
            if lv.phantom[i] {
                continue;
            }
            if copy_cells {
                cells.push(c);
            }
            let q = self.q[lv.particle[i] as usize].map(|v| v >> shift);
            positions.push(
                (origin + (glam::DVec3::new(q[0] as f64, q[1] as f64, q[2] as f64) + 0.5) * cube)
                    .as_vec3(),
            );
        }
        let pick = |store: &Option<Vec<Vec<[u32; 3]>>>| -> Option<Vec<[u32; 3]>> {
            let lvl = store.as_ref()?.get(r as usize)?;
            Some(
                lvl.iter()
                    .zip(&lv.phantom)
                    .filter(|(_, p)| !**p)
                    .map(|(v, _)| *v)
                    .collect(),
            )
        };
        let colours = pick(&self.colours).map(|v| {
            v.iter()
                .map(|c| [c[0] as u8, c[1] as u8, c[2] as u8, 255])
                .collect()
        });
        let normals = pick(&self.normals).map(|v| {
            v.iter()
                .map(|&n| attributes::dequantise_normal(n))
                .collect()
        });
        Ok(LevelSurface {
            level: r,
            frame: self.header.frame,
            cells,
            positions,
            colours,
            normals,
        })
    }
}
