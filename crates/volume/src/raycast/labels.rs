//! A label map ray cast as a volume ([`LabelVolume`]): each sample takes one label,
//! the one with the largest interpolated occupancy (per label, the trilinear weights
//! of the cell's corner voxels that hold it: between two labels the boundary is where
//! each covers half), so two labels are never blended into a third colour and their
//! boundaries are the interpolated indicator's level set rather than the voxels'
//! faces (nearest-voxel sampling showed a label's surface as stair steps); each
//! label's colour and opacity from a palette, lit by the scene's shader with the
//! normal of the labels' smoothed opacity boundary.

use std::collections::BTreeMap;

use rayon::prelude::*;

use glint_core::camera::Camera;
use glint_core::{Clip, HalfSpace, Image, RenderError, RenderStats, Shader, Vec3};

use super::caster::jitter;
use super::TERMINATION_OPACITY;

/// Half-width, in voxels, of the central differences of the trilinear opacity field
/// that give a label sample its normal: one voxel spans the 4-voxel neighbourhood
/// across a boundary, which rounds the voxel stairs of a label's surface off (glint's
/// choice, as the surfaces' one-voxel Gaussian).
const NORMAL_SPAN: f32 = 1.0;

/// Gradient length (opacity per voxel) below which a sample has no boundary normal
/// and is lit as facing the viewer (deep inside a translucent label).
const FLAT_GRADIENT: f32 = 1e-3;

/// A label map prepared for ray casting: per voxel an index into a palette of
/// colours and opacities (slots 0, the background, and 1, labels not drawn), placed in world
/// mm by its affine.
#[derive(Clone, Debug)]
pub struct LabelVolume {
    dims: [usize; 3],
    /// Voxel index to world mm (row-major 4x4), and its inverse.
    affine: [[f64; 4]; 4],
    inverse: [[f64; 4]; 4],
    /// Palette index per voxel, `i + dims[0] * (j + dims[1] * k)`.
    index: Vec<u16>,
    /// Per palette entry: linear RGB and opacity per voxel length (entry 0 is
    /// transparent).
    palette: Vec<[f32; 4]>,
    /// The smallest voxel edge, mm.
    min_spacing: f64,
    /// Index box of the voxels drawn (`None`: none), half a voxel wider.
    drawn: Option<([f32; 3], [f32; 3])>,
}

/// The palette slot of label 0, the background.
const BACKGROUND: u16 = 0;

/// The palette slot of every other label not drawn: one class apart from the
/// background, so that hiding a label does not move the boundaries of the labels it
/// touches (they compete with it as with any label).
const HIDDEN: u16 = 1;

/// What one label looks like in a [`LabelVolume`].
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct LabelLook {
    /// Linear RGB.
    pub color: [f32; 3],
    /// Opacity of one voxel's length of the label, in 0..=1 (1: opaque at once).
    pub opacity: f32,
}

impl LabelVolume {
    /// The label grid `labels` (`dims`, placed by `affine`) with each label of `looks`
    /// drawn in its colour and opacity; labels not in `looks` (and 0) are not drawn.
    pub fn new(
        dims: [usize; 3],
        affine: [[f64; 4]; 4],
        labels: &[u32],
        looks: &BTreeMap<u32, LabelLook>,
    ) -> Result<LabelVolume, RenderError> {
        let count = dims.iter().try_fold(1usize, |a, &d| a.checked_mul(d));
        if dims.contains(&0) || count != Some(labels.len()) {
            return Err(RenderError::Parameter(format!(
                "label volume of {dims:?} voxels given {} labels",
                labels.len()
            )));
        }
        if looks.len() >= usize::from(u16::MAX - HIDDEN) {
            return Err(RenderError::Parameter(format!(
                "{} labels drawn as a volume: at most {}",
                looks.len(),
                u16::MAX - HIDDEN - 1
            )));
        }
        if let Some((v, l)) = looks
            .iter()
            .find(|(_, l)| !(0.0..=1.0).contains(&l.opacity))
        {
            return Err(RenderError::Parameter(format!(
                "label {v}: opacity {} is not in 0..=1",
                l.opacity
            )));
        }
        let inverse = invert(&affine)
            .ok_or_else(|| RenderError::Parameter("the label map's affine is singular".into()))?;
        // Slots BACKGROUND and HIDDEN, transparent.
        let mut palette = vec![[0.0f32; 4]; usize::from(HIDDEN) + 1];
        let mut slot = BTreeMap::new();
        for (&v, l) in looks {
            if v != 0 && l.opacity > 0.0 {
                slot.insert(v, palette.len() as u16);
                palette.push([l.color[0], l.color[1], l.color[2], l.opacity]);
            }
        }
        let mut lo = [usize::MAX; 3];
        let mut hi = [0usize; 3];
        let [nx, ny, _] = dims;
        let mut last = (u32::MAX, 0u16);
        let index: Vec<u16> = labels
            .iter()
            .enumerate()
            .map(|(i, &v)| {
                if v != last.0 {
                    let other = if v == 0 { BACKGROUND } else { HIDDEN };
                    last = (v, slot.get(&v).copied().unwrap_or(other));
                }
                if last.1 > HIDDEN {
                    let p = [i % nx, i / nx % ny, i / (nx * ny)];
                    for a in 0..3 {
                        lo[a] = lo[a].min(p[a]);
                        hi[a] = hi[a].max(p[a]);
                    }
                }
                last.1
            })
            .collect();
        let drawn =
            (lo[0] <= hi[0]).then(|| (lo.map(|x| x as f32 - 0.5), hi.map(|x| x as f32 + 0.5)));
        let min_spacing = (0..3)
            .map(|c| (0..3).map(|r| affine[r][c].powi(2)).sum::<f64>().sqrt())
            .fold(f64::INFINITY, f64::min);
        Ok(LabelVolume {
            dims,
            affine,
            inverse,
            index,
            palette,
            min_spacing,
            drawn,
        })
    }

