//! The rays of a frame and the reference loops that march them, one sample at a time.

use crossbeam_epoch::Guard;
use glint_core::camera::Camera;
use glint_core::{RayLighting, RenderMode, RenderStats, Shader, Vec3, MAX_LIGHTS};

use super::settings::FrameSettings;
use super::{ISO_REFINE_STEPS, TERMINATION_OPACITY, TILE};
use crate::classification::{ColourVolume, Last, Lut, Sampling};
use crate::clip::IndexClip;
use crate::field::{clip_ray, Field, Loc, MACRO_CELL};
use crate::light::ShadowField;

/// Per-render state shared by all rays.
pub(super) struct Caster<'a> {
    pub(super) field: &'a Field,
    pub(super) lut: &'a Lut,
    /// [`Classification::distance`].
    pub(super) distance: &'a [u8],
    /// [`Classification::clip_box`] in f32.
    pub(super) clip_box: ([f32; 3], [f32; 3]),
    /// The camera's rays in index space.
    pub(super) rays: IndexRays,
    pub(super) shader: &'a Shader,
    pub(super) frame: &'a FrameSettings,
    /// [`ClassifySettings::mode`](super::ClassifySettings::mode).
    pub(super) mode: RenderMode,
    /// [`ClassifySettings::iso`](super::ClassifySettings::iso).
    pub(super) iso_value: f32,
    /// [`ClassifySettings::skip_empty`].
    pub(super) skip_empty: bool,
    /// Step in mm.
    pub(super) dt: f32,
    /// Run the AVX2 compositing loop.
    pub(super) simd: bool,
    /// Offset each ray's samples by [`jitter`].
    pub(super) jitter: bool,
    /// [`ClassifySettings::sampling`].
    pub(super) sampling: Sampling,
    /// The `shadows` model's light volumes (`None`: local lighting).
    pub(super) shadows: Option<&'a ShadowField>,
    /// A colour volume's colours, which replace the transfer function's
    /// ([`Classification::with_colour`](super::Classification::with_colour)).
    pub(super) colour: Option<&'a ColourVolume>,
    /// The frame's clip planes and crop box: the rays' bounds are cut to what they
    /// keep ([`FrameSettings::clip`]); here, the cut faces' normals.
    pub(super) clip: Option<&'a IndexClip>,
}

