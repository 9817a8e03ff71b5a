//! Per-pixel lighting of surfaces with a [`Shader`]'s lobe, geometry, material and
//! lights: the volume renderer's model (ambient + diffuse + lobe specular) with a unit
//! surface normal in place of the gradient, and no gradient gate.

use glint_lobe::Geometry;

use super::frame::Frame;
use super::tile::Ctx;
use super::Surfaces;
use crate::camera::Projection;
use crate::math::Vec3;
use crate::shading::Shader;

impl Shader {
    /// Lit linear colour of a surface point of colour `base`, unit `normal` and unit
    /// `view` (towards the eye). Two-sided: a normal facing away from the viewer is
    /// flipped, so open surfaces and inner walls are lit from the side that is seen.
    /// The reference of [`Batch`]'s lighting, which lights many samples at once.
    #[cfg(test)]
    pub(crate) fn shade_surface(&self, base: [f32; 3], normal: Vec3, view: Vec3) -> [f32; 3] {
        let m = &self.material;
        if !m.shade {
            return base;
        }
        let mut n = normal;
        let mut n_dot_v = n.dot(view);
        if n_dot_v < 0.0 {
            n = -n;
            n_dot_v = -n_dot_v;
        }
        let (mut diffuse, mut specular) = (0.0f32, 0.0f32);
        for &(l, intensity) in &self.lights {
            let n_dot_l = n.dot(l);
            if n_dot_l > 0.0 {
                diffuse += intensity * n_dot_l;
                // Phong R·V = 2(N·L)(N·V) - L·V, Blinn N·H (glint_lobe::Geometry::cos
                // for unit vectors).
                let c = match self.geometry {
                    Geometry::Phong => 2.0 * n_dot_l * n_dot_v - l.dot(view),
                    Geometry::Blinn => n.dot((l + view).normalize_or_zero()),
                };
                specular += intensity * self.specular.eval(c);
            }
        }
        let lit = m.ambient + m.diffuse * diffuse;
        let spec = m.specular * specular;
        base.map(|c| c * lit + spec)
    }
}

/// Samples a [`Batch`] lights at once.
const BATCH: usize = 256;

/// Covered samples awaiting light, as columns: each step of the lighting runs over
/// the whole batch (vectorisable loops, one call of the lobe's SIMD
/// [`eval_slice`](glint_lobe::Specular::eval_slice) per light).
pub(super) struct Batch {
    len: usize,
    /// The triangle of each sample.
    id: Vec<u32>,
    /// The pixel of the tile each sample belongs to.
    pixel: Vec<u32>,
    /// Sample coordinates.
    x: Vec<f32>,
    y: Vec<f32>,
    /// The interpolated normal, then unit, then flipped to face the viewer.
    n: [Vec<f32>; 3],
    /// Samples whose interpolated normal is zero or not finite.
    degenerate: Vec<bool>,
    /// Unlit colour, then lit.
    color: [Vec<f32>; 3],
    /// Unit vector towards the eye.
    view: [Vec<f32>; 3],
    n_dot_v: Vec<f32>,
    n_dot_l: Vec<f32>,
    cos: Vec<f32>,
    lobe: Vec<f32>,
    diffuse: Vec<f32>,
    specular: Vec<f32>,
}

