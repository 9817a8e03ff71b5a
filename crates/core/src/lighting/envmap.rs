//! An environment map: an equirectangular image of the radiance arriving from every
//! direction, fixed to the volume's world frame (RAS+: the map's vertical axis is the
//! patient's superior `+z`), turned about that axis and scaled; evaluated by
//! direction and importance-sampled by solid angle for the path tracer's next-event
//! estimation, combined with the scattering model's own sampling by multiple
//! importance sampling (`path`), and fitted by a few directional lights for the
//! deterministic `shadows` model (its median cut, `median_cut.rs`).
//!
//! Sampling is the 2D marginal/conditional piecewise-constant distribution of pbrt-v4
//! (`PiecewiseConstant2D`, src/pbrt/util/sampling.h; Pharr, Jakob and Humphreys,
//! "Physically Based Rendering", 4th ed., 12.5.2 and A.5) and of Mitsuba 3's `envmap`
//! emitter: each texel's luminance times `sin θ` of its row (the equirectangular
//! map's area distortion), a conditional CDF over each row and a marginal CDF over the
//! rows. A point `(u, v)` of the unit square drawn with density `p(u, v)` is the
//! direction `θ = π·v`, `φ = 2π·u`, of density `p(u, v) / (2π²·sin θ)` per steradian.
//! The map is read as piecewise constant (the nearest texel), so the density follows
//! the radiance exactly where the map is constant along rows. Written here (about 100
//! lines) since no maintained crate provides a 2D piecewise-constant distribution.

use std::f32::consts::PI;

use crate::color::luminance_f32;
use crate::error::RenderError;
use crate::math::Vec3;

/// Most texels along a map's width (16k: larger probes are not needed for lighting,
/// and their CDFs would be hundreds of MB).
pub const MAX_ENV_WIDTH: u32 = 16384;

/// Most texels along a map's height.
pub const MAX_ENV_HEIGHT: u32 = 8192;

/// Largest intensity factor a map takes.
pub const MAX_ENV_INTENSITY: f32 = 1000.0;

/// An equirectangular environment map with its sampling distribution.
#[derive(Clone, Debug)]
pub struct EnvMap {
    width: u32,
    height: u32,
    /// Linear RGB radiance, row by row from the top (`θ = 0`, superior).
    texels: Vec<[f32; 3]>,
    /// Radians the map is turned about the vertical axis.
    rotation: f32,
    intensity: f32,
    /// Per row: the conditional CDF over its columns (`width + 1` entries).
    conditional: Vec<Guided>,
    /// Per row: the integral of its function over `[0, 1)`.
    row_integral: Vec<f32>,
    /// The marginal CDF over the rows (`height + 1` entries).
    marginal: Guided,
    /// The integral of the whole function over the unit square.
    integral: f32,
}

/// A direction drawn from an [`EnvMap`].
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct EnvSample {
    /// Unit world direction towards the environment.
    pub wi: Vec3,
    /// The radiance arriving from it (the map's intensity applied).
    pub radiance: [f32; 3],
    /// The density of `wi` per steradian.
    pub pdf: f32,
}

/// Checks a map's size before its texels are allocated or read.
pub fn check_env_size(width: u32, height: u32) -> Result<(), RenderError> {
    if width == 0 || height == 0 || width > MAX_ENV_WIDTH || height > MAX_ENV_HEIGHT {
        return Err(RenderError::Parameter(format!(
            "environment map of {width}x{height} texels: expected 1..={MAX_ENV_WIDTH} by 1..={MAX_ENV_HEIGHT}"
        )));
    }
    Ok(())
}

impl EnvMap {
    /// A map of `width x height` linear RGB texels (row by row from the top), checked:
    /// a sensible size, every texel finite and not negative.
    pub fn new(width: u32, height: u32, texels: Vec<[f32; 3]>) -> Result<EnvMap, RenderError> {
        check_env_size(width, height)?;
        if texels.len() != width as usize * height as usize {
            return Err(RenderError::Parameter(format!(
                "environment map of {width}x{height} texels holds {}",
                texels.len()
            )));
        }
        if let Some(i) = texels
            .iter()
            .position(|t| t.iter().any(|c| !c.is_finite() || *c < 0.0))
        {
            let (x, y) = (i % width as usize, i / width as usize);
            return Err(RenderError::Parameter(format!(
                "environment map texel ({x}, {y}) is {:?}: expected finite radiance >= 0",
                texels[i]
            )));
        }
        let (w, h) = (width as usize, height as usize);
        let mut conditional = Vec::with_capacity(h);
        let mut row_integral = Vec::with_capacity(h);
        for y in 0..h {
            let sin = (PI * (y as f32 + 0.5) / h as f32).sin();
            let row = &texels[y * w..(y + 1) * w];
            let (cdf, integral) = cdf(row.iter().map(|&t| luminance_f32(t) * sin));
            conditional.push(Guided::new(cdf));
            row_integral.push(integral);
        }
        let (marginal, integral) = cdf(row_integral.iter().copied());
        let marginal = Guided::new(marginal);
        Ok(EnvMap {
            width,
            height,
            texels,
            rotation: 0.0,
            intensity: 1.0,
            conditional,
            row_integral,
            marginal,
            integral,
        })
    }

