//! The built-in denoiser: the edge-avoiding à-trous wavelet filter of Dammertz,
//! Sewtz, Hanika and Lensch ("Edge-avoiding À-Trous wavelet transform for fast global
//! illumination filtering", HPG 2010), guided by a `path` frame's feature buffers
//! ([`PathFeatures`]) with the depth and normal weights of SVGF's spatial part (Schied
//! et al., HPG 2017). Written here: no maintained crate filters an image guided by
//! per-pixel features (the image crates blur without guides), and the filter is a
//! few dozen lines.
//!
//! It filters the linear HDR radiance (before any tone curve), demodulated by the
//! albedo: the filter smooths the light reaching the first hit, not the colours of
//! the transfer function, which are multiplied back afterwards, so colour edges of
//! the classification stay sharp however wide the kernel grows.
//!
//! The colour weight is SVGF's (Schied et al. 2017, eq. 3-5): a neighbour's
//! luminance difference against a multiple of the pixel's own standard error, taken
//! from the samples' variance (the frame's sums of squares of luminance;
//! where a pixel has one sample, a 7x7 spatial estimate), prefiltered by a 3x3
//! Gaussian and carried through each pass as the filtered values' variance. So the
//! filter smooths what the samples say is noise and stops at differences they say are
//! signal: a converged image passes almost unchanged, a 1-spp image is smoothed hard.

use rayon::prelude::*;

use glint_core::Image;
use glint_volume::PathFeatures;

/// The B3 spline's taps, the à-trous kernel of Dammertz et al.
const TAPS: [f32; 5] = [1.0 / 16.0, 1.0 / 4.0, 3.0 / 8.0, 1.0 / 4.0, 1.0 / 16.0];

/// Largest radiance a pixel brings into the filter (the largest finite half float,
/// which Intel Open Image Denoise also takes): a voxel of 1e30 does not swamp its
/// neighbours' sums.
pub const MAX_RADIANCE: f32 = 65504.0;

/// Smallest albedo a pixel's radiance is divided by (demodulation): darker albedos
/// are filtered as they are.
const MIN_ALBEDO: f32 = 0.01;

/// The à-trous filter's parameters ([`atrous`]).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct AtrousSettings {
    /// Passes, each with twice the previous pass's tap spacing (1, 2, 4, ...): 3
    /// passes reach 14 pixels across, 5 reach 62.
    pub iterations: u32,
    /// Colour weight: how many standard errors of the pixel's (demodulated) luminance
    /// a neighbour may differ by before its weight falls to 1/e (SVGF's sigma_l, 4).
    /// The standard error is the pixel's, from its samples, and shrinks with each
    /// pass as the filtered values' variance does.
    pub sigma_color: f32,
    /// Normal weight: the exponent of the cosine between the normals (SVGF's 128 is
    /// for meshes; a volume's gradients turn faster, 8 is kinder).
    pub sigma_normal: f32,
    /// Depth weight: how many times the depth difference the local depth slope
    /// predicts a neighbour may differ by (SVGF's 1).
    pub sigma_depth: f32,
    /// Albedo weight: the albedo difference at which a neighbour's weight falls to 1/e.
    pub sigma_albedo: f32,
}

/// SVGF's colour weight (4) and depth weight (1); the normal and albedo weights were
/// chosen by the mean squared error to a 512-spp image of the Shepp-Logan phantom at
/// 2 spp and of the head phantom at 1 and 4 spp (normal 2 to 64, albedo 0.1 to 10);
/// three passes (reaching 14 pixels across), not SVGF's five, by mean ꟻLIP to a
/// 256-spp image of the head CT at 128x128 at 1 to 8 spp (passes 2 to 5, colour 2 to
/// 6, normal 4 to 32, depth 0.5 and 1, albedo 0.1 to 1; docs/lighting.md): more
/// passes blur the bone's fine detail once the samples are a few.
impl Default for AtrousSettings {
    fn default() -> AtrousSettings {
        AtrousSettings {
            iterations: 3,
            sigma_color: 4.0,
            sigma_normal: 8.0,
            sigma_depth: 1.0,
            sigma_albedo: 0.3,
        }
    }
}

/// A finite radiance in `0..=`[`MAX_RADIANCE`] (NaN and -inf give 0).
fn sanitize(v: f32) -> f32 {
    if v.is_nan() {
        0.0
    } else {
        v.clamp(0.0, MAX_RADIANCE)
    }
}

/// The guides of one pixel, read by the weights.
struct Guide<'a> {
    f: &'a PathFeatures,
    /// Per pixel: the depth's slope along x and y (mm per pixel; 0 off a hit).
    slope: Vec<[f32; 2]>,
}