impl Caster<'_> {
    /// Renders the pixels of `px`, row by row.
    #[inline(always)]
    pub(super) fn tile(
        &self,
        px: &Pixels,
        rgb: &mut Vec<[f32; 3]>,
        alpha: &mut Vec<f32>,
        stats: &mut RenderStats,
        guard: &Guard,
    ) {
        let bg = self.frame.background;
        let (xs, ys) = (px.xs, px.ys);
        let tw = xs.1 - xs.0;
        for y in ys.0..ys.1 {
            for x in xs.0..xs.1 {
                let i = (y - ys.0) * tw + (x - xs.0);
                let (c, op) = self.cast(x as f32, y as f32, (px.start[i], px.end[i]), stats, guard);
                rgb.push([
                    c[0] + (1.0 - op) * bg[0],
                    c[1] + (1.0 - op) * bg[1],
                    c[2] + (1.0 - op) * bg[2],
                ]);
                alpha.push(op);
            }
        }
    }

    /// Premultiplied colour and opacity of the ray through pixel `(x, y)`, whose
    /// samples outside `range` (mm) cannot show.
    #[inline(always)]
    pub(super) fn cast(
        &self,
        x: f32,
        y: f32,
        range: (f32, f32),
        stats: &mut RenderStats,
        guard: &Guard,
    ) -> ([f32; 3], f32) {
        let Some((ray, view)) = self.ray(x, y, range) else {
            return ([0.0; 3], 0.0);
        };
        match self.mode {
            RenderMode::Composite => self.composite(&ray, &self.shader.for_ray(view), stats, guard),
            RenderMode::Iso => self.iso(&ray, view, self.iso_value, guard),
            RenderMode::Mip => self.mip(&ray, guard),
            // Refused by `ClassifySettings::validate`: a surface scene is rasterised.
            RenderMode::Surface => ([0.0; 3], 0.0),
        }
    }

    /// The ray through pixel `(x, y)` in index space with its sample range, and its
    /// view vector (unit, world, towards the eye); `None` when it takes no sample.
    /// Samples before `start` or past `end` (mm) cannot show.
    #[inline(always)]
    pub(super) fn ray(&self, x: f32, y: f32, (start, end): (f32, f32)) -> Option<(Ray, Vec3)> {
        if start == f32::INFINITY {
            return None;
        }
        let (o, d, dir) = self.rays.ray(x, y);
        // Slab test against the box of voxel centres [0, dims-1], or the box of the
        // cells that can show a sample (samples outside it lie in inactive cells), t in
        // mm.
        let (t0, t1) = clip_ray(o, d, self.clip_box, (0.0, f32::INFINITY))?;
        let mut inv_dk = [f32::INFINITY; 3];
        let mut face_up = [true; 3];
        for a in 0..3 {
            let da = d.get(a);
            if da.abs() < 1e-12 {
                continue;
            }
            inv_dk[a] = (1.0 / da) / self.dt;
            face_up[a] = da > 0.0;
        }
        // With a clip, `start` holds where the kept interval begins: an iso hit is
        // then never bisected back across the cut.
        let t_entry = if self.clip.is_some() {
            t0.max(start)
        } else {
            t0
        };
        let t0 = t0.max(start);
        let t1 = t1.min(end);
        if t0 > t1 {
            return None;
        }
        // Sample k lies at t = (k + j) dt: the jitter j shifts the ray's samples by a
        // fraction of a step that varies from pixel to pixel.
        let j = if self.jitter { jitter(x, y) } else { 0.0 };
        let k0 = ceil_i64(t0 / self.dt - j);
        let k1 = floor_i64(t1 / self.dt - j);
        if k1 < k0 {
            return None;
        }
        let ray = Ray {
            o,
            d,
            inv_dk,
            face_up,
            k0,
            k1,
            t_entry,
            k_entry: ceil_i64(t_entry / self.dt - j),
            j,
        };
        // The view vector: from the sample towards the eye. Every sample of a ray lies
        // on the line through the eye, so -dir is exact for each (perspective-correct);
        // for orthographic rays it is the same for all.
        Some((ray, -dir))
    }

    /// The macro cell holding index-space point `p`.
    #[inline(always)]
    pub(super) fn cell_of(&self, p: Vec3) -> ([usize; 3], usize) {
        let cd = self.field.cell_dims;
        let c = [
            ((p.x.max(0.0) as usize) / MACRO_CELL).min(cd[0] - 1),
            ((p.y.max(0.0) as usize) / MACRO_CELL).min(cd[1] - 1),
            ((p.z.max(0.0) as usize) / MACRO_CELL).min(cd[2] - 1),
        ];
        (c, c[0] + cd[0] * (c[1] + cd[1] * c[2]))
    }

    /// Leaps over the empty region around inactive macro cell `c`, whose entry in the
    /// distance map is `dist` (at least 1): the cube of cells closer than `dist` to it
    /// holds no active cell (Cohen and Sheffer 1994, "Proximity clouds"), so one leap
    /// crosses a whole empty region. Returns the first sample index past the cube,
    /// or `k + 1`, whichever is later.
    #[inline(always)]
    pub(super) fn leap(&self, ray: &Ray, c: [usize; 3], dist: u8, k: i64) -> i64 {
        let r = dist as usize - 1;
        let mut q = f32::INFINITY;
        for (a, &ca) in c.iter().enumerate() {
            let face = if ray.face_up[a] {
                (ca + r + 1) * MACRO_CELL
            } else {
                ca.saturating_sub(r) * MACRO_CELL
            } as f32;
            // In samples; an axis the ray does not move along gives +inf or NaN, which
            // `min` ignores.
            q = q.min((face - ray.o.get(a)) * ray.inv_dk[a]);
        }
        // A sixty-fourth of a step short of the face: rounding can then never carry
        // the leap past the first sample beyond it.
        ceil_i64(q - ray.j - 1.0 / 64.0).max(k + 1)
    }

    /// Front-to-back compositing, one sample at a time (the reference loop). Each
    /// sample composites the pre-integrated segment from the previous sample
    /// ([`crate::classification::preint`]); after a leap, or at the ray's first sample, the previous
    /// sample is read for that alone ([`Caster::before`]).
    pub(super) fn composite(
        &self,
        ray: &Ray,
        lighting: &RayLighting,
        stats: &mut RenderStats,
        guard: &Guard,
    ) -> ([f32; 3], f32) {
        let pre = &self.lut.pre;
        let mut color = [0.0f32; 3];
        let mut alpha = 0.0f32;
        let mut k = ray.k0;
        let mut cached_cell = usize::MAX;
        let mut dist = 0;
        // The last sample read, and its table coordinate.
        let mut prev: Option<(i64, f32)> = None;
        let mut last = Last::default();
        while k <= ray.k1 {
            let p = ray.at(ray.t(k, self.dt));
            let loc = self.field.locate(p);
            let cell = self.field.cell_index(&loc);
            if cell != cached_cell {
                cached_cell = cell;
                dist = self.distance[cell];
            }
            // A sample in empty space still ends the segment from the sample before it,
            // when that one was read (the segment may leave a visible cell); the
            // segments between samples inside the leap's empty cells cross no opacity.
            let leap = dist != 0;
            let front = match prev {
                Some((pk, u)) if pk == k - 1 => Some(u),
                _ => None,
            };
            if self.sampling == Sampling::Point {
                if !leap {
                    stats.samples += 1;
                    let e = self.lut.get(self.field.value_at(&loc, guard));
                    let mut acc = (&mut color, &mut alpha);
                    if e[3] > 0.0 && self.add(&loc, e, lighting, &mut acc, stats, guard) {
                        break;
                    }
                }
            } else if !leap || front.is_some() {
                stats.samples += 1;
                let front = front.unwrap_or_else(|| self.before(ray, k, guard));
                let back = self.lut.position(self.field.value_at(&loc, guard));
                prev = Some((k, back));
                if let Some(e) = pre.segment(front, back, &mut last) {
                    let mut acc = (&mut color, &mut alpha);
                    if self.add(&loc, e, lighting, &mut acc, stats, guard) {
                        break;
                    }
                }
            }
            if leap {
                stats.skips += 1;
                k = self.leap(ray, loc.ijk.map(|x| x / MACRO_CELL), dist, k);
            } else {
                k += 1;
            }
        }
        (color, alpha)
    }

    /// Shades the sample at `loc` with colour and opacity `rgba` and adds it behind
    /// the ray's colour and opacity `acc`; returns whether the ray is now opaque enough
    /// to stop.
    #[inline(always)]
    pub(super) fn add(
        &self,
        loc: &Loc,
        rgba: [f32; 4],
        lighting: &RayLighting,
        (color, alpha): &mut (&mut [f32; 3], &mut f32),
        stats: &mut RenderStats,
        guard: &Guard,
    ) -> bool {
        stats.shaded += 1;
        let mut grad = self.field.gradient_at(loc, guard);
        let base = match self.colour {
            Some(c) => c.at(loc),
            None => [rgba[0], rgba[1], rgba[2]],
        };
        let p = || {
            Vec3::new(
                loc.ijk[0] as f32 + loc.t[0],
                loc.ijk[1] as f32 + loc.t[1],
                loc.ijk[2] as f32 + loc.t[2],
            )
        };
        if let Some(clip) = self.clip {
            grad = clip.cut_gradient(p(), grad);
        }
        let rgb = match self.shadows {
            None => self.shader.shade(base, grad, lighting),
            Some(s) => self.shade_shadowed(s, p(), base, grad, lighting),
        };
        let w = (1.0 - **alpha) * rgba[3];
        color[0] += w * rgb[0];
        color[1] += w * rgb[1];
        color[2] += w * rgb[2];
        **alpha += w;
        **alpha >= TERMINATION_OPACITY
    }

    /// [`Shader::shade_shadowed`] of a sample at index-space point `p`, its lights'
    /// transmittance and ambient occlusion read from `shadows`.
    #[inline(always)]
    pub(super) fn shade_shadowed(
        &self,
        shadows: &ShadowField,
        p: Vec3,
        base: [f32; 3],
        grad: Vec3,
        lighting: &RayLighting,
    ) -> [f32; 3] {
        let mut t = [1.0f32; MAX_LIGHTS];
        let occlusion = shadows.at(p, &mut t);
        self.shader
            .shade_shadowed(base, grad, lighting, &t[..shadows.lights()], occlusion)
    }

    /// The table coordinate of sample `k - 1` of `ray`: the front of the segment
    /// ending at sample `k`, when `k - 1` was not read (a leap or the ray's start just
    /// before `k`). The SIMD loop's lanes read it as their first sample of the step
    /// (`Lanes::segment_step`), with the same arithmetic.
    pub(super) fn before(&self, ray: &Ray, k: i64, guard: &Guard) -> f32 {
        let loc = self.field.locate(ray.at(ray.t(k - 1, self.dt)));
        self.lut.position(self.field.value_at(&loc, guard))
    }

    /// The iso mode's ray: the surface at `threshold` shaded where the ray first
    /// meets it ([`Caster::iso_hit`]), or nothing.
    pub(super) fn iso(
        &self,
        ray: &Ray,
        view: Vec3,
        threshold: f32,
        guard: &Guard,
    ) -> ([f32; 3], f32) {
        let Some(hi) = self.iso_hit(ray, threshold, guard) else {
            return ([0.0; 3], 0.0);
        };
        let p = ray.at(hi);
        let e = self.lut.get(threshold);
        let mut g = self.field.gradient_in(p, guard);
        if let Some(clip) = self.clip {
            g = clip.cut_gradient(p, g);
        }
        let lighting = self.shader.for_ray(view);
        let base = match self.colour {
            Some(c) => c.at(&self.field.locate(p)),
            None => [e[0], e[1], e[2]],
        };
        let rgb = match self.shadows {
            None => self.shader.shade(base, g, &lighting),
            Some(s) => self.shade_shadowed(s, p, base, g, &lighting),
        };
        (rgb, 1.0)
    }

    /// The ray parameter (mm) where `ray` first reaches `threshold`: the first sample
    /// at or above it, refined by bisection and a linear step towards the sample
    /// before; `None` when no sample reaches it.
    pub(super) fn iso_hit(&self, ray: &Ray, threshold: f32, guard: &Guard) -> Option<f32> {
        let value = |p: Vec3| self.field.value_in(p, guard);
        let mut k = ray.k0;
        let mut cached_cell = usize::MAX;
        let mut dist = 0;
        while k <= ray.k1 {
            let t = ray.t(k, self.dt);
            let p = ray.at(t);
            let (c, cell) = self.cell_of(p);
            if cell != cached_cell {
                cached_cell = cell;
                dist = self.distance[cell];
            }
            if dist != 0 {
                k = self.leap(ray, c, dist, k);
                continue;
            }
            if value(p) >= threshold {
                // Bisect between the previous sample point (below the threshold, or the
                // entry point) and this one.
                let mut lo = (t - self.dt).max(ray.t_entry);
                let mut hi = t;
                if k > ray.k_entry && value(ray.at(lo)) < threshold {
                    for _ in 0..ISO_REFINE_STEPS {
                        let mid = 0.5 * (lo + hi);
                        if value(ray.at(mid)) >= threshold {
                            hi = mid;
                        } else {
                            lo = mid;
                        }
                    }
                    // Linear interpolation inside the last bracket.
                    let (vl, vh) = (value(ray.at(lo)), value(ray.at(hi)));
                    if vh > vl {
                        hi = lo + (hi - lo) * ((threshold - vl) / (vh - vl)).clamp(0.0, 1.0);
                    }
                }
                return Some(hi);
            }
            k += 1;
        }
        None
    }

    /// The MIP mode's ray: the classified colour of its maximum ([`Caster::mip_max`]).
    pub(super) fn mip(&self, ray: &Ray, guard: &Guard) -> ([f32; 3], f32) {
        let Some((best, _)) = self.mip_max(ray, guard) else {
            return ([0.0; 3], 0.0);
        };
        let e = self.lut.get(best);
        ([e[0] * e[3], e[1] * e[3], e[2] * e[3]], e[3])
    }

    /// The largest value of `ray`'s samples and the ray parameter (mm) of the first
    /// sample that holds it; `None` when it takes no finite sample.
    pub(super) fn mip_max(&self, ray: &Ray, guard: &Guard) -> Option<(f32, f32)> {
        let mut best = f32::NEG_INFINITY;
        let mut best_k = ray.k0;
        let mut k = ray.k0;
        while k <= ray.k1 {
            let p = ray.at(ray.t(k, self.dt));
            if self.skip_empty {
                let (c, cell) = self.cell_of(p);
                // A cell whose maximum cannot beat the current best is skipped.
                if self.field.cells[cell].1 <= best {
                    k = self.leap(ray, c, self.distance[cell].max(1), k);
                    continue;
                }
            }
            let v = self.field.value_in(p, guard);
            if v > best {
                (best, best_k) = (v, k);
            }
            k += 1;
        }
        best.is_finite().then(|| (best, ray.t(best_k, self.dt)))
    }
}

