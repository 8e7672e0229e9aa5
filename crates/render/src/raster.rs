//! Rasterisation into a band of the sample buffer: edge functions with the
//! top-left fill rule, perspective-correct barycentrics and a depth test.
//!
//! Edge functions are evaluated on snapped `i64` coordinates
//! ([`clip`](crate::clip)), so they are exact: two triangles sharing an
//! edge compute exactly opposite values on it, and the top-left rule gives
//! every sample on a shared edge to exactly one of them (no cracks, no
//! double coverage). The buffer stores, per sample, what covers it nearest
//! (face or point id, barycentrics, inverse depth); colour comes later in
//! [`shade`](crate::shade), once per visible sample.

use glam::Vec3;

use crate::clip::{ONE, ScreenTri};

/// Id of a sample nothing covers.
pub(crate) const EMPTY: u32 = u32::MAX;

/// A horizontal band of the sample buffer: rows `y0 .. y0 + rows` of an
/// image `width` samples wide.
pub(crate) struct Band {
    pub width: usize,
    pub y0: usize,
    pub rows: usize,
    /// Face (or point) index of the nearest surface, or [`EMPTY`].
    pub id: Vec<u32>,
    /// Inverse depth `1/z` of the nearest surface (0 = nothing: infinitely far).
    pub inv_z: Vec<f32>,
    /// Barycentric coordinates of the sample in face `id` (corners 0, 1, 2).
    pub bary: Vec<Vec3>,
}

impl Band {
    pub fn new(width: usize, y0: usize, rows: usize) -> Band {
        let n = width * rows;
        Band {
            width,
            y0,
            rows,
            id: vec![EMPTY; n],
            inv_z: vec![0.0; n],
            bary: vec![Vec3::ZERO; n],
        }
    }

    /// Draws one screen triangle. Either winding is drawn (no culling):
    /// scans are open surfaces whose inside is seen through their holes.
    /// At equal depth the triangle drawn first keeps the sample, so the
    /// result depends on the face order only, never on timing.
    pub fn triangle(&mut self, t: &ScreenTri) {
        let (mut x, mut y, mut iz, mut b) = (t.x, t.y, t.inv_z, t.bary);
        let edge = |ax: i64, ay: i64, bx: i64, by: i64, px: i64, py: i64| {
            (bx - ax) * (py - ay) - (by - ay) * (px - ax)
        };
        let mut area = edge(x[0], y[0], x[1], y[1], x[2], y[2]);
        if area == 0 {
            return;
        }
        if area < 0 {
            x.swap(1, 2);
            y.swap(1, 2);
            iz.swap(1, 2);
            b.swap(1, 2);
            area = -area;
        }
        let (x0, x1) = (
            x.iter().min().copied().unwrap_or(0),
            x.iter().max().copied().unwrap_or(0),
        );
        let (r0, r1) = t.rows();
        let row_lo = r0.max(self.y0 as i64);
        let row_hi = r1.min((self.y0 + self.rows) as i64 - 1);
        let col_lo = (x0 - ONE / 2).div_euclid(ONE).max(0);
        let col_hi = ((x1 - ONE / 2).div_euclid(ONE) + 1).min(self.width as i64 - 1);
        if row_lo > row_hi || col_lo > col_hi {
            return;
        }
        // Edge i runs from corner i+1 to corner i+2 and weighs corner i.
        // With a positive area (clockwise on the y-down screen) an edge is
        // top-left when it goes up (dy < 0), or right along a horizontal
        // top (dy == 0, dx > 0); other edges exclude their own samples.
        let mut dx = [0i64; 3];
        let mut dy = [0i64; 3];
        let mut bias = [0i64; 3];
        let (px, py) = (col_lo * ONE + ONE / 2, row_lo * ONE + ONE / 2);
        let mut e_row = [0i64; 3];
        for i in 0..3 {
            let (a, c) = ((i + 1) % 3, (i + 2) % 3);
            dx[i] = x[c] - x[a];
            dy[i] = y[c] - y[a];
            let top_left = dy[i] < 0 || (dy[i] == 0 && dx[i] > 0);
            bias[i] = if top_left { 0 } else { -1 };
            e_row[i] = edge(x[a], y[a], x[c], y[c], px, py) + bias[i];
        }
        let inv_area = 1.0 / area as f64;
        for row in row_lo..=row_hi {
            let base = (row as usize - self.y0) * self.width;
            let mut e = e_row;
            for col in col_lo..=col_hi {
                if (e[0] | e[1] | e[2]) >= 0 {
                    let l = [
                        ((e[0] - bias[0]) as f64 * inv_area) as f32,
                        ((e[1] - bias[1]) as f64 * inv_area) as f32,
                        ((e[2] - bias[2]) as f64 * inv_area) as f32,
                    ];
                    let w = [l[0] * iz[0], l[1] * iz[1], l[2] * iz[2]];
                    let z = w[0] + w[1] + w[2];
                    let s = base + col as usize;
                    if z > self.inv_z[s] {
                        self.inv_z[s] = z;
                        self.id[s] = t.face;
                        self.bary[s] = (b[0] * w[0] + b[1] * w[1] + b[2] * w[2]) / z;
                    }
                }
                for i in 0..3 {
                    e[i] -= dy[i] * ONE;
                }
            }
            for i in 0..3 {
                e_row[i] += dx[i] * ONE;
            }
        }
    }