    /// The label grid's smallest voxel edge, mm.
    pub fn min_spacing(&self) -> f64 {
        self.min_spacing
    }

    /// Ray casts the labels seen by `camera` into a `width` x `height` image over
    /// `background` (linear RGB), samples `step` voxels of the smallest edge apart,
    /// lit by `shader` (its lights relative to the camera). A ray stops at `end[y *
    /// width + x]` (mm along the pixel's ray from the eye, or from the image plane for
    /// orthographic cameras; `f32::INFINITY`: nowhere), e.g. at a surface drawn with
    /// the same camera. Returns the image (RGB over the background, alpha the
    /// opacity) and each pixel's distance to the first label sample it shows
    /// (`f32::INFINITY`: none), what a volume drawn in front of it stops at. Labels
    /// outside what `clip` keeps are not drawn (each ray is cut to its kept interval).
    pub fn render_layer(
        &self,
        camera: &Camera,
        shader: &Shader,
        (width, height): (u32, u32),
        background: [f32; 3],
        step: f64,
        (end, clip): (&[f32], &Clip),
    ) -> Result<(Image, Vec<f32>), RenderError> {
        let (w, h) = (width as usize, height as usize);
        if end.len() != w * h {
            return Err(RenderError::Parameter(format!(
                "{} ray limits for {} pixels",
                end.len(),
                w * h
            )));
        }
        if !(step.is_finite() && step > 0.0) {
            return Err(RenderError::Parameter(format!(
                "label volume step {step}: expected a positive number of voxels"
            )));
        }
        clip.validate()?;
        let keep = clip.half_spaces();
        let shader = &shader.placed(camera);
        let dt = (step * self.min_spacing) as f32;
        let rows: Vec<Row> = (0..h)
            .into_par_iter()
            .map(|y| {
                let mut out = (
                    Vec::with_capacity(w),
                    Vec::with_capacity(w),
                    Vec::with_capacity(w),
                    RenderStats::default(),
                );
                for x in 0..w {
                    let (o, d) = camera.ray(x as f32, y as f32, width, height);
                    let (start, end) = kept(&keep, o, d, end[y * w + x]);
                    let march = March {
                        jitter: jitter(x as f32, y as f32),
                        start,
                        end,
                        dt,
                    };
                    let (c, a, first) = self.cast(o, d, &march, shader, &mut out.3);
                    out.0.push([
                        c[0] + (1.0 - a) * background[0],
                        c[1] + (1.0 - a) * background[1],
                        c[2] + (1.0 - a) * background[2],
                    ]);
                    out.1.push(a);
                    out.2.push(first);
                }
                out
            })
            .collect();
        let mut rgb = Vec::with_capacity(w * h);
        let mut alpha = Vec::with_capacity(w * h);
        let mut far = Vec::with_capacity(w * h);
        let mut stats = RenderStats::default();
        for (r, a, f, s) in rows {
            rgb.extend(r);
            alpha.extend(a);
            far.extend(f);
            stats.samples += s.samples;
            stats.shaded += s.shaded;
        }
        let image = Image {
            width,
            height,
            rgb,
            alpha,
            stats,
        };
        Ok((image, far))
    }

