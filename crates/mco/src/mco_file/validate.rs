//! The checks every loaded model passes before it is used, for both
//! versions: every index extraction follows is in range, and the tables
//! agree with each other.

use super::format::{MAX_NODE_TRIANGLES, MAX_PATCH_SUBS};
use crate::model::McoModel;

/// Every index extraction follows must be in range, and the tables must
/// agree with each other (the tree, the LOD tables, finite positions,
/// normals and metrics). `O(size)`.
pub(crate) fn validate(m: &McoModel) -> std::result::Result<(), String> {
    let (v, n) = (m.vertices.len() as u64, m.nodes.len() as u64);
    if n == 0 {
        return Err("the model has no nodes".into());
    }
    if let Some(i) = m.tris.iter().position(|&x| x as u64 >= v) {
        return Err(format!("triangle index {i} points past the {v} vertices"));
    }
    if !m.tris.len().is_multiple_of(3) {
        return Err("the triangle index count is not a multiple of 3".into());
    }
    for (i, nd) in m.nodes.iter().enumerate() {
        let bad = |what: &str| Err(format!("node {i}: {what} out of range"));
        if (nd.parent != u32::MAX && nd.parent as u64 >= n) || (i == 0) != (nd.parent == u32::MAX) {
            return bad("parent");
        }
        if nd.first_child as u64 + nd.child_count as u64 > n
            || (nd.child_count > 0 && nd.first_child as usize <= i)
        {
            return bad("children");
        }
        if nd.tri_start as u64 + 3 * nd.tri_count as u64 > m.tris.len() as u64
            || nd.tri_count as usize > MAX_NODE_TRIANGLES
        {
            return bad("triangles");
        }
        if nd.patch_start as u64 + nd.patch_count as u64 > m.patches.len() as u64
            || nd.patch_count > 6
        {
            return bad("patches");
        }
        if nd.deps_start as u64 + nd.deps_count as u64 > m.deps.len() as u64 {
            return bad("balance dependencies");
        }
        if nd.level as u32 > m.grid.depth {
            return bad("level");
        }
    }
    for (i, p) in m.patches.iter().enumerate() {
        if p.coarse as u64 >= n
            || p.subs_start as u64 + p.subs_count as u64 > m.subs.len() as u64
            || p.subs_count as usize > MAX_PATCH_SUBS
        {
            return Err(format!("patch {i} out of range"));
        }
    }
    if m.subs.iter().any(|s| s[0] as u64 >= v || s[1] as u64 >= v) {
        return Err("a crack-patch vertex is out of range".into());
    }
    if m.deps.iter().any(|&x| x as u64 >= n) || m.lod.iter().any(|&x| x as u64 >= n) {
        return Err("a node reference is out of range".into());
    }
    if m.groups.first() != Some(&0)
        || m.groups.windows(2).any(|w| w[0] > w[1])
        || *m.groups.last().expect("non-empty") as usize > m.lod.len()
    {
        return Err("the LOD groups are not an increasing prefix of the LOD array".into());
    }
    if m.acc.len() != m.groups.len() {
        return Err("the accumulation table does not match the LOD numbers".into());
    }
    if m.prio.len() != m.nodes.len() || m.metric.len() != m.nodes.len() {
        return Err("per-node arrays do not match the node count".into());
    }
    if m.prio
        .iter()
        .any(|&k| k != u32::MAX && (k == 0 || k as usize >= m.groups.len()))
    {
        return Err("a priority number is out of range".into());
    }
    if m.vertices.normals.len() != m.vertices.positions.len()
        || m.vertices.colors.len() != m.vertices.positions.len()
    {
        return Err("vertex arrays differ in length".into());
    }
    if let Some(i) = (m.vertices.positions.iter().zip(&m.vertices.normals))
        .position(|(p, n)| !(p.is_finite() && n.is_finite()))
    {
        return Err(format!("vertex {i}: position or normal is not finite"));
    }
    if let Some(i) = m.metric.iter().position(|x| !x.is_finite()) {
        return Err(format!("node {i}: LOD metric is not finite"));
    }
    validate_tree(m)?;
    validate_lod_tables(m)
}

