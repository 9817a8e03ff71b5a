//! An environment map as a few directional lights, for the deterministic `shadows`
//! model: the median-cut algorithm of Debevec ("A Median Cut Algorithm for Light
//! Probe Sampling", SIGGRAPH 2005 poster; USC ICT technical report, 2006). The map's
//! energy per texel (luminance times the texel's solid angle, so weighted by `sin θ`)
//! is split `k` times: each region along its longer side (its width measured at the
//! row of its largest `sin θ`, as the sphere sees it) at the column or row that best
//! halves its energy, giving `2^k` regions of (nearly) equal energy; each becomes a
//! directional light towards its energy centroid (the energy-weighted mean of its
//! texels' unit directions, normalised: the same as Debevec's image-space centroid
//! for a small region, and without the azimuth's wrap-around for a wide one) carrying
//! its energy `Φ = ∫ L dω` over the region.

use std::f32::consts::PI;

use super::envmap::EnvMap;
use crate::color::luminance_f32;
use crate::math::Vec3;

/// Most splits [`EnvMap::median_cut`] takes (256 lights).
pub const MAX_MEDIAN_CUT_SPLITS: u32 = 8;

/// A region of texels: columns `x0..x1`, rows `y0..y1`.
#[derive(Clone, Copy, Debug)]
struct Region {
    x0: usize,
    x1: usize,
    y0: usize,
    y1: usize,
}

impl EnvMap {
    /// The map as `2^splits` directional lights (at most [`MAX_MEDIAN_CUT_SPLITS`]
    /// splits): per region, the unit world direction towards its energy centroid
    /// (the map's rotation applied) and its energy `Φ = Σ luminance · intensity · dω`
    /// over its texels (`dω = sin θ · (2π / w) · (π / h)`), the irradiance it gives a
    /// surface facing it. A region without energy gives no light, so a black map
    /// gives none.
    pub fn median_cut(&self, splits: u32) -> Vec<(Vec3, f32)> {
        (self.cut(splits).into_iter())
            .map(|(d, e, _)| (d, e))
            .collect()
    }

    /// The lights of [`EnvMap::median_cut`] (the same regions and directions) with
    /// their colour: per region the RGB power `Σ L_c · intensity · dω` over its texels
    /// for each channel `c`, so the lights carry the map's tint as well as its energy
    /// (their luminances are `median_cut`'s energies). The powers of all lights sum to
    /// the map's integral `∫ L dω` per channel.
    pub fn median_cut_rgb(&self, splits: u32) -> Vec<(Vec3, [f32; 3])> {
        (self.cut(splits).into_iter())
            .map(|(d, _, rgb)| (d, rgb))
            .collect()
    }