    /// The distance (mm, as [`LabelVolume::render_layer`]'s) to the first label
    /// sample the ray through pixel `(x, y)` (pixel index coordinates, centres at
    /// whole numbers) of a `width` x `height` image by `camera` shows, the ray
    /// stopped at `end` and cut by `clip` as [`LabelVolume::render_layer`] cuts it: a
    /// pick of the label volume. `None` when it shows none.
    pub fn first_drawn(
        &self,
        camera: &Camera,
        shader: &Shader,
        (x, y): (f32, f32),
        (width, height): (u32, u32),
        step: f64,
        (end, clip): (f32, &Clip),
    ) -> Option<f32> {
        let (o, d) = camera.ray(x, y, width, height);
        let (start, end) = kept(&clip.half_spaces(), o, d, end);
        let march = March {
            jitter: jitter(x, y),
            start,
            end,
            dt: (step * self.min_spacing) as f32,
        };
        let shader = shader.placed(camera);
        let first = self
            .cast(o, d, &march, &shader, &mut RenderStats::default())
            .2;
        first.is_finite().then_some(first)
    }

    /// Premultiplied colour, opacity and first drawn sample's distance (mm) of the
    /// world ray from `o` along unit `d`.
    fn cast(
        &self,
        o: Vec3,
        d: Vec3,
        march: &March,
        shader: &Shader,
        stats: &mut RenderStats,
    ) -> ([f32; 3], f32, f32) {
        let none = ([0.0; 3], 0.0, f32::INFINITY);
        let Some((lo, hi)) = self.drawn else {
            return none;
        };
        let oi = self.to_index(o, 1.0);
        let di = self.to_index(d, 0.0);
        let (mut t0, mut t1) = (march.start, march.end);
        for a in 0..3 {
            if di[a].abs() < 1e-12 {
                if oi[a] < lo[a] || oi[a] > hi[a] {
                    return none;
                }
            } else {
                let (ta, tb) = ((lo[a] - oi[a]) / di[a], (hi[a] - oi[a]) / di[a]);
                t0 = t0.max(ta.min(tb));
                t1 = t1.min(ta.max(tb));
            }
        }
        if t0 > t1 {
            return none;
        }
        let dt = march.dt;
        // Opacity over one step from opacity over one voxel's length.
        let per_step = (f64::from(dt) / self.min_spacing) as f32;
        let mut color = [0.0f32; 3];
        let mut alpha = 0.0f32;
        let mut first = f32::INFINITY;
        let mut k = (t0 / dt - march.jitter).ceil();
        loop {
            let t = (k + march.jitter) * dt;
            if t > t1 {
                break;
            }
            k += 1.0;
            stats.samples += 1;
            let p = [0, 1, 2].map(|a| oi[a] + di[a] * t);
            let slot = self.winner(p);
            if slot <= HIDDEN {
                continue;
            }
            let e = self.palette[usize::from(slot)];
            let a = if e[3] >= 1.0 {
                1.0
            } else {
                1.0 - (1.0 - e[3]).powf(per_step)
            };
            first = first.min(t);
            stats.shaded += 1;
            let rgb = shader.shade_normal([e[0], e[1], e[2]], self.normal(p, d), -d);
            let wgt = (1.0 - alpha) * a;
            for c in 0..3 {
                color[c] += wgt * rgb[c];
            }
            alpha += wgt;
            if alpha >= TERMINATION_OPACITY {
                break;
            }
        }
        (color, alpha, first)
    }

    /// `v` (a point when `w` is 1, a direction when 0) in index space.
    fn to_index(&self, v: Vec3, w: f64) -> [f32; 3] {
        let m = &self.inverse;
        let v = [f64::from(v.x), f64::from(v.y), f64::from(v.z)];
        std::array::from_fn(|r| {
            (m[r][0] * v[0] + m[r][1] * v[1] + m[r][2] * v[2] + m[r][3] * w) as f32
        })
    }

