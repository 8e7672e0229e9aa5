//! Summed-area table of a silhouette: the number of object pixels in any
//! rectangle from four reads, so a cube's footprint is classified in
//! constant time whatever its size (Crow 1984; the carvers of Szeliski
//! 1993 and Schmitt & Yemez 1999 test footprints the same way, with
//! quadtrees of the masks).

/// Counts of object pixels: `table[(y) * (w + 1) + x]` is the count in
/// `[0, x) × [0, y)`.
#[derive(Debug, Clone)]
pub struct Sat {
    width: u32,
    height: u32,
    table: Vec<u32>,
}

impl Sat {
    /// The table of a `width × height` silhouette (row-major flags).
    /// Cost: one pass, `4 (w + 1)(h + 1)` bytes.
    pub fn new(width: u32, height: u32, silhouette: &[bool]) -> Sat {
        let (w, h) = (width as usize, height as usize);
        let stride = w + 1;
        let mut table = vec![0u32; stride * (h + 1)];
        for y in 0..h {
            let mut row = 0u32;
            for x in 0..w {
                row += u32::from(silhouette[y * w + x]);
                table[(y + 1) * stride + x + 1] = table[y * stride + x + 1] + row;
            }
        }
        Sat {
            width,
            height,
            table,
        }
    }

    /// Image width.
    pub fn width(&self) -> u32 {
        self.width
    }

    /// Image height.
    pub fn height(&self) -> u32 {
        self.height
    }

    /// Object pixels in the whole image.
    pub fn total(&self) -> u64 {
        u64::from(*self.table.last().unwrap_or(&0))
    }

    /// Object pixels in columns `x0..=x1`, rows `y0..=y1`, clipped to
    /// the image (pixels outside it count as background).
    pub fn count(&self, x0: i64, y0: i64, x1: i64, y1: i64) -> u64 {
        let (w, h) = (i64::from(self.width), i64::from(self.height));
        let (x0, y0) = (x0.max(0), y0.max(0));
        let (x1, y1) = ((x1 + 1).min(w), (y1 + 1).min(h));
        if x0 >= x1 || y0 >= y1 {
            return 0;
        }
        let s = self.width as usize + 1;
        let at = |x: i64, y: i64| i64::from(self.table[y as usize * s + x as usize]);
        (at(x1, y1) - at(x0, y1) - at(x1, y0) + at(x0, y0)) as u64
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn counts_match_a_direct_sum_and_clip_to_the_image() {
        let (w, h) = (7u32, 5u32);
        let s: Vec<bool> = (0..w * h).map(|i| (i * 7 + i / 3) % 3 == 0).collect();
        let sat = Sat::new(w, h, &s);
        for (x0, y0, x1, y1) in [
            (0, 0, 6, 4),
            (2, 1, 4, 3),
            (3, 3, 3, 3),
            (-5, -5, 20, 20),
            (5, 0, 2, 4),
        ] {
            let mut n = 0;
            for y in y0.max(0)..=y1.min(4) {
                for x in x0.max(0)..=x1.min(6) {
                    n += u64::from(s[(y * 7 + x) as usize]);
                }
            }
            assert_eq!(sat.count(x0, y0, x1, y1), n, "{x0} {y0} {x1} {y1}");
        }
        assert_eq!(sat.total(), s.iter().filter(|&&b| b).count() as u64);
    }
}
