//! Per-pixel lighting of surfaces: covered samples gathered into batches, their normals
//! made unit and their view vectors computed here, then lit by glint-core's lighting
//! model ([`glint_core::Shader::shade_normals`]) and added to their pixels.

use glint_core::camera::Projection;
use glint_core::{ShadeBatch, Vec3};

use super::ctx::Ctx;
use super::frame::Frame;
use super::Surfaces;

/// Samples a [`Batch`] lights at once.
const BATCH: usize = 256;

/// Covered samples awaiting light, as columns: each step runs over the whole batch
/// (vectorisable loops), the lighting itself in glint-core's [`ShadeBatch`].
pub(super) struct Batch {
    len: usize,
    /// The triangle of each sample.
    id: Vec<u32>,
    /// The pixel of the tile each sample belongs to.
    pixel: Vec<u32>,
    /// Sample coordinates.
    x: Vec<f32>,
    y: Vec<f32>,
    /// Samples whose interpolated normal is zero or not finite.
    degenerate: Vec<bool>,
    /// The normals (interpolated, then unit), views and colours (unlit, then lit).
    shade: ShadeBatch,
}

impl Default for Batch {
    fn default() -> Self {
        let mut shade = ShadeBatch::default();
        shade.set_len(BATCH);
        Batch {
            len: 0,
            id: vec![0; BATCH],
            pixel: vec![0; BATCH],
            degenerate: vec![false; BATCH],
            x: vec![0.0; BATCH],
            y: vec![0.0; BATCH],
            shade,
        }
    }
}

impl Batch {
    /// Empties the batch.
    pub(super) fn clear(&mut self) {
        self.len = 0;
    }

    /// Whether the batch holds [`BATCH`] samples (flush it before the next push).
    pub(super) fn is_full(&self) -> bool {
        self.len == BATCH
    }

    /// Adds the sample at `(x, y)` of pixel `pixel` on triangle `id`, with its
    /// interpolated normal (not normalised) and unlit colour.
    #[inline(always)]
    pub(super) fn push(
        &mut self,
        id: u32,
        pixel: u32,
        x: f32,
        y: f32,
        normal: Vec3,
        color: [f32; 3],
    ) {
        let k = self.len;
        self.id[k] = id;
        self.pixel[k] = pixel;
        self.x[k] = x;
        self.y[k] = y;
        self.shade.normal[0][k] = normal.x;
        self.shade.normal[1][k] = normal.y;
        self.shade.normal[2][k] = normal.z;
        for (c, v) in self.shade.color.iter_mut().zip(color) {
            c[k] = v;
        }
        self.len += 1;
    }

    /// Lights the samples and adds each to its pixel's `sum` and `covered`; returns
    /// how many there were and empties the batch.
    pub(super) fn flush(&mut self, ctx: &Ctx, sum: &mut [[f32; 3]], covered: &mut [u32]) -> u64 {
        #[cfg(target_arch = "x86_64")]
        if ctx.avx2 {
            // SAFETY: `avx2` is set only when the CPU supports AVX2
            // (`super::avx2::supported`).
            return unsafe { self.flush_avx2(ctx, sum, covered) };
        }
        self.flush_body(ctx, sum, covered)
    }

    /// [`Batch::flush`] compiled for AVX2: the same loops, eight lanes wide (no FMA,
    /// so the results are the same).
    ///
    /// # Safety
    /// The CPU must support AVX2.
    #[cfg(target_arch = "x86_64")]
    #[target_feature(enable = "avx2")]
    unsafe fn flush_avx2(&mut self, ctx: &Ctx, sum: &mut [[f32; 3]], covered: &mut [u32]) -> u64 {
        self.flush_body(ctx, sum, covered)
    }

    #[inline(always)]
    fn flush_body(&mut self, ctx: &Ctx, sum: &mut [[f32; 3]], covered: &mut [u32]) -> u64 {
        let n = self.len;
        if n == 0 {
            return 0;
        }
        self.normalize(ctx.s);
        if ctx.shader.material().shade {
            self.views(ctx.frame);
            self.shade.set_len(n);
            ctx.shader.shade_normals(&mut self.shade);
        }
        let [r, g, b] = &self.shade.color;
        for (k, &p) in self.pixel[..n].iter().enumerate() {
            let s = &mut sum[p as usize];
            s[0] += r[k];
            s[1] += g[k];
            s[2] += b[k];
            covered[p as usize] += 1;
        }
        self.len = 0;
        n as u64
    }

    /// Makes the normals unit ([`Vec3::normalize_or_zero`]); a sample whose normal
    /// is zero or not finite gets its triangle's face normal.
    #[inline(always)]
    fn normalize(&mut self, s: &Surfaces) {
        let n = self.len;
        let [nx, ny, nz] = &mut self.shade.normal;
        let (nx, ny, nz) = (&mut nx[..n], &mut ny[..n], &mut nz[..n]);
        let degenerate = &mut self.degenerate[..n];
        let mut any = false;
        for k in 0..n {
            let (x, y, z) = (nx[k], ny[k], nz[k]);
            let len = (x * x + y * y + z * z).sqrt();
            let ok = len.is_finite() && len > 0.0;
            let inv = 1.0 / len;
            let (x, y, z) = if ok {
                (x * inv, y * inv, z * inv)
            } else {
                (0.0, 0.0, 0.0)
            };
            (nx[k], ny[k], nz[k]) = (x, y, z);
            let bad = (x == 0.0 && y == 0.0 && z == 0.0) || !x.is_finite();
            degenerate[k] = bad;
            any |= bad;
        }
        if !any {
            return;
        }
        for k in 0..n {
            if degenerate[k] {
                let [pa, pb, pc] =
                    s.triangles[self.id[k] as usize].map(|i| s.positions[i as usize]);
                let f = (pb - pa).cross(pc - pa).normalize_or_zero();
                (nx[k], ny[k], nz[k]) = (f.x, f.y, f.z);
            }
        }
    }

    /// The unit vectors towards the eye ([`Frame::view`], per sample).
    #[inline(always)]
    fn views(&mut self, frame: &Frame) {
        let n = self.len;
        let cam = &frame.camera;
        let [vx, vy, vz] = &mut self.shade.view;
        let (vx, vy, vz) = (&mut vx[..n], &mut vy[..n], &mut vz[..n]);
        if cam.projection == Projection::Orthographic {
            let v = -cam.forward;
            vx.fill(v.x);
            vy.fill(v.y);
            vz.fill(v.z);
            return;
        }
        let [u0, du, v0, dv] = frame.plane;
        let (f, r, up) = (cam.forward, cam.right, cam.up);
        let (x, y) = (&self.x[..n], &self.y[..n]);
        for k in 0..n {
            let (u, v) = (u0 + x[k] * du, v0 + y[k] * dv);
            // (forward + right u) + up v, then normalize_or_zero, negated.
            let d = [
                f.x + r.x * u + up.x * v,
                f.y + r.y * u + up.y * v,
                f.z + r.z * u + up.z * v,
            ];
            let len = (d[0] * d[0] + d[1] * d[1] + d[2] * d[2]).sqrt();
            let ok = len.is_finite() && len > 0.0;
            let s = 1.0 / len;
            vx[k] = if ok { -(d[0] * s) } else { -0.0 };
            vy[k] = if ok { -(d[1] * s) } else { -0.0 };
            vz[k] = if ok { -(d[2] * s) } else { -0.0 };
        }
    }
}