    /// The palette slot that wins at index-space point `p`: per slot its interpolated
    /// occupancy, the trilinear weights of the cell's corner voxels holding it (they
    /// sum to one; voxels outside the grid are background); the largest wins, a tie
    /// the lower slot. Between two labels the boundary is where each covers half, the
    /// level set of their interpolated indicator, which follows a sphere far closer
    /// than the voxels' faces (nearest-voxel sampling; the test below).
    #[inline(always)]
    fn winner(&self, p: [f32; 3]) -> u16 {
        let f = p.map(f32::floor);
        let t = [p[0] - f[0], p[1] - f[1], p[2] - f[2]];
        let b = f.map(|x| x as isize);
        let corner = |c: usize| [c & 1, c >> 1 & 1, c >> 2 & 1];
        let at: [u16; 8] = std::array::from_fn(|c| {
            let o = corner(c);
            self.slot(
                b[0] + o[0] as isize,
                b[1] + o[1] as isize,
                b[2] + o[2] as isize,
            )
        });
        // Inside a label (most samples): no weights needed.
        if at.iter().all(|&s| s == at[0]) {
            return at[0];
        }
        let (mut slots, mut occupancy, mut n) = ([0u16; 8], [0.0f32; 8], 0);
        for (c, &s) in at.iter().enumerate() {
            let o = corner(c);
            let w: f32 = (0..3)
                .map(|a| if o[a] == 1 { t[a] } else { 1.0 - t[a] })
                .product();
            match slots[..n].iter().position(|&x| x == s) {
                Some(i) => occupancy[i] += w,
                None => {
                    (slots[n], occupancy[n]) = (s, w);
                    n += 1;
                }
            }
        }
        let mut best = 0;
        for i in 1..n {
            let (a, b) = (occupancy[i], occupancy[best]);
            if a > b || (a == b && slots[i] < slots[best]) {
                best = i;
            }
        }
        slots[best]
    }

    /// The palette slot of voxel `(i, j, k)` ([`BACKGROUND`] outside the grid).
    #[inline(always)]
    fn slot(&self, i: isize, j: isize, k: isize) -> u16 {
        let [nx, ny, nz] = self.dims.map(|d| d as isize);
        if i < 0 || j < 0 || k < 0 || i >= nx || j >= ny || k >= nz {
            return BACKGROUND;
        }
        self.index[(i + nx * (j + ny * k)) as usize]
    }

    /// The palette slot of the voxel nearest index-space point `p` (background
    /// outside): the classification before `LabelVolume::winner`, kept for its test.
    #[cfg(test)]
    fn nearest(&self, p: [f32; 3]) -> u16 {
        let mut at = [0usize; 3];
        for a in 0..3 {
            let q = (p[a] + 0.5).floor();
            if q < 0.0 || q >= self.dims[a] as f32 {
                return BACKGROUND;
            }
            at[a] = q as usize;
        }
        self.index[at[0] + self.dims[0] * (at[1] + self.dims[1] * at[2])]
    }

    /// The opacity of voxel `(i, j, k)` (0 outside the grid).
    #[inline(always)]
    fn opacity(&self, i: isize, j: isize, k: isize) -> f32 {
        self.palette[usize::from(self.slot(i, j, k))][3]
    }

    /// The trilinear interpolation of the voxels' opacities at index-space `p`.
    fn opacity_at(&self, p: [f32; 3]) -> f32 {
        let f = p.map(f32::floor);
        let t = [p[0] - f[0], p[1] - f[1], p[2] - f[2]];
        let b = f.map(|x| x as isize);
        let mut sum = 0.0;
        for c in 0..8 {
            let o = [c & 1, c >> 1 & 1, c >> 2 & 1];
            let wgt: f32 = (0..3)
                .map(|a| if o[a] == 1 { t[a] } else { 1.0 - t[a] })
                .product();
            if wgt > 0.0 {
                sum += wgt * self.opacity(b[0] + o[0], b[1] + o[1], b[2] + o[2]);
            }
        }
        sum
    }

    /// The unit world normal of the labels' opacity boundary at index-space `p`:
    /// minus the gradient of the trilinear opacity field (central differences
    /// [`NORMAL_SPAN`] voxels wide, taken to world by the inverse affine's transpose);
    /// facing the viewer (`-d`) where the field is flat.
    fn normal(&self, p: [f32; 3], d: Vec3) -> Vec3 {
        let h = NORMAL_SPAN;
        let g: [f32; 3] = std::array::from_fn(|a| {
            let (mut lo, mut hi) = (p, p);
            lo[a] -= h;
            hi[a] += h;
            (self.opacity_at(hi) - self.opacity_at(lo)) / (2.0 * h)
        });
        if g.iter().map(|x| x * x).sum::<f32>() < FLAT_GRADIENT * FLAT_GRADIENT {
            return -d;
        }
        let m = &self.inverse;
        let world: [f32; 3] =
            std::array::from_fn(|c| (0..3).map(|r| m[r][c] as f32 * g[r]).sum::<f32>());
        let n = Vec3::new(-world[0], -world[1], -world[2]);
        let len = n.length();
        if len > 0.0 && len.is_finite() {
            n * (1.0 / len)
        } else {
            -d
        }
    }