/// A camera's rays ([`Camera::ray`]) expressed in a field's index space: per pixel a
/// few f32 operations, instead of building the world ray and transforming it in f64.
pub(super) struct IndexRays {
    /// Perspective: the eye; orthographic: the image centre (index units).
    pub(super) origin: Vec3,
    /// The camera's forward, right and up axes in world units, and in index units.
    pub(super) world: [Vec3; 3],
    pub(super) index: [Vec3; 3],
    pub(super) perspective: bool,
    /// Image-plane coordinate of pixel `(x, y)`: `u = u0 + x du`, `v = v0 + y dv`.
    pub(super) u0: f32,
    pub(super) du: f32,
    pub(super) v0: f32,
    pub(super) dv: f32,
}

impl IndexRays {
    pub(super) fn new(camera: &Camera, field: &Field, width: u32, height: u32) -> IndexRays {
        let to_index = |v: Vec3| {
            let d = field.direction_to_index([v.x as f64, v.y as f64, v.z as f64]);
            Vec3::new(d[0] as f32, d[1] as f32, d[2] as f32)
        };
        let e = camera.eye;
        let o = field.world_to_index([e.x as f64, e.y as f64, e.z as f64]);
        let world = [camera.forward, camera.right, camera.up];
        let [u0, du, v0, dv] = camera.image_plane(width, height);
        IndexRays {
            origin: Vec3::new(o[0] as f32, o[1] as f32, o[2] as f32),
            world,
            index: world.map(to_index),
            perspective: camera.projection == glint_core::camera::Projection::Perspective,
            u0,
            du,
            v0,
            dv,
        }
    }