    /// A map of one radiance everywhere (`width x height` texels).
    pub fn constant(radiance: [f32; 3], width: u32, height: u32) -> Result<EnvMap, RenderError> {
        EnvMap::new(
            width,
            height,
            vec![radiance; width as usize * height as usize],
        )
    }

    /// This map turned by `degrees` about the vertical axis (positive: from `+x`
    /// towards `+y`, anticlockwise seen from above) and scaled by `intensity`.
    pub fn placed(mut self, degrees: f64, intensity: f32) -> Result<EnvMap, RenderError> {
        if !degrees.is_finite() || degrees.abs() > 360.0 {
            return Err(RenderError::Parameter(format!(
                "environment rotation {degrees}: expected -360..=360 degrees"
            )));
        }
        if !intensity.is_finite() || !(0.0..=MAX_ENV_INTENSITY).contains(&intensity) {
            return Err(RenderError::Parameter(format!(
                "environment intensity {intensity}: expected 0..={MAX_ENV_INTENSITY}"
            )));
        }
        self.rotation = degrees.to_radians() as f32;
        self.intensity = intensity;
        Ok(self)
    }

    /// Width and height in texels.
    pub fn size(&self) -> [u32; 2] {
        [self.width, self.height]
    }

    /// The texels (linear RGB, row by row from the top, before the intensity).
    pub fn texels(&self) -> &[[f32; 3]] {
        &self.texels
    }

    /// The intensity factor.
    pub fn intensity(&self) -> f32 {
        self.intensity
    }

    /// Radians the map is turned about the vertical axis.
    pub fn rotation(&self) -> f32 {
        self.rotation
    }

    /// The radiance arriving from unit world direction `wi`.
    #[inline]
    pub fn eval(&self, wi: Vec3) -> [f32; 3] {
        let (u, v) = self.to_uv(wi);
        let x = ((u * self.width as f32) as usize).min(self.width as usize - 1);
        let y = ((v * self.height as f32) as usize).min(self.height as usize - 1);
        let t = self.texels[y * self.width as usize + x];
        t.map(|c| c * self.intensity)
    }

    /// The density per steradian with which [`EnvMap::sample`] draws unit `wi`.
    #[inline]
    pub fn pdf(&self, wi: Vec3) -> f32 {
        if self.integral <= 0.0 || self.intensity == 0.0 {
            return 0.0;
        }
        let (u, v) = self.to_uv(wi);
        let (w, h) = (self.width as usize, self.height as usize);
        let x = ((u * w as f32) as usize).min(w - 1);
        let y = ((v * h as f32) as usize).min(h - 1);
        let c = &self.conditional[y].cdf;
        // The function's value at the texel over the whole integral: the texel's CDF
        // step times the row's integral, times the width (a texel is 1/w wide).
        let f = (c[x + 1] - c[x]) * self.row_integral[y] * w as f32;
        let sin = (PI * v).sin();
        if sin <= 0.0 {
            return 0.0;
        }
        f / self.integral / (2.0 * PI * PI * sin)
    }

    /// Draws a direction with density proportional to the luminance (times `sin θ`)
    /// from two uniform numbers in `[0, 1)`. `None` for a black map.
    #[inline]
    pub fn sample(&self, u: [f32; 2]) -> Option<EnvSample> {
        if self.integral <= 0.0 || self.intensity == 0.0 {
            return None;
        }
        let (v, y, pv) = self.marginal.sample(u[1]);
        let (uu, x, pu) = self.conditional[y].sample(u[0]);
        let pdf_uv = pv * pu * (self.width as f32 * self.height as f32);
        let theta = PI * v;
        let sin = theta.sin();
        if sin <= 0.0 || pdf_uv <= 0.0 {
            return None;
        }
        let phi = 2.0 * PI * uu + self.rotation;
        let wi = Vec3::new(sin * phi.cos(), sin * phi.sin(), theta.cos());
        let t = self.texels[y * self.width as usize + x];
        Some(EnvSample {
            wi,
            radiance: t.map(|c| c * self.intensity),
            pdf: pdf_uv / (2.0 * PI * PI * sin),
        })
    }

    /// The map's radiance (luminance, times the intensity) averaged over the sphere,
    /// by solid angle: `∫ L dω / 4π`.
    #[inline]
    pub fn mean_radiance(&self) -> f32 {
        // `integral` is the mean of luminance times sin θ over the texels; a texel
        // spans (2π / w)(π / h) sin θ steradians.
        self.integral * self.intensity * (PI / 2.0)
    }