    /// The world position of index-space point `p` (tests and framing).
    pub fn index_to_world(&self, p: [f64; 3]) -> [f64; 3] {
        let m = &self.affine;
        std::array::from_fn(|r| m[r][0] * p[0] + m[r][1] * p[1] + m[r][2] * p[2] + m[r][3])
    }
}

/// One image row: RGB over the background, alpha, first drawn sample's distance,
/// and the row's work counters.
type Row = (Vec<[f32; 3]>, Vec<f32>, Vec<f32>, RenderStats);

/// One ray's sampling: its jitter (fraction of a step), where it stops (mm), and the
/// step (mm).
struct March {
    jitter: f32,
    /// Where the ray starts and ends (mm): the frame's limit and the clip's interval.
    start: f32,
    end: f32,
    dt: f32,
}

/// The part of `[0, end]` of the world ray from `o` along unit `d` inside every
/// half-space of `keep` (empty: start after end).
fn kept(keep: &[HalfSpace], o: Vec3, d: Vec3, end: f32) -> (f32, f32) {
    let (mut lo, mut hi) = (0.0f32, end);
    for h in keep {
        let n = Vec3::new(h.normal[0] as f32, h.normal[1] as f32, h.normal[2] as f32);
        let (f0, slope) = (n.dot(o) + h.offset as f32, n.dot(d));
        if slope > 0.0 {
            lo = lo.max(-f0 / slope);
        } else if slope < 0.0 {
            hi = hi.min(-f0 / slope);
        } else if f0 < 0.0 {
            return (f32::INFINITY, f32::NEG_INFINITY);
        }
    }
    (lo, hi)
}

/// The inverse of an affine 4x4 (last row 0 0 0 1); `None` when singular.
fn invert(m: &[[f64; 4]; 4]) -> Option<[[f64; 4]; 4]> {
    let a = |r: usize, c: usize| m[r][c];
    let det = a(0, 0) * (a(1, 1) * a(2, 2) - a(1, 2) * a(2, 1))
        - a(0, 1) * (a(1, 0) * a(2, 2) - a(1, 2) * a(2, 0))
        + a(0, 2) * (a(1, 0) * a(2, 1) - a(1, 1) * a(2, 0));
    if !det.is_finite() || det.abs() < 1e-12 {
        return None;
    }
    let mut inv = [[0.0; 4]; 4];
    for (r, row) in inv.iter_mut().take(3).enumerate() {
        for (c, x) in row.iter_mut().take(3).enumerate() {
            // Cofactor of (c, r) over the determinant.
            let (r1, r2) = ((c + 1) % 3, (c + 2) % 3);
            let (c1, c2) = ((r + 1) % 3, (r + 2) % 3);
            *x = (a(r1, c1) * a(r2, c2) - a(r1, c2) * a(r2, c1)) / det;
        }
    }
    for row in inv.iter_mut().take(3) {
        row[3] = -(0..3).map(|c| row[c] * m[c][3]).sum::<f64>();
    }
    inv[3][3] = 1.0;
    Some(inv)
}

#[cfg(test)]
mod tests {
    use super::*;
    use glint_core::camera::CameraSpec;
    use glint_core::{Light, Material};
    use glint_lobe::{Geometry, LobeKind};

    const RED: [f32; 3] = [1.0, 0.0, 0.0];
    const GREEN: [f32; 3] = [0.0, 1.0, 0.0];
    const N: usize = 16;
    const SIZE: u32 = 48;

    /// A 16^3 grid (1 mm voxels, a translated affine): label 1 where i < 8, label 2
    /// where i >= 8, inside the box 3..13 on every axis; 0 elsewhere.
    fn halves() -> ([[f64; 4]; 4], Vec<u32>) {
        let mut labels = vec![0u32; N * N * N];
        for k in 3..13 {
            for j in 3..13 {
                for i in 3..13 {
                    labels[i + N * (j + N * k)] = if i < 8 { 1 } else { 2 };
                }
            }
        }
        let affine = [
            [1.0, 0.0, 0.0, -7.5],
            [0.0, 1.0, 0.0, -7.5],
            [0.0, 0.0, 1.0, -7.5],
            [0.0, 0.0, 0.0, 1.0],
        ];
        (affine, labels)
    }

    fn look(color: [f32; 3], opacity: f32) -> LabelLook {
        LabelLook { color, opacity }
    }

    fn shader(shade: bool) -> Shader {
        let material = Material {
            shade,
            ..Material::default()
        };
        Shader::new(
            LobeKind::Exact,
            10.0,
            0,
            Geometry::Phong,
            material,
            vec![Light::HEADLIGHT],
            0.0,
        )
        .unwrap()
    }

