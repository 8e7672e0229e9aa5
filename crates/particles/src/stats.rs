//! Per-level figures of a stream — the columns of Table 1 of Yemez &
//! Schmitt (ON nodes `k_r`, eliminated nodes, phantoms `m_r`, triangles,
//! non-manifold triangulations, the distribution of configurations
//! `C_1–3 / C_4–5 / C_6 / C_>6`, time) plus bytes and bits per particle,
//! and the per-level meshes a caller such as `lodkit build` needs.
use std::time::Instant;

use lodkit_mesh::TriMesh;

use crate::container::Header;
use crate::decode::{DecodeOptions, decode};
use crate::error::Result;
use crate::triangulate::{TriangulateOptions, TriangulationStats, triangulate};

/// One level of a decoded stream, triangulated.
#[derive(Debug, Clone)]
pub struct ProgressiveLevel {
    /// Octree level `r`.
    pub level: u8,
    /// Stream bytes a reader needs to show this level (header included).
    pub bytes_so_far: usize,
    /// Particles (kept ON nodes) at this level.
    pub particles: usize,
    /// Bits per coordinate of the particle positions decoded (N).
    pub precision: u8,
    /// The triangulated level (oriented).
    pub mesh: TriMesh,
    /// Its triangulation figures.
    pub stats: TriangulationStats,
}

/// Decodes every level of `bytes` and triangulates each — what `lodkit
/// build` puts in its report. Levels are decoded at the precision their
/// own chunks give (N = R, no refinement layer), so `bytes_so_far` is
/// exactly what a reader needs for that mesh; when the stream carries
/// refinement layers, one more entry follows: the finest level at the
/// stream's full precision, with `bytes_so_far` the whole stream.
pub fn progressive_levels(
    bytes: &[u8],
    opts: &TriangulateOptions,
) -> Result<Vec<ProgressiveLevel>> {
    let header = crate::container::read_header(bytes)?;
    let d = decode(
        bytes,
        &DecodeOptions {
            max_precision: Some(header.depth),
            ..DecodeOptions::default()
        },
    )?;
    let mut out = Vec::with_capacity(d.levels.len() + 1);
    let mut push = |d: &crate::decode::Decoded, r: usize, bytes_so_far: usize| -> Result<()> {
        let s = d.surface(r as u8)?;
        let t = triangulate(&s, opts);
        out.push(ProgressiveLevel {
            level: r as u8,
            bytes_so_far,
            particles: s.cells.len(),
            precision: d.precision,
            mesh: t.mesh,
            stats: t.stats,
        });
        Ok(())
    };
    for r in 0..d.levels.len() {
        push(&d, r, d.bytes_per_level[r])?;
    }
    if header.precision > header.depth && d.levels.len() == usize::from(header.depth) + 1 {
        let full = decode(bytes, &DecodeOptions::default())?;
        push(&full, usize::from(header.depth), full.bytes_read)?;
    }
    Ok(out)
}

/// Table 1 row.
#[derive(Debug, Clone, Default, PartialEq, serde::Serialize)]
pub struct LevelStats {
    /// Octree level `r`.
    pub level: u8,
    /// ON nodes after thinning, `k_r`.
    pub on_nodes: usize,
    /// Cubes thinning eliminated at this level (Table 1).
    pub eliminated: u32,
    /// Phantom nodes, `m_r`.
    pub phantoms: usize,
    /// New particles at this level, `n_r`.
    pub new_particles: usize,
    /// Triangles of the level.
    pub triangles: usize,
    /// Ambiguous neighbourhoods left whole (Table 1's "non-manifold").
    pub non_manifold_configurations: u64,
    /// Triangles on an edge shared by more than two triangles.
    pub non_manifold_triangles: usize,
    /// Percentages of `C_1–3`, `C_4–5`, `C_6`, `C_>6`.
    pub distribution: [f64; 4],
    /// Neighbourhoods of each class `C_1..C_17` (index 0 unused).
    pub configurations: Vec<u64>,
    /// Ambiguous neighbourhoods resolved by a unique Hamiltonian cycle.
    pub disambiguated: u64,
    /// Seconds to triangulate this level.
    pub triangulate_seconds: f64,
    /// Bytes of this level's structure chunk payload.
    pub structure_bytes: usize,
    /// Stream bytes up to and including this level.
    pub bytes_so_far: usize,
    /// `8 · bytes_so_far / k_r`.
    pub bits_per_particle: f64,
}

/// All of [`LevelStats`] for a stream.
#[derive(Debug, Clone, serde::Serialize)]
pub struct StreamStats {
    /// Coding mode name.
    pub mode: String,
    /// Octree resolution `R`.
    pub depth: u8,
    /// Vertex precision `N`.
    pub precision: u8,
    /// Particles at level `R`.
    pub particles: u32,
    /// Whether colours are coded.
    pub colours: bool,
    /// Whether normals are coded.
    pub normals: bool,
    /// Stream size in bytes.
    pub total_bytes: usize,
    /// Seconds to decode the whole stream.
    pub decode_seconds: f64,
    /// Structure bits per particle at `N = R` (level chunk payloads only).
    pub structure_bits_per_particle: f64,
    /// The paper's §7.1 estimate at `N = R`: 61/12 ≈ 5.08.
    pub paper_estimate: f64,
    /// All bits per particle at the stream's full precision.
    pub bits_per_particle: f64,
    /// Per level, coarsest first.
    pub levels: Vec<LevelStats>,
}

