//! Face-neighbour links between the nodes of one level: the entropy
//! contexts of [`super::levels`] and [`super::precision_layers`] read their
//! neighbours through them, built level by level from the parent's links.

/// No node across this face (a [`Links`] row's marker).
pub(crate) const NONE: u32 = u32::MAX;

/// Face-neighbour links of one level, for the entropy contexts: `nb[i][d]`
/// is the index of the node across face `d` of node `i` (`d = a` towards
/// `−a`, `d = 3 + a` towards `+a`) or `NONE`. Built from the parent
/// level's links while the level is coded (a child's neighbour is a
/// sibling or a child of its parent's neighbour), so no context needs a
/// hash or a search: the coder of level `r` reads only arrays.
///
/// The links of level `R` serve only
/// [`crate::coding::precision_layers::particle_faces`], which reads each
/// once: [`code_level`] leaves them unbuilt there (`pending`), and they are
/// derived on the fly from what builds them.
#[derive(Debug, Clone, Default)]
pub struct Links {
    pub(super) nb: Vec<[u32; 6]>,
    pub(super) pending: Option<Pending>,
}

/// What [`child_links`] builds a level's links from.
#[derive(Debug, Clone)]
pub(super) struct Pending {
    pub(super) parent_nb: Vec<[u32; 6]>,
    pub(super) masks: Vec<u8>,
    pub(super) firsts: Vec<u32>,
    pub(super) n: usize,
}

impl Links {
    /// The links of level 0: the root has no neighbour.
    pub fn root() -> Links {
        Links {
            nb: vec![[NONE; 6]],
            pending: None,
        }
    }

    /// Nodes the links describe.
    pub(crate) fn len(&self) -> usize {
        self.pending.as_ref().map_or(self.nb.len(), |p| p.n)
    }

    /// Calls `f(i, links of node i)` for every node in order, deriving
    /// pending links on the fly.
    #[inline(always)]
    pub(crate) fn for_each_row(&self, mut f: impl FnMut(usize, [u32; 6])) {
        match &self.pending {
            Some(p) => each_child_links(&p.parent_nb, &p.masks, &p.firsts, f),
            None => {
                for (i, row) in self.nb.iter().enumerate() {
                    f(i, *row);
                }
            }
        }
    }

    /// Builds links left pending.
    pub(super) fn materialise(&mut self) {
        if let Some(p) = self.pending.take() {
            self.nb = Vec::with_capacity(p.n);
            each_child_links(&p.parent_nb, &p.masks, &p.firsts, |_, row| {
                self.nb.push(row)
            });
        }
    }
}

/// The links of the children level: a child's neighbour across a face is
/// a sibling, or a child of the parent's neighbour across that face.
pub(super) fn child_links(parent_nb: &[[u32; 6]], masks: &[u8], firsts: &[u32], n: usize) -> Links {
    let mut nb = Vec::with_capacity(n);
    each_child_links(parent_nb, masks, firsts, |_, row| nb.push(row));
    debug_assert_eq!(nb.len(), n);
    Links { nb, pending: None }
}

/// Calls `f(i, links of child i)` for the children level's nodes in order.
///
/// Which children exist is data: each link is selected with masks (the
/// child's rank among its siblings from a table), not branched on.
#[inline(always)]
fn each_child_links(
    parent_nb: &[[u32; 6]],
    masks: &[u8],
    firsts: &[u32],
    mut f: impl FnMut(usize, [u32; 6]),
) {
    let mut i = 0;
    for p in 0..masks.len() {
        let m = masks[p];
        if m == 0 {
            continue;
        }
        let first = firsts[p];
        // Children masks and first indices of the parent's face neighbours
        // (an empty mask for a missing one; index 0 stands in for it).
        let mut nm = [0u8; 6];
        let mut nf = [0u32; 6];
        for d in 0..6 {
            let q = parent_nb[p][d];
            let present = q != NONE;
            let q = if present { q as usize } else { 0 };
            nm[d] = masks[q] & u8::from(present).wrapping_neg();
            nf[d] = firsts[q];
        }
        let mut rest = m;
        while rest != 0 {
            let k = rest.trailing_zeros() as usize;
            rest &= rest - 1;
            let mut row = [NONE; 6];
            for (d, link) in row.iter_mut().enumerate() {
                let bit = 1usize << (d % 3);
                let towards_plus = d >= 3;
                let inside = (k & bit != 0) != towards_plus;
                let (qm, qf) = if inside { (m, first) } else { (nm[d], nf[d]) };
                let j = k ^ bit;
                let index = qf + u32::from(RANK[usize::from(qm) << 3 | j]);
                *link = if qm >> j & 1 == 1 { index } else { NONE };
            }
            f(i, row);
            i += 1;
        }
    }
}

/// `RANK[8 · mask + j]`: the children of `mask` below child `j` — the
/// index of child `j` among its siblings (a population count, which the
/// baseline x86-64 instruction set lacks).
pub(super) static RANK: [u8; 2048] = {
    let mut t = [0u8; 2048];
    let mut i = 0;
    while i < 2048 {
        t[i] = ((i >> 3) & ((1 << (i & 7)) - 1)).count_ones() as u8;
        i += 1;
    }
    t
};