impl Default for Batch {
    fn default() -> Self {
        let col = || vec![0.0f32; BATCH];
        Batch {
            len: 0,
            id: vec![0; BATCH],
            pixel: vec![0; BATCH],
            degenerate: vec![false; BATCH],
            x: col(),
            y: col(),
            n: [col(), col(), col()],
            color: [col(), col(), col()],
            view: [col(), col(), col()],
            n_dot_v: col(),
            n_dot_l: col(),
            cos: col(),
            lobe: col(),
            diffuse: col(),
            specular: col(),
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
        self.n[0][k] = normal.x;
        self.n[1][k] = normal.y;
        self.n[2][k] = normal.z;
        for (c, v) in self.color.iter_mut().zip(color) {
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
        if ctx.shader.material.shade {
            self.views(ctx.frame);
            self.light(ctx.shader);
        }
        let [r, g, b] = &self.color;
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
        let [nx, ny, nz] = &mut self.n;
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
        let [vx, vy, vz] = &mut self.view;
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

    /// [`Shader::shade_surface`] over the batch, the lobe through `eval_slice`.
    #[inline(always)]
    fn light(&mut self, shader: &Shader) {
        let n = self.len;
        let m = &shader.material;
        let [nx, ny, nz] = &mut self.n;
        let (nx, ny, nz) = (&mut nx[..n], &mut ny[..n], &mut nz[..n]);
        let [vx, vy, vz] = &self.view;
        let (vx, vy, vz) = (&vx[..n], &vy[..n], &vz[..n]);
        let n_dot_v = &mut self.n_dot_v[..n];
        // Two-sided: a normal facing away from the viewer is flipped.
        for k in 0..n {
            let d = nx[k] * vx[k] + ny[k] * vy[k] + nz[k] * vz[k];
            let flip = d < 0.0;
            nx[k] = if flip { -nx[k] } else { nx[k] };
            ny[k] = if flip { -ny[k] } else { ny[k] };
            nz[k] = if flip { -nz[k] } else { nz[k] };
            n_dot_v[k] = if flip { -d } else { d };
        }
        let diffuse = &mut self.diffuse[..n];
        let specular = &mut self.specular[..n];
        diffuse.fill(0.0);
        specular.fill(0.0);
        let (n_dot_l, cos, lobe) = (
            &mut self.n_dot_l[..n],
            &mut self.cos[..n],
            &mut self.lobe[..n],
        );
        for &(l, intensity) in &shader.lights {
            for k in 0..n {
                let ndl = nx[k] * l.x + ny[k] * l.y + nz[k] * l.z;
                n_dot_l[k] = ndl;
                cos[k] = match shader.geometry {
                    // Phong R·V = 2(N·L)(N·V) - L·V.
                    Geometry::Phong => {
                        2.0 * ndl * n_dot_v[k] - (l.x * vx[k] + l.y * vy[k] + l.z * vz[k])
                    }
                    // Blinn N·H.
                    Geometry::Blinn => {
                        let h = (l + Vec3::new(vx[k], vy[k], vz[k])).normalize_or_zero();
                        nx[k] * h.x + ny[k] * h.y + nz[k] * h.z
                    }
                };
            }
            shader.specular.eval_slice(cos, lobe);
            for k in 0..n {
                let lit = n_dot_l[k] > 0.0;
                diffuse[k] = if lit {
                    diffuse[k] + intensity * n_dot_l[k]
                } else {
                    diffuse[k]
                };
                specular[k] = if lit {
                    specular[k] + intensity * lobe[k]
                } else {
                    specular[k]
                };
            }
        }
        for c in &mut self.color {
            for (c, (d, s)) in c[..n].iter_mut().zip(diffuse.iter().zip(specular.iter())) {
                *c = *c * (m.ambient + m.diffuse * *d) + m.specular * *s;
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use glint_lobe::LobeKind;

    use super::*;
    use crate::tf::Material;

    #[test]
    fn surface_shading_matches_glint_lobe_geometry_and_is_two_sided() {
        let l = Vec3::new(0.3, 0.2, 0.9).normalize_or_zero();
        let v = Vec3::new(-0.1, 0.1, 1.0).normalize_or_zero();
        let n = Vec3::new(0.1, 0.0, 1.0).normalize_or_zero();
        let m = Material::default();
        for geometry in [Geometry::Phong, Geometry::Blinn] {
            let mut shader =
                Shader::new(LobeKind::Exact, 20.0, 4, geometry, m, vec![], 0.0).unwrap();
            shader.lights = vec![(l, 1.0)];
            let c = geometry.cos(n.to_array(), l.to_array(), v.to_array());
            let want = m.ambient + m.diffuse * n.dot(l) + m.specular * c.max(0.0).powf(20.0);
            let got = shader.shade_surface([1.0; 3], n, v);
            assert!(
                (got[0] - want).abs() < 1e-5,
                "{geometry}: {got:?} vs {want}"
            );
            // The back face seen from the front is lit like the front.
            assert_eq!(shader.shade_surface([1.0; 3], -n, v), got);
        }
    }
}