impl Guide<'_> {
    /// The weight of pixel `q` for pixel `p`, `(dx, dy)` pixels away, without colour.
    #[inline]
    fn weight(&self, p: usize, q: usize, dx: i32, dy: i32, s: &AtrousSettings) -> f32 {
        let f = self.f;
        match (f.hit(p), f.hit(q)) {
            (false, false) => return 1.0,
            (true, true) => {}
            _ => return 0.0,
        }
        let (np, nq) = (f.normal[p], f.normal[q]);
        let zero = |n: [f32; 3]| n == [0.0; 3];
        let w_n = match (zero(np), zero(nq)) {
            (true, true) => 1.0,
            (false, false) => {
                let c = np[0] * nq[0] + np[1] * nq[1] + np[2] * nq[2];
                c.max(0.0).powf(s.sigma_normal)
            }
            _ => 0.0,
        };
        let [sx, sy] = self.slope[p];
        let predicted = s.sigma_depth * (sx.abs() * dx.abs() as f32 + sy.abs() * dy.abs() as f32);
        // A floor of a tenth of a millimetre per pixel of distance: flat depth does not
        // forbid every difference.
        let floor = 0.1 * (dx.abs() + dy.abs()) as f32;
        let w_z = (-(f.depth[p] - f.depth[q]).abs() / (predicted + floor)).exp();
        let (ap, aq) = (f.albedo[p], f.albedo[q]);
        let da = (0..3).map(|c| (ap[c] - aq[c]).powi(2)).sum::<f32>();
        let w_a = (-da / (s.sigma_albedo * s.sigma_albedo)).exp();
        w_n * w_z * w_a
    }
}

/// The depth slopes of `f` (central differences between hits, one-sided at a hit's
/// edge, 0 where there is no neighbour hit).
fn slopes(f: &PathFeatures) -> Vec<[f32; 2]> {
    let (w, h) = (f.width as usize, f.height as usize);
    let mut out = vec![[0.0; 2]; w * h];
    let d = |x: usize, y: usize| {
        let i = y * w + x;
        f.hit(i).then(|| f.depth[i])
    };
    for y in 0..h {
        for x in 0..w {
            let Some(z) = d(x, y) else { continue };
            let slope = |a: Option<f32>, b: Option<f32>| match (a, b) {
                (Some(a), Some(b)) => 0.5 * (b - a),
                (Some(a), None) => z - a,
                (None, Some(b)) => b - z,
                (None, None) => 0.0,
            };
            let left = (x > 0).then(|| d(x - 1, y)).flatten();
            let right = (x + 1 < w).then(|| d(x + 1, y)).flatten();
            let up = (y > 0).then(|| d(x, y - 1)).flatten();
            let down = (y + 1 < h).then(|| d(x, y + 1)).flatten();
            out[y * w + x] = [slope(left, right), slope(up, down)];
        }
    }
    out
}

/// `image` (linear radiance) filtered by the edge-avoiding à-trous wavelet transform
/// guided by `features` (the same size; the caller checks) and by `variance`, each
/// pixel's variance of its mean luminance (NaN where it has fewer than two samples,
/// or where `variance` is not the image's size: estimated from its 7x7 neighbours).
/// The alpha is kept. Every output value is finite; a constant image of constant
/// features comes out unchanged bit for bit (each pixel moves by the weighted mean of
/// its neighbours' differences from it). Rows are filtered in parallel, each pixel's
/// sums in a fixed order: the output is the same bit for bit on any number of threads.
pub fn atrous(
    image: &Image,
    features: &PathFeatures,
    variance: &[f32],
    s: &AtrousSettings,
) -> Image {
    let (w, h) = (image.width as usize, image.height as usize);
    let albedo = |i: usize| -> [f32; 3] {
        if features.hit(i) {
            features.albedo[i].map(|a| a.max(MIN_ALBEDO))
        } else {
            [1.0; 3]
        }
    };
    // Demodulated, sanitized radiance.
    let input: Vec<[f32; 3]> = image
        .rgb
        .iter()
        .enumerate()
        .map(|(i, c)| {
            let a = albedo(i);
            [0, 1, 2].map(|k| sanitize(c[k]) / a[k])
        })
        .collect();
    // The demodulated luminance's variance: the radiance's over the albedo's
    // luminance squared.
    let raw = sample_variance(image, features, variance);
    let mut var: Vec<f32> = (0..w * h)
        .map(|i| raw[i] / luma(&albedo(i)).powi(2))
        .collect();
    let guide = Guide {
        f: features,
        slope: slopes(features),
    };
    let mut current = input.clone();
    let mut next = vec![[0.0f32; 3]; w * h];
    let mut next_var = vec![0.0f32; w * h];
    for pass in 0..s.iterations.min(16) {
        let step = 1i32 << pass;
        let blurred = gauss3(&var, w, h);
        let (src, src_var) = (&current, &var);
        (next.par_chunks_mut(w).zip(next_var.par_chunks_mut(w)))
            .enumerate()
            .for_each(|(y, (row, row_var))| {
                for (x, (out, out_var)) in row.iter_mut().zip(row_var).enumerate() {
                    let p = y * w + x;
                    let cp = src[p];
                    let lp = luma(&cp);
                    // SVGF's epsilon, relative here: a pixel of no variance still
                    // averages with neighbours equal to it to a part in a million.
                    let inv_l = 1.0 / (s.sigma_color * blurred[p].sqrt() + 1e-6 * lp + 1e-12);
                    let mut sum = [0.0f32; 3];
                    // The centre tap's weight is its own (all guides equal, no colour
                    // difference); its difference from itself is 0.
                    let centre = TAPS[2] * TAPS[2];
                    let mut total = centre;
                    let mut sum_var = centre * centre * src_var[p];
                    for (j, ty) in TAPS.iter().enumerate() {
                        let dy = (j as i32 - 2) * step;
                        let qy = y as i32 + dy;
                        if qy < 0 || qy >= h as i32 {
                            continue;
                        }
                        for (i, tx) in TAPS.iter().enumerate() {
                            let dx = (i as i32 - 2) * step;
                            let qx = x as i32 + dx;
                            if qx < 0 || qx >= w as i32 || (dx == 0 && dy == 0) {
                                continue;
                            }
                            let q = qy as usize * w + qx as usize;
                            let cq = src[q];
                            let w_l = (-(luma(&cq) - lp).abs() * inv_l).exp();
                            let wt = tx * ty * guide.weight(p, q, dx, dy, s) * w_l;
                            if wt > 0.0 && wt.is_finite() {
                                total += wt;
                                sum_var += wt * wt * src_var[q];
                                for k in 0..3 {
                                    sum[k] += wt * (cq[k] - cp[k]);
                                }
                            }
                        }
                    }
                    *out = [0, 1, 2].map(|k| sanitize(cp[k] + sum[k] / total));
                    *out_var = finite_or_zero(sum_var / (total * total));
                }
            });
        std::mem::swap(&mut current, &mut next);
        std::mem::swap(&mut var, &mut next_var);
    }
    let rgb = (0..w * h)
        .map(|i| {
            let a = albedo(i);
            let c = sanitize_all(image.rgb[i]);
            // Remodulated as a change of the pixel's own radiance, so an unchanged
            // demodulated value gives back the input exactly.
            [0, 1, 2].map(|k| sanitize(c[k] + (current[i][k] - input[i][k]) * a[k]))
        })
        .collect();
    Image {
        width: image.width,
        height: image.height,
        rgb,
        alpha: image.alpha.clone(),
        stats: image.stats,
    }
}