    /// The point of the unit square of unit world direction `wi`: `u` the azimuth
    /// (less the rotation) over 2π, `v` the polar angle from `+z` over π.
    #[inline]
    fn to_uv(&self, wi: Vec3) -> (f32, f32) {
        let theta = wi.z.clamp(-1.0, 1.0).acos();
        let phi = wi.y.atan2(wi.x) - self.rotation;
        let u = (phi / (2.0 * PI)).rem_euclid(1.0);
        (u, theta / PI)
    }
}

/// The normalised CDF (`n + 1` entries, from 0 to 1) of a piecewise-constant function
/// over `[0, 1)` of `n` non-negative values, and its integral (their mean). A
/// function of zero integral gets the uniform CDF.
fn cdf(values: impl ExactSizeIterator<Item = f32>) -> (Vec<f32>, f32) {
    let n = values.len();
    let mut cdf = Vec::with_capacity(n + 1);
    let mut sum = 0.0f64;
    cdf.push(0.0);
    for v in values {
        sum += f64::from(v);
        cdf.push(sum as f32);
    }
    if sum <= 0.0 {
        for (i, c) in cdf.iter_mut().enumerate() {
            *c = i as f32 / n as f32;
        }
        return (cdf, 0.0);
    }
    let inv = (1.0 / sum) as f32;
    for c in &mut cdf {
        *c *= inv;
    }
    cdf[n] = 1.0;
    (cdf, (sum / n as f64) as f32)
}

/// Entries of a [`Guided`] CDF's guide table: at most this many, so a map of the
/// largest size keeps its tables to 8 MiB.
const GUIDE: usize = 256;

/// A normalised CDF and its guide table (Chen and Asau, 1974; Devroye, "Non-Uniform
/// Random Variate Generation", 1986, III.2.4): entry `g` of `G` is the last CDF index
/// at or below `g / G`, so the segment of `u` lies between the entries of `floor(u G)`
/// and the next, a bracket of a few entries searched in place of the whole CDF. The result is the full binary
/// search's exactly (checked, and the full search taken, where float rounding puts
/// `u` outside the bracket), so sampling draws the same directions as before.
#[derive(Clone, Debug)]
struct Guided {
    cdf: Vec<f32>,
    guide: Vec<u32>,
}

impl Guided {
    fn new(cdf: Vec<f32>) -> Guided {
        let n = cdf.len() - 1;
        let g = n.clamp(1, GUIDE);
        let guide = (0..=g)
            .map(|k| {
                let x = k as f32 / g as f32;
                // The last index whose entry is at most x (entry 0 is 0).
                (cdf.partition_point(|&c| c <= x).max(1) - 1) as u32
            })
            .collect();
        Guided { cdf, guide }
    }

    /// `cdf.partition_point(|&c| c <= u)`, by the guide table.
    #[inline]
    fn first_above(&self, u: f32) -> usize {
        let (cdf, g) = (&self.cdf, self.guide.len() - 1);
        let k = ((u * g as f32) as usize).min(g - 1);
        let lo = self.guide[k] as usize;
        let hi = (self.guide[k + 1] as usize + 1).min(cdf.len());
        if cdf[lo] <= u && (hi == cdf.len() || cdf[hi] > u) {
            lo + cdf[lo..hi].partition_point(|&c| c <= u)
        } else {
            cdf.partition_point(|&c| c <= u)
        }
    }

    /// Samples a piecewise-constant distribution given by its CDF: the continuous point
    /// in `[0, 1)`, the segment, and the segment's probability (its density is that times
    /// the number of segments).
    #[inline]
    fn sample(&self, u: f32) -> (f32, usize, f32) {
        let cdf = &self.cdf;
        let n = cdf.len() - 1;
        let i = self.first_above(u).clamp(1, n) - 1;
        let p = cdf[i + 1] - cdf[i];
        let du = if p > 0.0 { (u - cdf[i]) / p } else { 0.5 };
        let x = ((i as f32 + du.clamp(0.0, 1.0)) / n as f32).min(1.0 - f32::EPSILON);
        (x, i, p)
    }
}

/// The power heuristic with β = 2 (Veach, "Robust Monte Carlo Methods for Light
/// Transport Simulation", PhD thesis, Stanford 1997, 9.2.4): the weight of a sample
/// drawn with density `f` when another strategy would have drawn it with density `g`.
#[inline]
pub fn power_heuristic(f: f32, g: f32) -> f32 {
    let (f2, g2) = (f * f, g * g);
    if f2 + g2 > 0.0 && (f2 + g2).is_finite() {
        f2 / (f2 + g2)
    } else if f.is_infinite() {
        1.0
    } else {
        0.0
    }
}

#[cfg(test)]
#[path = "envmap_tests.rs"]
mod tests;
