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
    /// Passes, each with twice the previous pass's tap spacing (1, 2, 4, ...): 5
    /// passes reach 62 pixels across.
    pub iterations: u32,
    /// Colour weight: the radiance difference (relative to the image's mean
    /// demodulated radiance, times the square root of the samples per pixel) at which
    /// a neighbour's weight falls to 1/e, for the first pass; halved at each pass
    /// (Dammertz et al.), as the noise the later passes see is smaller.
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

/// The defaults were chosen by the mean squared error to a 512-spp image of the
/// Shepp-Logan phantom at 2 spp and of the head phantom at 1 and 4 spp (colour 0.5 to
/// 1e9, normal 2 to 64, albedo 0.1 to 10): a tight colour weight keeps the noise (at 1
/// spp the noise is as large as the signal), none at all blurs the lighting's own
/// detail once the samples are many.
impl Default for AtrousSettings {
    fn default() -> AtrousSettings {
        AtrousSettings {
            iterations: 5,
            sigma_color: 24.0,
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

/// `image` (linear radiance, the frame's `spp` samples per pixel) filtered by the
/// edge-avoiding à-trous wavelet transform guided by `features` (the same size; the
/// caller checks). The alpha is kept. Every output value is finite; a constant image
/// of constant features comes out unchanged bit for bit (each pixel moves by the
/// weighted mean of its neighbours' differences from it). Rows are filtered in
/// parallel, each pixel's sums in a fixed order: the output is the same bit for bit
/// on any number of threads.
pub fn atrous(image: &Image, features: &PathFeatures, spp: u32, s: &AtrousSettings) -> Image {
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
    let luma = |c: &[f32; 3]| 0.2126 * c[0] + 0.7152 * c[1] + 0.0722 * c[2];
    let mean = input.iter().map(|c| f64::from(luma(c))).sum::<f64>() / (w * h).max(1) as f64;
    let scale = (mean as f32).max(1e-6) / (spp.max(1) as f32).sqrt();
    let guide = Guide {
        f: features,
        slope: slopes(features),
    };
    let mut current = input.clone();
    let mut next = vec![[0.0f32; 3]; w * h];
    for pass in 0..s.iterations.min(16) {
        let step = 1i32 << pass;
        let sigma_c = s.sigma_color * scale * 0.5f32.powi(pass as i32);
        let inv_c = 1.0 / (sigma_c * sigma_c).max(1e-30);
        let src = &current;
        next.par_chunks_mut(w).enumerate().for_each(|(y, row)| {
            for (x, out) in row.iter_mut().enumerate() {
                let p = y * w + x;
                let cp = src[p];
                let mut sum = [0.0f32; 3];
                let mut total = 0.0f32;
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
                        let diff = [cq[0] - cp[0], cq[1] - cp[1], cq[2] - cp[2]];
                        let d2 = diff[0] * diff[0] + diff[1] * diff[1] + diff[2] * diff[2];
                        let wt = tx * ty * guide.weight(p, q, dx, dy, s) * (-d2 * inv_c).exp();
                        if wt > 0.0 && wt.is_finite() {
                            total += wt;
                            for k in 0..3 {
                                sum[k] += wt * diff[k];
                            }
                        }
                    }
                }
                // The centre tap's weight is its own (all guides equal, no colour
                // difference); its difference from itself is 0.
                total += TAPS[2] * TAPS[2];
                *out = [0, 1, 2].map(|k| sanitize(cp[k] + sum[k] / total));
            }
        });
        std::mem::swap(&mut current, &mut next);
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

/// Every channel of `c` sanitized ([`MAX_RADIANCE`]).
fn sanitize_all(c: [f32; 3]) -> [f32; 3] {
    c.map(sanitize)
}
