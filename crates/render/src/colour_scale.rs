//! The heat-map colour scale: blue (0) → cyan → green → yellow → red (1).
//!
//! A rainbow in the manner of Google's Turbo (which fixed Jet's bands and
//! dark ends), written here from its idea rather than its table: six
//! anchor colours chosen by hand, joined by straight segments in the OKLab
//! perceptual space (Ottosson 2020), so equal steps of `t` inside a segment
//! look like equal colour steps and no false band appears where segments
//! meet. The ends are a clear blue and a clear red, never black, so a
//! distance of 0 and the maximum both read as colours on a dark or light
//! background.

/// Anchors at `t = 0, 0.2, 0.4, 0.6, 0.8, 1` (sRGB).
const ANCHORS: [[u8; 3]; 6] = [
    [38, 64, 196],
    [32, 142, 232],
    [36, 200, 168],
    [150, 220, 60],
    [250, 180, 40],
    [204, 28, 28],
];

/// The colour of `t` in `[0, 1]` (sRGB). `t` outside is clamped, NaN is
/// treated as 0. Deterministic; cost: a few cube roots.
pub fn colour_scale(t: f32) -> [u8; 3] {
    let t = if t.is_nan() { 0.0 } else { t.clamp(0.0, 1.0) };
    let x = t * (ANCHORS.len() - 1) as f32;
    let i = (x.floor() as usize).min(ANCHORS.len() - 2);
    let f = x - i as f32;
    let a = oklab(ANCHORS[i]);
    let b = oklab(ANCHORS[i + 1]);
    let m = [
        a[0] + (b[0] - a[0]) * f,
        a[1] + (b[1] - a[1]) * f,
        a[2] + (b[2] - a[2]) * f,
    ];
    srgb(m)
}

fn to_linear(c: u8) -> f32 {
    let c = c as f32 / 255.0;
    if c <= 0.04045 {
        c / 12.92
    } else {
        ((c + 0.055) / 1.055).powf(2.4)
    }
}

fn to_srgb(c: f32) -> u8 {
    let c = c.clamp(0.0, 1.0);
    let s = if c <= 0.003_130_8 {
        c * 12.92
    } else {
        1.055 * c.powf(1.0 / 2.4) - 0.055
    };
    (s * 255.0).round() as u8
}

/// sRGB → OKLab (Ottosson's published matrices).
fn oklab(c: [u8; 3]) -> [f32; 3] {
    let (r, g, b) = (to_linear(c[0]), to_linear(c[1]), to_linear(c[2]));
    let l = (0.412_221_46 * r + 0.536_332_55 * g + 0.051_445_995 * b).cbrt();
    let m = (0.211_903_5 * r + 0.680_699_5 * g + 0.107_396_96 * b).cbrt();
    let s = (0.088_302_46 * r + 0.281_718_85 * g + 0.629_978_7 * b).cbrt();
    [
        0.210_454_26 * l + 0.793_617_8 * m - 0.004_072_047 * s,
        1.977_998_5 * l - 2.428_592_2 * m + 0.450_593_7 * s,
        0.025_904_037 * l + 0.782_771_77 * m - 0.808_675_77 * s,
    ]
}

/// OKLab → sRGB (the inverse matrices), clamped to the gamut.
fn srgb(lab: [f32; 3]) -> [u8; 3] {
    let l = lab[0] + 0.396_337_78 * lab[1] + 0.215_803_76 * lab[2];
    let m = lab[0] - 0.105_561_346 * lab[1] - 0.063_854_17 * lab[2];
    let s = lab[0] - 0.089_484_18 * lab[1] - 1.291_485_5 * lab[2];
    let (l, m, s) = (l * l * l, m * m * m, s * s * s);
    [
        to_srgb(4.076_741_7 * l - 3.307_711_6 * m + 0.230_969_94 * s),
        to_srgb(-1.268_438 * l + 2.609_757_4 * m - 0.341_319_38 * s),
        to_srgb(-0.004_196_086_3 * l - 0.703_418_6 * m + 1.707_614_7 * s),
    ]
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn ends_are_blue_and_red_and_anchors_round_trip() {
        let lo = colour_scale(0.0);
        let hi = colour_scale(1.0);
        assert!(lo[2] > lo[0] && lo[2] > lo[1], "{lo:?}");
        assert!(hi[0] > hi[1] && hi[0] > hi[2], "{hi:?}");
        for (i, a) in ANCHORS.iter().enumerate() {
            let c = colour_scale(i as f32 / 5.0);
            for k in 0..3 {
                assert!(
                    (c[k] as i32 - a[k] as i32).abs() <= 1,
                    "{i}: {c:?} vs {a:?}"
                );
            }
        }
        assert_eq!(colour_scale(-3.0), lo);
        assert_eq!(colour_scale(7.0), hi);
        assert_eq!(colour_scale(f32::NAN), lo);
    }

    #[test]
    fn neighbouring_steps_are_close() {
        // 256 steps: no jump larger than a small fraction of the range.
        let mut prev = colour_scale(0.0);
        for i in 1..=256 {
            let c = colour_scale(i as f32 / 256.0);
            let d: i32 = (0..3)
                .map(|k| (c[k] as i32 - prev[k] as i32).abs())
                .max()
                .unwrap();
            assert!(d <= 12, "step {i}: {prev:?} → {c:?}");
            prev = c;
        }
    }
}