    fn render(looks: &BTreeMap<u32, LabelLook>, shade: bool) -> (Image, Vec<f32>) {
        let (affine, labels) = halves();
        let vol = LabelVolume::new([N; 3], affine, &labels, looks).unwrap();
        let camera = Camera::frame(&CameraSpec::default(), Vec3::ZERO, 9.0, SIZE, SIZE).unwrap();
        let end = vec![f32::INFINITY; (SIZE * SIZE) as usize];
        vol.render_layer(
            &camera,
            &shader(shade),
            (SIZE, SIZE),
            [0.0; 3],
            0.5,
            (&end, &Clip::default()),
        )
        .unwrap()
    }

    #[test]
    fn each_label_shows_its_own_colour_and_boundaries_are_not_blended() {
        let looks = BTreeMap::from([(1, look(RED, 1.0)), (2, look(GREEN, 1.0))]);
        let (image, far) = render(&looks, false);
        let (mut red, mut green) = (0, 0);
        for y in 0..SIZE as usize {
            // In each row the labels meet once: every red pixel on one side of every
            // green one (the anterior view sees the i axis across the image).
            let mut row = Vec::new();
            for x in 0..SIZE as usize {
                let i = y * SIZE as usize + x;
                let c = image.rgb[i];
                if c == RED {
                    red += 1;
                    row.push('r');
                } else if c == GREEN {
                    green += 1;
                    row.push('g');
                } else {
                    // Not a mix: the background, unlit and transparent.
                    assert_eq!((c, image.alpha[i]), ([0.0; 3], 0.0), "pixel ({x}, {y})");
                    assert_eq!(far[i], f32::INFINITY);
                    continue;
                }
                assert_eq!(image.alpha[i], 1.0);
                assert!(far[i].is_finite());
            }
            let s: String = row.into_iter().collect();
            assert!(
                !s.contains("rg") || !s.contains("gr"),
                "row {y} alternates: {s}"
            );
            assert!(!s.contains("grg") && !s.contains("rgr"), "row {y}: {s}");
        }
        // Two halves of one box: about as many pixels each, hundreds of them.
        assert!(red > 200 && green > 200, "{red} red, {green} green");
        let ratio = red as f64 / green as f64;
        assert!((0.8..1.25).contains(&ratio), "{red} red, {green} green");
    }

    #[test]
    fn a_hidden_label_is_not_drawn() {
        let both = BTreeMap::from([(1, look(RED, 1.0)), (2, look(GREEN, 1.0))]);
        let (all, _) = render(&both, false);
        let one = BTreeMap::from([(1, look(RED, 1.0))]);
        let (image, far) = render(&one, false);
        assert!(!image.rgb.contains(&GREEN));
        let reds = |im: &Image| im.rgb.iter().filter(|c| **c == RED).count();
        assert_eq!(reds(&image), reds(&all), "label 1 covers the same pixels");
        // Where label 2 was, the background.
        for (i, c) in all.rgb.iter().enumerate() {
            if *c == GREEN {
                assert_eq!(image.rgb[i], [0.0; 3]);
                assert_eq!(far[i], f32::INFINITY);
            }
        }
    }

    #[test]
    fn a_translucent_label_lets_what_is_behind_through() {
        // Label 1 at opacity 0.2 per voxel, seen through its 10 voxels along j:
        // 1 - 0.8^10 = 0.893 (the nearest-voxel faces move by up to half a step at
        // each end: 1 - 0.8^9.5..10.5, 0.88..0.905).
        let looks = BTreeMap::from([(1, look(RED, 0.2))]);
        let (image, _) = render(&looks, false);
        // The middle of label 1's half in the opaque image.
        let (opaque, _) = render(&BTreeMap::from([(1, look(RED, 1.0))]), false);
        let row = (SIZE / 2 * SIZE) as usize;
        let xs: Vec<usize> = (0..SIZE as usize)
            .filter(|x| opaque.rgb[row + x] == RED)
            .collect();
        assert!(xs.len() > 5, "{xs:?}");
        let c = row + xs[xs.len() / 2];
        let a = image.alpha[c];
        assert!((0.875..0.91).contains(&a), "alpha {a}");
        // Premultiplied red over a black background.
        assert!((image.rgb[c][0] - a).abs() < 1e-5 && image.rgb[c][1] == 0.0);
    }

