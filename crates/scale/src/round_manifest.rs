//! A round's manifest and the checks of a staging folder before a run
//! trusts it: the partition's record (bounding box, reach, per block its
//! faces and input checksum, itself checksummed), and a folder whose
//! blocks, outputs and links are checked against it (anything that does
//! not hold is made again).

use std::path::Path;

use glam::Vec3;

use crate::partition::{block_input, block_output};
use crate::soup::{self, Layout, Sum};
use crate::staging::io_err;

/// A round folder's record that its partition is complete: the bounding
/// box, the round's [`Cuts::reach`], and per block its faces and the
/// [`Sum`] of its input file.
pub(crate) struct Manifest {
    pub min: Vec3,
    pub max: Vec3,
    pub reach: f32,
    pub counts: Vec<u64>,
    pub sums: Vec<Sum>,
}

/// The manifest's text: the box and reach as the bits of seven `f32`s,
/// one `FACES SUM` line per block, and `end SUM`, the checksum of the
/// lines before it (a manifest cut short or edited is no manifest).
pub(crate) fn manifest_text(m: &Manifest) -> String {
    let mut s = String::new();
    for c in m.min.to_array().into_iter().chain(m.max.to_array()) {
        s.push_str(&format!("{:08x} ", c.to_bits()));
    }
    s.push_str(&format!("{:08x}\n", m.reach.to_bits()));
    for (c, h) in m.counts.iter().zip(&m.sums) {
        s.push_str(&format!("{c} {:016x}\n", h.0));
    }
    let mut h = Sum::NEW;
    h.add(s.as_bytes());
    s.push_str(&format!("end {:016x}\n", h.0));
    s
}

/// Writes a round's manifest atomically: its presence means the round's
/// block inputs are complete.
pub(crate) fn write_manifest(dir: &Path, m: &Manifest) -> std::io::Result<()> {
    soup::write_small(&dir.join("parted"), manifest_text(m).as_bytes())
}

/// The manifest of a round folder of `blocks` blocks; `None` if there is
/// none, or it is not one this lodkit wrote whole: a link, a checksum
/// that does not hold, a box or reach that is not finite (or a box turned
/// inside out), another number of blocks. The round is then partitioned
/// again, or the folder redone ([`check_staging`]).
pub(crate) fn read_manifest(dir: &Path, blocks: usize) -> Option<Manifest> {
    let path = dir.join("parted");
    let meta = std::fs::symlink_metadata(&path).ok()?;
    // 50 bytes a block at most; anything larger is not a manifest.
    if !meta.is_file() || meta.len() > 64 * (blocks as u64 + 2) {
        return None;
    }
    let s = std::fs::read_to_string(&path).ok()?;
    let body_end = s.trim_end_matches('\n').rfind('\n')? + 1;
    let (body, end) = s.split_at(body_end);
    let mut h = Sum::NEW;
    h.add(body.as_bytes());
    if end != format!("end {:016x}\n", h.0) {
        return None;
    }
    let mut lines = body.lines();
    let bb: Vec<f32> = lines
        .next()?
        .split_whitespace()
        .map(|w| u32::from_str_radix(w, 16).map(f32::from_bits))
        .collect::<Result<_, _>>()
        .ok()?;
    if bb.len() != 7 || !bb.iter().all(|v| v.is_finite()) || bb[6] < 0.0 {
        return None;
    }
    let (min, max) = (
        Vec3::new(bb[0], bb[1], bb[2]),
        Vec3::new(bb[3], bb[4], bb[5]),
    );
    if !min.cmple(max).all() {
        return None;
    }
    let mut counts = Vec::with_capacity(blocks);
    let mut sums = Vec::with_capacity(blocks);
    for l in lines {
        let (c, h) = l.split_once(' ')?;
        counts.push(c.parse().ok()?);
        sums.push(Sum(u64::from_str_radix(h, 16).ok()?));
    }
    (counts.len() == blocks).then_some(Manifest {
        min,
        max,
        reach: bb[6],
        counts,
        sums,
    })
}