    /// Index-space origin, index-space direction (index units per mm) and unit world
    /// direction of the ray through pixel `(x, y)`.
    #[inline(always)]
    pub(super) fn ray(&self, x: f32, y: f32) -> (Vec3, Vec3, Vec3) {
        let (u, v) = (self.u0 + x * self.du, self.v0 + y * self.dv);
        let [f, r, up] = self.index;
        if self.perspective {
            let [wf, wr, wu] = self.world;
            let w = wf + wr * u + wu * v;
            let inv = 1.0 / w.length();
            (self.origin, (f + r * u + up * v) * inv, w * inv)
        } else {
            (self.origin + r * u + up * v, f, self.world[0])
        }
    }
}

/// A ray in index space with its sample range.
pub(super) struct Ray {
    pub(super) o: Vec3,
    /// Direction: index units per mm.
    pub(super) d: Vec3,
    /// Per axis `1 / (d dt)` (samples per index unit), +inf where the ray does not
    /// move along the axis.
    pub(super) inv_dk: [f32; 3],
    /// Per axis: the ray moves towards higher indices (or not at all).
    pub(super) face_up: [bool; 3],
    /// First and last sample index to visit.
    pub(super) k0: i64,
    pub(super) k1: i64,
    /// Where the ray enters the clip box (mm), and the first sample index there (the
    /// start bound may put `k0` later).
    pub(super) t_entry: f32,
    pub(super) k_entry: i64,
    /// The samples' offset, in steps, from multiples of the step ([`jitter`]).
    pub(super) j: f32,
}