    #[test]
    fn clip_planes_and_crop_boxes_cut_the_labels() {
        // Label 1 lies at world x < 0, label 2 at x > 0 (nearest voxel).
        let looks = BTreeMap::from([(1, look(RED, 1.0)), (2, look(GREEN, 1.0))]);
        let (affine, labels) = halves();
        let vol = LabelVolume::new([N; 3], affine, &labels, &looks).unwrap();
        let camera = Camera::frame(&CameraSpec::default(), Vec3::ZERO, 9.0, SIZE, SIZE).unwrap();
        let end = vec![f32::INFINITY; (SIZE * SIZE) as usize];
        let draw = |clip: &Clip| {
            let (image, _) = vol
                .render_layer(
                    &camera,
                    &shader(false),
                    (SIZE, SIZE),
                    [0.0; 3],
                    0.5,
                    (&end, clip),
                )
                .unwrap();
            let count = |c: [f32; 3]| image.rgb.iter().filter(|&&p| p == c).count();
            (count(RED), count(GREEN))
        };
        let (red, green) = draw(&Clip::default());
        assert!(red > 50 && green > 50, "{red} {green}");
        let crop = Clip {
            planes: vec![],
            crop: Some(glint_core::CropBox {
                min: [0.0, -100.0, -100.0],
                max: [100.0; 3],
            }),
        };
        let (red, green) = draw(&crop);
        assert!(red == 0 && green > 50, "{red} {green}");
        let plane = Clip {
            planes: vec![glint_core::ClipPlane {
                point: [-1.0, 0.0, 0.0],
                normal: [-1.0, 0.0, 0.0],
            }],
            crop: None,
        };
        let (red, green) = draw(&plane);
        assert!(red > 50 && green == 0, "{red} {green}");
    }

    /// The radius along the ray from `c` in direction `d` where `class` first stops
    /// giving `from` (stepped by 0.005 voxel up to `r_max`).
    fn boundary(class: impl Fn([f32; 3]) -> u16, c: [f32; 3], d: [f32; 3], from: u16) -> f32 {
        let mut r = 0.0f32;
        while r < 15.0 && class([0, 1, 2].map(|a| c[a] + r * d[a])) == from {
            r += 0.005;
        }
        r
    }

    #[test]
    fn label_boundaries_follow_a_sphere_closer_than_the_nearest_voxel() {
        // Two labels: a ball of radius 5.3 (label 1) in a shell to 9.7 (label 2),
        // centred off the grid. Along 200 directions, the RMS error of where label 1
        // gives way to 2 and 2 to the background, nearest-voxel against the
        // interpolated occupancy.
        const M: usize = 28;
        let c = [13.3f32, 13.6, 13.45];
        let (r1, r2) = (5.3f32, 9.7f32);
        let mut labels = vec![0u32; M * M * M];
        for k in 0..M {
            for j in 0..M {
                for i in 0..M {
                    let d = [i, j, k].map(|x| x as f32);
                    let r = (0..3).map(|a| (d[a] - c[a]).powi(2)).sum::<f32>().sqrt();
                    labels[i + M * (j + M * k)] = if r < r1 {
                        1
                    } else if r < r2 {
                        2
                    } else {
                        0
                    };
                }
            }
        }
        let looks = BTreeMap::from([(1, look(RED, 1.0)), (2, look(GREEN, 1.0))]);
        let affine = [
            [1.0, 0.0, 0.0, 0.0],
            [0.0, 1.0, 0.0, 0.0],
            [0.0, 0.0, 1.0, 0.0],
            [0.0, 0.0, 0.0, 1.0],
        ];
        let vol = LabelVolume::new([M; 3], affine, &labels, &looks).unwrap();
        let (one, two) = (HIDDEN + 1, HIDDEN + 2);
        let rms = |class: &dyn Fn([f32; 3]) -> u16| {
            let (mut inner, mut outer) = (0.0f64, 0.0f64);
            let n = 200;
            for s in 0..n {
                // A spiral of directions over the sphere.
                let z = 1.0 - 2.0 * (s as f32 + 0.5) / n as f32;
                let phi = s as f32 * 2.399_963;
                let q = (1.0 - z * z).sqrt();
                let d = [q * phi.cos(), q * phi.sin(), z];
                let a = boundary(class, c, d, one);
                let p = [0, 1, 2].map(|x| c[x] + (a + 0.01) * d[x]);
                assert_eq!(class(p), two, "label 2 beyond label 1 along {d:?}");
                let start = [0, 1, 2].map(|x| c[x] + (a + 0.01) * d[x]);
                let b = a + 0.01 + boundary(class, start, d, two);
                inner += f64::from(a - r1).powi(2);
                outer += f64::from(b - r2).powi(2);
            }
            ((inner / n as f64).sqrt(), (outer / n as f64).sqrt())
        };
        let nearest = rms(&|p| vol.nearest(p));
        let smooth = rms(&|p| vol.winner(p));
        // Nearest: the voxels' faces, 0.29 and 0.30 voxel RMS off the spheres;
        // interpolated, 0.18 and 0.19.
        assert!(
            smooth.0 < 0.7 * nearest.0 && smooth.1 < 0.7 * nearest.1,
            "interpolated {smooth:?} against nearest {nearest:?}"
        );
        assert!(smooth.0 < 0.25 && smooth.1 < 0.25, "{smooth:?}");
    }