/// Rec. 709 luminance.
fn luma(c: &[f32; 3]) -> f32 {
    0.2126 * c[0] + 0.7152 * c[1] + 0.0722 * c[2]
}

/// `v` where finite and not negative, else 0.
fn finite_or_zero(v: f32) -> f32 {
    if v.is_finite() && v > 0.0 {
        v
    } else {
        0.0
    }
}

/// Each pixel's variance of its mean luminance (radiance units squared): `variance`'s
/// where known (finite, the image's size), else the variance of the luminance of the
/// pixels within 3 of it that share its hit or miss (one sample each, so that is the
/// variance of a one-sample mean; SVGF estimates it spatially the same way while a
/// pixel's history is short).
fn sample_variance(image: &Image, features: &PathFeatures, variance: &[f32]) -> Vec<f32> {
    let (w, h) = (image.width as usize, image.height as usize);
    let known = variance.len() == w * h;
    let lum: Vec<f32> = image.rgb.iter().map(|c| luma(&sanitize_all(*c))).collect();
    (0..w * h)
        .into_par_iter()
        .map(|p| {
            if known && variance[p].is_finite() {
                return variance[p].max(0.0);
            }
            let (x, y) = ((p % w) as i64, (p / w) as i64);
            let (mut n, mut s1, mut s2) = (0.0f64, 0.0f64, 0.0f64);
            for qy in (y - 3).max(0)..(y + 4).min(h as i64) {
                for qx in (x - 3).max(0)..(x + 4).min(w as i64) {
                    let q = qy as usize * w + qx as usize;
                    if features.hit(q) == features.hit(p) {
                        let l = f64::from(lum[q]);
                        n += 1.0;
                        s1 += l;
                        s2 += l * l;
                    }
                }
            }
            let mean = s1 / n;
            finite_or_zero((s2 / n - mean * mean) as f32)
        })
        .collect()
}

/// `v` blurred by the 3x3 Gaussian (1 2 1) x (1 2 1) / 16, edges clamped: SVGF's
/// prefilter of the variance before the colour weight reads it.
fn gauss3(v: &[f32], w: usize, h: usize) -> Vec<f32> {
    const G: [f32; 3] = [0.25, 0.5, 0.25];
    (0..w * h)
        .into_par_iter()
        .map(|p| {
            let (x, y) = (p % w, p / w);
            let mut sum = 0.0;
            for (j, gy) in G.iter().enumerate() {
                let qy = (y + j).saturating_sub(1).min(h - 1);
                for (i, gx) in G.iter().enumerate() {
                    let qx = (x + i).saturating_sub(1).min(w - 1);
                    sum += gx * gy * v[qy * w + qx];
                }
            }
            sum
        })
        .collect()
}

/// Every channel of `c` sanitized ([`MAX_RADIANCE`]).
fn sanitize_all(c: [f32; 3]) -> [f32; 3] {
    c.map(sanitize)
}