/// A tile's pixels and their rays' start bounds.
pub(super) struct Pixels<'a> {
    pub(super) xs: (usize, usize),
    pub(super) ys: (usize, usize),
    /// Row-major over the tile: [`StartBounds::tile`].
    pub(super) start: &'a [f32; TILE * TILE],
    /// Row-major over the tile: where each ray stops (mm; infinite unless a surface
    /// hides what lies behind, [`Classification::frame`]'s `far`).
    pub(super) end: &'a [f32; TILE * TILE],
}

/// `ceil(x)` as an integer without libm (baseline x86-64 has no rounding
/// instruction); `x` is finite or saturates.
#[inline(always)]
pub(super) fn ceil_i64(x: f32) -> i64 {
    let k = x as i64;
    k + ((k as f32) < x) as i64
}

/// `floor(x)` as an integer without libm.
#[inline(always)]
pub(super) fn floor_i64(x: f32) -> i64 {
    let k = x as i64;
    k - ((k as f32) > x) as i64
}

impl Ray {
    #[inline(always)]
    pub(super) fn at(&self, t: f32) -> Vec3 {
        self.o + self.d * t
    }

    /// The ray parameter (mm) of sample `k`: `(k + j) dt` (the SIMD loop computes the
    /// same sum for `k = k0 + lane` as `(k0 + lane) + j`, exact for |k| < 2^24).
    #[inline(always)]
    pub(super) fn t(&self, k: i64, dt: f32) -> f32 {
        (k as f32 + self.j) * dt
    }
}