    /// The median cut's lights: direction, energy (luminance) and RGB power.
    fn cut(&self, splits: u32) -> Vec<(Vec3, f32, [f32; 3])> {
        let [w, h] = self.size().map(|s| s as usize);
        let d_omega = (2.0 * PI / w as f32) * (PI / h as f32);
        let sin: Vec<f32> = (0..h)
            .map(|y| (PI * (y as f32 + 0.5) / h as f32).sin())
            .collect();
        // Each texel's energy (before the intensity), and a summed-area table of it
        // (f64: millions of texels).
        let energy: Vec<f32> = (self.texels().iter().enumerate())
            .map(|(i, &t)| luminance_f32(t) * sin[i / w] * d_omega)
            .collect();
        let mut sat = vec![0.0f64; (w + 1) * (h + 1)];
        for y in 0..h {
            let mut row = 0.0f64;
            for x in 0..w {
                row += f64::from(energy[y * w + x]);
                sat[(y + 1) * (w + 1) + x + 1] = sat[y * (w + 1) + x + 1] + row;
            }
        }
        let sum = |r: &Region| {
            sat[r.y1 * (w + 1) + r.x1] - sat[r.y0 * (w + 1) + r.x1] - sat[r.y1 * (w + 1) + r.x0]
                + sat[r.y0 * (w + 1) + r.x0]
        };
        let mut regions = vec![Region {
            x0: 0,
            x1: w,
            y0: 0,
            y1: h,
        }];
        for _ in 0..splits.min(MAX_MEDIAN_CUT_SPLITS) {
            regions = (regions.iter())
                .flat_map(|r| split(r, &sin, w, h, &sum))
                .collect();
        }
        let rotation = self.rotation();
        (regions.iter())
            .filter_map(|r| {
                let mut c = [0.0f64; 3];
                let mut rgb = [0.0f64; 3];
                for y in r.y0..r.y1 {
                    let theta = PI * (y as f32 + 0.5) / h as f32;
                    let weight = f64::from(sin[y] * d_omega);
                    for x in r.x0..r.x1 {
                        let t = self.texels()[y * w + x];
                        for (p, v) in rgb.iter_mut().zip(t) {
                            *p += f64::from(v) * weight;
                        }
                        let e = f64::from(energy[y * w + x]);
                        if e == 0.0 {
                            continue;
                        }
                        let phi = 2.0 * PI * (x as f32 + 0.5) / w as f32 + rotation;
                        let d = [
                            theta.sin() * phi.cos(),
                            theta.sin() * phi.sin(),
                            theta.cos(),
                        ];
                        for (c, d) in c.iter_mut().zip(d) {
                            *c += e * f64::from(d);
                        }
                    }
                }
                let e = sum(r) as f32 * self.intensity();
                let dir = Vec3::new(c[0] as f32, c[1] as f32, c[2] as f32).normalize_or_zero();
                let rgb = rgb.map(|p| p as f32 * self.intensity());
                (e > 0.0 && dir != Vec3::ZERO).then_some((dir, e, rgb))
            })
            .collect()
    }

    /// The mean radiance's luminance over the sphere of directions (the intensity
    /// applied): the radiance of the uniform environment of the same energy.
    pub fn mean_luminance(&self) -> f32 {
        let [w, h] = self.size().map(|s| s as usize);
        let mut num = 0.0f64;
        let mut den = 0.0f64;
        for y in 0..h {
            let sin = f64::from((PI * (y as f32 + 0.5) / h as f32).sin());
            for t in &self.texels()[y * w..(y + 1) * w] {
                num += f64::from(luminance_f32(*t)) * sin;
                den += sin;
            }
        }
        (num / den) as f32 * self.intensity()
    }
}

/// Splits `r` in two along its longer side (width at its largest `sin θ` against
/// height) at the line that best halves its energy; a region of one texel along that
/// side is split along the other, one of one texel is kept whole.
fn split(
    r: &Region,
    sin: &[f32],
    w: usize,
    h: usize,
    sum: &impl Fn(&Region) -> f64,
) -> Vec<Region> {
    let widest = (r.y0..r.y1).map(|y| sin[y]).fold(0.0f32, f32::max);
    let width = (r.x1 - r.x0) as f32 * (2.0 * PI / w as f32) * widest;
    let height = (r.y1 - r.y0) as f32 * (PI / h as f32);
    let along_x = (width >= height && r.x1 - r.x0 > 1) || r.y1 - r.y0 <= 1;
    let (lo, hi) = if along_x { (r.x0, r.x1) } else { (r.y0, r.y1) };
    if hi - lo <= 1 {
        return vec![*r];
    }
    let part = |m: usize| {
        if along_x {
            (Region { x1: m, ..*r }, Region { x0: m, ..*r })
        } else {
            (Region { y1: m, ..*r }, Region { y0: m, ..*r })
        }
    };
    let total = sum(r);
    // The cut m in lo+1..hi whose first part's energy is nearest half the total
    // (the energy before the cut grows with m: binary search, then the nearer side).
    let (mut a, mut b) = (lo + 1, hi - 1);
    while a < b {
        let m = (a + b) / 2;
        if sum(&part(m).0) < 0.5 * total {
            a = m + 1;
        } else {
            b = m;
        }
    }
    let m = if a > lo + 1
        && (sum(&part(a - 1).0) - 0.5 * total).abs() <= (sum(&part(a).0) - 0.5 * total).abs()
    {
        a - 1
    } else {
        a
    };
    let (p, q) = part(m);
    vec![p, q]
}

#[cfg(test)]
#[path = "median_cut_tests.rs"]
mod tests;