    #[test]
    fn a_ray_stops_where_it_is_told() {
        let looks = BTreeMap::from([(1, look(RED, 1.0)), (2, look(GREEN, 1.0))]);
        let (affine, labels) = halves();
        let vol = LabelVolume::new([N; 3], affine, &labels, &looks).unwrap();
        let camera = Camera::frame(&CameraSpec::default(), Vec3::ZERO, 9.0, SIZE, SIZE).unwrap();
        let (_, far) = render(&looks, false);
        // Stop every ray just before its first label sample: nothing is drawn.
        let end: Vec<f32> = far.iter().map(|f| f - 0.01).collect();
        let (image, _) = vol
            .render_layer(
                &camera,
                &shader(false),
                (SIZE, SIZE),
                [0.0; 3],
                0.5,
                (&end, &Clip::default()),
            )
            .unwrap();
        assert!(image.alpha.iter().all(|a| *a == 0.0));
    }

    #[test]
    fn lit_faces_take_the_boundary_normal() {
        let looks = BTreeMap::from([(1, look(RED, 1.0)), (2, look(GREEN, 1.0))]);
        let (affine, labels) = halves();
        let vol = LabelVolume::new([N; 3], affine, &labels, &looks).unwrap();
        // On the face i = 2.5 (outside label 1's voxels at i = 3), mid-face: the normal
        // points to -x; on the face j = 12.5 to +y; inside, where two opaque labels
        // meet, the field is flat and the normal faces the viewer.
        let d = Vec3::new(0.0, -1.0, 0.0);
        let n = vol.normal([2.5, 8.0, 8.0], d);
        assert!(n.x < -0.99, "{n:?}");
        let n = vol.normal([8.0, 12.5, 8.0], d);
        assert!(n.y > 0.99, "{n:?}");
        let n = vol.normal([7.5, 8.0, 8.0], d);
        assert_eq!(n, -d);
        // Shading makes the face seen head-on brighter than its rim.
        // Lit, the face seen head-on is lit, not black and not unlit colour.
        let (image, _) = render(&looks, true);
        let (flat, _) = render(&looks, false);
        let lit: Vec<usize> = (0..image.rgb.len())
            .filter(|&i| flat.rgb[i] == RED)
            .collect();
        assert!(lit
            .iter()
            .all(|&i| image.rgb[i][0] > 0.1 && image.rgb[i][1] < image.rgb[i][0]));
    }

    #[test]
    fn bad_grids_and_looks_are_refused() {
        let (affine, labels) = halves();
        let looks = BTreeMap::from([(1, look(RED, 1.5))]);
        assert!(LabelVolume::new([N; 3], affine, &labels, &looks).is_err());
        let looks = BTreeMap::from([(1, look(RED, 1.0))]);
        assert!(LabelVolume::new([N, N, N + 1], affine, &labels, &looks).is_err());
        let mut flat = affine;
        flat[2][2] = 0.0;
        assert!(LabelVolume::new([N; 3], flat, &labels, &looks).is_err());
    }

    #[test]
    fn the_inverse_undoes_an_oblique_affine() {
        let m = [
            [0.0, 1.5, 0.2, 10.0],
            [-2.0, 0.0, 0.1, -3.0],
            [0.3, 0.0, 0.8, 7.0],
            [0.0, 0.0, 0.0, 1.0],
        ];
        let inv = invert(&m).unwrap();
        let p = [1.0, -2.0, 3.5];
        let w: [f64; 3] =
            std::array::from_fn(|r| (0..3).map(|c| m[r][c] * p[c]).sum::<f64>() + m[r][3]);
        let back: [f64; 3] =
            std::array::from_fn(|r| (0..3).map(|c| inv[r][c] * w[c]).sum::<f64>() + inv[r][3]);
        for a in 0..3 {
            assert!((back[a] - p[a]).abs() < 1e-12, "{back:?}");
        }
    }
}