    /// Draws point `id` as a disc of `radius` samples centred at sample
    /// coordinates `(cx, cy)` at inverse depth `inv_z`. A disc smaller
    /// than a sample still covers the sample nearest its centre.
    pub fn splat(&mut self, id: u32, cx: f32, cy: f32, radius: f32, inv_z: f32) {
        let r = radius.max(std::f32::consts::FRAC_1_SQRT_2);
        let row_lo = ((cy - r - 0.5).floor() as i64).max(self.y0 as i64);
        let row_hi = ((cy + r - 0.5).ceil() as i64).min((self.y0 + self.rows) as i64 - 1);
        let col_lo = ((cx - r - 0.5).floor() as i64).max(0);
        let col_hi = ((cx + r - 0.5).ceil() as i64).min(self.width as i64 - 1);
        for row in row_lo..=row_hi {
            let dy = row as f32 + 0.5 - cy;
            for col in col_lo..=col_hi {
                let dx = col as f32 + 0.5 - cx;
                if dx * dx + dy * dy <= r * r {
                    let s = (row as usize - self.y0) * self.width + col as usize;
                    if inv_z > self.inv_z[s] {
                        self.inv_z[s] = inv_z;
                        self.id[s] = id;
                    }
                }
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn tri(face: u32, p: [(i64, i64); 3]) -> ScreenTri {
        ScreenTri {
            face,
            x: [p[0].0 * ONE, p[1].0 * ONE, p[2].0 * ONE],
            y: [p[0].1 * ONE, p[1].1 * ONE, p[2].1 * ONE],
            inv_z: [1.0; 3],
            bary: [Vec3::X, Vec3::Y, Vec3::Z],
        }
    }

    /// A square split along its diagonal, in both windings: every sample
    /// inside is covered exactly once (the top-left rule), none outside.
    #[test]
    fn shared_edges_cover_each_sample_once() {
        for flip in [false, true] {
            let mut b = Band::new(16, 0, 16);
            let mut count = vec![0u32; 256];
            let mut t1 = tri(0, [(2, 2), (12, 2), (12, 12)]);
            let mut t2 = tri(1, [(2, 2), (12, 12), (2, 12)]);
            if flip {
                t1.x.swap(1, 2);
                t1.y.swap(1, 2);
                t2.x.swap(1, 2);
                t2.y.swap(1, 2);
            }
            for t in [t1, t2] {
                b.id.fill(EMPTY);
                b.inv_z.fill(0.0);
                b.triangle(&t);
                for (s, &id) in b.id.iter().enumerate() {
                    count[s] += (id != EMPTY) as u32;
                }
            }
            // Sample centres at k + ½: columns and rows 2..=11 lie inside.
            for j in 0..16 {
                for i in 0..16 {
                    let inside = (2..12).contains(&i) && (2..12).contains(&j);
                    assert_eq!(count[j * 16 + i], inside as u32, "({i}, {j}) flip {flip}");
                }
            }
        }
    }

    #[test]
    fn nearer_triangle_wins_and_ties_keep_the_first() {
        let mut b = Band::new(8, 0, 8);
        let mut far = tri(0, [(0, 0), (8, 0), (0, 8)]);
        far.inv_z = [0.5; 3];
        let mut near = tri(1, [(0, 0), (8, 0), (0, 8)]);
        near.inv_z = [1.0; 3];
        b.triangle(&far);
        b.triangle(&near);
        b.triangle(&far);
        assert_eq!(b.id[0], 1);
        let tie = tri(2, [(0, 0), (8, 0), (0, 8)]);
        b.triangle(&tie);
        assert_eq!(b.id[0], 1);
    }
}