/// The first sample's offset for pixel `(x, y)`, in [0, 1) steps: interleaved gradient
/// noise (J. Jimenez, "Next Generation Post Processing in Call of Duty: Advanced
/// Warfare", SIGGRAPH 2014 course), a deterministic low-discrepancy pattern whose
/// neighbouring pixels take well-spread offsets. Samples then no longer lie on the same
/// spheres (planes, orthographic) around the eye for all pixels, whose crossings with
/// the data's surfaces draw concentric "wood-grain" rings; what is left of sampling
/// error becomes fine, unstructured noise.
#[inline(always)]
pub(super) fn jitter(x: f32, y: f32) -> f32 {
    let fract = |v: f32| v - v.floor();
    fract(52.982_918 * fract(0.067_110_56 * x + 0.005_837_15 * y))
}

#[cfg(test)]
mod jitter_tests {
    use std::sync::Arc;

    use super::*;
    use crate::{Classification, ClassifySettings, TransferFunction};
    use glint_core::Light;
    use glint_core::Material;
    use glint_io::{Samples, Volume};
    use glint_lobe::{Geometry, LobeKind};

    /// Largest per-channel difference (linear RGB, 0..1) allowed between the jittered
    /// and unjittered images of a smooth sphere, away from its silhouette: jitter moves
    /// every sample by less than one step along its ray, which changes the composite
    /// integral of a field smooth on the scale of a step by a small fraction of its
    /// value; the same differences at edges are excluded.
    const JITTER_TOLERANCE: f32 = 0.03;