/// Makes what an earlier run left in the staging folder trustworthy
/// before any of it is used, redoing what is not: the rounds `r0`, `r1`,
/// … must follow on each other, each with its manifest ([`read_manifest`])
/// but for the last, whose partition was cut short (it is removed and
/// made again); in the last complete round, each block is done (its
/// output intact, [`soup::is_intact`]; an output that is not is removed)
/// or has its input at the size and checksum the manifest records. Links
/// and anything else lodkit does not write are refused by starting over.
/// Anything else wrong (a block neither done nor with its input, a hole
/// in the rounds) empties the folder but its lock, so the run starts over:
/// the same bytes come out, never different ones. Cost: one read of the
/// files of the last round (only when resuming).
pub(crate) fn check_staging(staging: &Path, blocks: usize, layout: Layout) -> Result<(), String> {
    let trusted = |staging: &Path| -> Option<()> {
        let mut rounds = Vec::new();
        for e in std::fs::read_dir(staging).ok()? {
            let e = e.ok()?;
            let name = e.file_name();
            let name = name.to_str()?;
            if name == "lock" {
                continue;
            }
            let r: u32 = name.strip_prefix('r')?.parse().ok()?;
            if !e.file_type().ok()?.is_dir() || name != format!("r{r}") {
                return None;
            }
            rounds.push(r);
        }
        rounds.sort_unstable();
        if rounds.iter().enumerate().any(|(i, &r)| r as usize != i) {
            return None;
        }
        let complete = rounds
            .iter()
            .take_while(|&&r| read_manifest(&staging.join(format!("r{r}")), blocks).is_some())
            .count();
        match rounds.len() - complete {
            0 => {}
            // A partition cut short: made again.
            1 => std::fs::remove_dir_all(staging.join(format!("r{complete}"))).ok()?,
            _ => return None,
        }
        let Some(last) = complete.checked_sub(1) else {
            return Some(());
        };
        let dir = staging.join(format!("r{last}"));
        for e in std::fs::read_dir(&dir).ok()? {
            if !e.ok()?.file_type().ok()?.is_file() {
                return None;
            }
        }
        let m = read_manifest(&dir, blocks)?;
        for (b, (&count, &sum)) in m.counts.iter().zip(&m.sums).enumerate() {
            if count == 0 {
                continue;
            }
            let out = block_output(&dir, b);
            if soup::is_intact(&out, layout) {
                continue;
            }
            if std::fs::symlink_metadata(&out).is_ok() {
                std::fs::remove_file(&out).ok()?;
            }
            let input = block_input(&dir, b);
            let ok = std::fs::symlink_metadata(&input)
                .is_ok_and(|m| m.is_file() && m.len() == count * layout.face_bytes())
                && Sum::of_file(&input).is_ok_and(|(s, _)| s == sum);
            if !ok {
                return None;
            }
        }
        Some(())
    };
    if trusted(staging).is_some() {
        return Ok(());
    }
    // Start over: everything but the lock goes (links removed, never
    // followed).
    let entries = std::fs::read_dir(staging).map_err(io_err(staging))?;
    for e in entries {
        let e = e.map_err(io_err(staging))?;
        if e.file_name() == "lock" {
            continue;
        }
        let p = e.path();
        let r = if e.file_type().is_ok_and(|t| t.is_dir()) {
            std::fs::remove_dir_all(&p)
        } else {
            std::fs::remove_file(&p)
        };
        r.map_err(io_err(&p))?;
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A manifest reads back as written; one cut short, edited, with a
    /// box that is not finite or inside out, or for another grid, is no
    /// manifest (the round is made again).
    #[test]
    fn manifests_read_back_and_damaged_ones_are_none() {
        let d = tempfile::tempdir().unwrap();
        let m = Manifest {
            min: Vec3::new(-1.0, 0.5, 2.0),
            max: Vec3::new(3.0, 4.5, 6.25),
            reach: 0.125,
            counts: vec![3, 0, 7],
            sums: vec![Sum(1), Sum::NEW, Sum(u64::MAX)],
        };
        write_manifest(d.path(), &m).unwrap();
        let r = read_manifest(d.path(), 3).unwrap();
        assert_eq!(
            (r.min, r.max, r.reach, &r.counts, &r.sums),
            (m.min, m.max, m.reach, &m.counts, &m.sums)
        );
        assert!(read_manifest(d.path(), 8).is_none());
        let text = manifest_text(&m);
        let put = |t: &str| std::fs::write(d.path().join("parted"), t).unwrap();
        // Cut short, one count edited.
        put(&text[..text.len() - 30]);
        assert!(read_manifest(d.path(), 3).is_none());
        put(&text.replace("\n7 ", "\n8 "));
        assert!(read_manifest(d.path(), 3).is_none());
        // NaN or infinite bounds, an inside-out box, a negative reach,
        // each with a checksum that holds.
        for (min, max, reach) in [
            (Vec3::new(f32::NAN, 0.0, 0.0), Vec3::ONE, 0.1),
            (Vec3::ZERO, Vec3::new(1.0, f32::INFINITY, 1.0), 0.1),
            (Vec3::ONE, Vec3::ZERO, 0.1),
            (Vec3::ZERO, Vec3::ONE, -1.0),
            (Vec3::ZERO, Vec3::ONE, f32::NAN),
        ] {
            put(&manifest_text(&Manifest {
                min,
                max,
                reach,
                ..m_clone(&m)
            }));
            assert!(read_manifest(d.path(), 3).is_none(), "{min} {max} {reach}");
        }
    }

    fn m_clone(m: &Manifest) -> Manifest {
        Manifest {
            min: m.min,
            max: m.max,
            reach: m.reach,
            counts: m.counts.clone(),
            sums: m.sums.clone(),
        }
    }
}