/// Decodes and triangulates every level of a whole stream and gathers the
/// columns of Table 1 of the paper per level (nodes, eliminated nodes,
/// phantoms, triangles, configurations, bits per particle).
///
/// Errors: as [`decode`](crate::decode). Cost: a decode plus one
/// triangulation per level (about twice the finest level's).
pub fn stream_stats(bytes: &[u8], opts: &TriangulateOptions) -> Result<StreamStats> {
    let t0 = Instant::now();
    let d = decode(bytes, &DecodeOptions::default())?;
    let decode_seconds = t0.elapsed().as_secs_f64();
    let Header {
        mode,
        depth,
        precision,
        particles,
        colours,
        normals,
        ..
    } = d.header;
    let mut levels = Vec::new();
    let mut new_so_far = 0usize;
    for r in 0..d.levels.len() {
        let lv = &d.levels[r];
        let s = d.surface(r as u8)?;
        let t = triangulate(&s, opts);
        let kept = lv.kept();
        let with_particles: std::collections::BTreeSet<u32> = lv
            .particle
            .iter()
            .copied()
            .filter(|&p| p != crate::ordering::NO_PARTICLE)
            .collect();
        let max_id = with_particles
            .iter()
            .next_back()
            .map_or(0, |m| *m as usize + 1);
        let new_particles = max_id.saturating_sub(new_so_far);
        new_so_far = new_so_far.max(max_id);
        levels.push(LevelStats {
            level: r as u8,
            on_nodes: kept,
            eliminated: d.eliminated[r],
            phantoms: lv.phantoms(),
            new_particles,
            triangles: t.stats.triangles,
            non_manifold_configurations: t.stats.fallbacks,
            non_manifold_triangles: non_manifold_triangles(&t.mesh),
            distribution: t.stats.distribution(),
            configurations: t.stats.configurations.clone(),
            disambiguated: t.stats.disambiguated,
            triangulate_seconds: t.stats.seconds,
            structure_bytes: d.structure_bytes[r],
            bytes_so_far: d.bytes_per_level[r],
            bits_per_particle: d.bytes_per_level[r] as f64 * 8.0 / kept.max(1) as f64,
        });
    }
    let structure: usize = d.structure_bytes.iter().sum();
    Ok(StreamStats {
        mode: mode.name().into(),
        depth,
        precision,
        particles,
        colours,
        normals,
        total_bytes: bytes.len(),
        decode_seconds,
        structure_bits_per_particle: structure as f64 * 8.0 / f64::from(particles.max(1)),
        paper_estimate: 61.0 / 12.0,
        bits_per_particle: bytes.len() as f64 * 8.0 / f64::from(particles.max(1)),
        levels,
    })
}

impl std::fmt::Display for StreamStats {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        writeln!(
            f,
            "mode {}  R = {}  N = {}  particles {}  {} bytes  decode {:.3} s",
            self.mode,
            self.depth,
            self.precision,
            self.particles,
            self.total_bytes,
            self.decode_seconds
        )?;
        writeln!(
            f,
            "structure {:.2} bits/particle at N = R (paper's estimate {:.2}), {:.2} bits/particle in all",
            self.structure_bits_per_particle, self.paper_estimate, self.bits_per_particle
        )?;
        writeln!(
            f,
            "{:>3} {:>9} {:>10} {:>8} {:>10} {:>8} {:>8} {:>7} {:>7} {:>7} {:>7} {:>8} {:>10} {:>8}",
            "r",
            "ON k_r",
            "eliminated",
            "phantoms",
            "triangles",
            "non-man",
            "nm-tris",
            "C1-3%",
            "C4-5%",
            "C6%",
            "C>6%",
            "time s",
            "bytes",
            "bits/p"
        )?;
        for l in &self.levels {
            writeln!(
                f,
                "{:>3} {:>9} {:>10} {:>8} {:>10} {:>8} {:>8} {:>7.2} {:>7.2} {:>7.2} {:>7.2} {:>8.3} {:>10} {:>8.2}",
                l.level,
                l.on_nodes,
                l.eliminated,
                l.phantoms,
                l.triangles,
                l.non_manifold_configurations,
                l.non_manifold_triangles,
                l.distribution[0],
                l.distribution[1],
                l.distribution[2],
                l.distribution[3],
                l.triangulate_seconds,
                l.bytes_so_far,
                l.bits_per_particle
            )?;
        }
        Ok(())
    }
}

/// Triangles incident to an edge that more than two triangles use (the
/// strict count, [`lodkit_mesh::topology::non_manifold_face_count`];
/// Table 1 counts non-manifold *local triangulations*, see
/// [`TriangulationStats::fallbacks`]).
///
/// Cost: one sort of the `3 · faces` edge keys.
pub fn non_manifold_triangles(mesh: &TriMesh) -> usize {
    lodkit_mesh::topology::non_manifold_face_count(mesh)
}