/// The nodes form one tree: each node's children follow it, name it as
/// their parent, and are octants of its cube one level down; every node
/// but the root is listed as a child exactly once. (Run after
/// [`validate`]'s range checks.)
fn validate_tree(m: &McoModel) -> std::result::Result<(), String> {
    let mut listed = 0u64;
    for (i, nd) in m.nodes.iter().enumerate() {
        for c in m.children(i as u32) {
            let cn = &m.nodes[c as usize];
            if cn.parent != i as u32 {
                return Err(format!(
                    "node {c}: its parent is {}, but node {i} lists it as a child",
                    cn.parent
                ));
            }
            if cn.level as u32 + 1 != nd.level as u32
                || (0..3).any(|a| cn.coord[a] >> 1 != nd.coord[a])
            {
                return Err(format!(
                    "node {c}: not an octant of its parent {i}'s cube one level down"
                ));
            }
        }
        listed += nd.child_count as u64;
    }
    if listed != m.nodes.len() as u64 - 1 {
        return Err(format!(
            "the nodes are not one tree: {listed} are children, {} expected",
            m.nodes.len() - 1
        ));
    }
    Ok(())
}

/// The LOD array, priority numbers, balance dependencies and the
/// accumulation table agree with each other and with the tree: LOD number
/// `k` expands `lod[groups[k-1]..groups[k]]` (at least one node), those
/// nodes and no others have priority number `k`, each has children, was
/// drawn before (its parent expanded at an earlier LOD number) and has its
/// balance dependencies expanded by then; and `acc[k]` is the triangle
/// count those expansions give, recomputed from the nodes' own counts.
/// (Run after [`validate`]'s range checks and [`validate_tree`].)
fn validate_lod_tables(m: &McoModel) -> std::result::Result<(), String> {
    let last = *m.groups.last().expect("non-empty") as usize;
    if last != m.lod.len() {
        return Err(format!(
            "the LOD groups cover {last} of the LOD array's {} entries",
            m.lod.len()
        ));
    }
    let numbered = m.prio.iter().filter(|&&k| k != u32::MAX).count();
    if numbered != m.lod.len() {
        return Err(format!(
            "{numbered} nodes have a priority number, the LOD array has {} entries",
            m.lod.len()
        ));
    }
    let mut tris = m.nodes[0].tri_count as u64;
    if m.acc[0] as u64 != tris {
        return Err(format!(
            "the triangle table gives {} triangles at LOD 0, the root has {tris}",
            m.acc[0]
        ));
    }
    for k in 1..m.groups.len() {
        if m.groups[k] == m.groups[k - 1] {
            return Err(format!("LOD {k} expands no node"));
        }
        for &n in m.group(k) {
            let nd = &m.nodes[n as usize];
            if m.prio[n as usize] != k as u32 {
                return Err(format!(
                    "LOD {k}: node {n} has priority number {}",
                    m.prio[n as usize]
                ));
            }
            if nd.child_count == 0 {
                return Err(format!("LOD {k}: node {n} has no children to expand"));
            }
            if nd.parent != u32::MAX && m.prio[nd.parent as usize] >= k as u32 {
                return Err(format!(
                    "LOD {k}: node {n} expands before its parent {}",
                    nd.parent
                ));
            }
            let deps = &m.deps[nd.deps_start as usize..][..nd.deps_count as usize];
            if let Some(d) = deps.iter().find(|&&d| m.prio[d as usize] > k as u32) {
                return Err(format!(
                    "LOD {k}: node {n} expands before its balance dependency {d}"
                ));
            }
            // `n` is drawn until now (parent expanded earlier, itself not).
            tris = tris.saturating_sub(nd.tri_count as u64);
            tris += m
                .children(n)
                .map(|c| m.nodes[c as usize].tri_count as u64)
                .sum::<u64>();
        }
        if m.acc[k] as u64 != tris {
            return Err(format!(
                "the triangle table gives {} triangles at LOD {k}, its nodes draw {tris}",
                m.acc[k]
            ));
        }
    }
    Ok(())
}