    #[test]
    fn jittered_and_unjittered_smooth_spheres_agree_away_from_edges() {
        // Value r - |x| (mm from the centre), a cone that is linear along every ray:
        // opacity ramps in over 6 mm inside the surface at radius 20.
        let n = 48;
        let c = (n - 1) as f32 / 2.0;
        let mut v = Vec::with_capacity(n * n * n);
        for k in 0..n {
            for j in 0..n {
                for i in 0..n {
                    let d =
                        ((i as f32 - c).powi(2) + (j as f32 - c).powi(2) + (k as f32 - c).powi(2))
                            .sqrt();
                    v.push(20.0 - d);
                }
            }
        }
        let vol = Volume::new([n; 3], [1.0; 3], Samples::F32(v)).unwrap();
        let field = Arc::new(Field::new(&vol).unwrap());
        let tf =
            TransferFunction::from_flat(&[0.0, 0.0, 6.0, 0.08, 40.0, 0.08], &[0.0, 0.9, 0.7, 0.5])
                .unwrap();
        let settings = FrameSettings {
            width: 64,
            height: 64,
            ..Default::default()
        };
        let class = Classification::new(field, &tf, &ClassifySettings::default()).unwrap();
        let shader = Shader::new(
            LobeKind::Exact,
            10.0,
            0,
            Geometry::Phong,
            Material::default(),
            vec![Light::HEADLIGHT],
            0.0,
        )
        .unwrap();
        let on = class
            .render_jittered(&shader, &settings, &|_| {}, true, Default::default())
            .unwrap();
        let off = class
            .render_jittered(&shader, &settings, &|_| {}, false, Default::default())
            .unwrap();
        assert_ne!(on.rgb, off.rgb, "jitter changed nothing");
        // Away from edges: pixels whose 5x5 neighbourhood is all nearly opaque.
        let (w, h) = (64usize, 64usize);
        let deep = |x: usize, y: usize| {
            (y.saturating_sub(2)..(y + 3).min(h)).all(|yy| {
                (x.saturating_sub(2)..(x + 3).min(w)).all(|xx| off.alpha[yy * w + xx] > 0.9)
            })
        };
        let mut checked = 0;
        for y in 2..h - 2 {
            for x in 2..w - 2 {
                if !deep(x, y) {
                    continue;
                }
                checked += 1;
                let (a, b) = (on.rgb[y * w + x], off.rgb[y * w + x]);
                for ch in 0..3 {
                    assert!(
                        (a[ch] - b[ch]).abs() <= JITTER_TOLERANCE,
                        "pixel ({x}, {y}): {a:?} vs {b:?}"
                    );
                }
            }
        }
        assert!(checked > 200, "only {checked} pixels inside the sphere");
    }

    #[test]
    fn jitter_is_a_fraction_of_a_step_and_deterministic() {
        let mut seen = [false; 10];
        for y in 0..32 {
            for x in 0..32 {
                let j = jitter(x as f32, y as f32);
                assert!((0.0..1.0).contains(&j), "{j}");
                assert_eq!(j.to_bits(), jitter(x as f32, y as f32).to_bits());
                seen[(j * 10.0) as usize] = true;
            }
        }
        // Spread over the whole step.
        assert!(seen.iter().all(|s| *s), "{seen:?}");
    }
}
