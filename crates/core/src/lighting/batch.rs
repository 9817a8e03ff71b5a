//! The lighting model's batch form: many samples lit at once, as columns (structure of
//! arrays), so every step is a loop the compiler vectorises and the lobe is evaluated
//! by one call of its SIMD kernel ([`glint_lobe::Specular::eval_slice`]) for every
//! sample and light. Each step performs the scalar form's operations in the same order
//! (no FMA contraction), so a batch gives [`Shader::shade`] and [`Shader::shade_normal`]
//! bit for bit (tested below); on x86-64 the loops are compiled a second time for AVX2
//! and chosen at run time.

use glint_lobe::Geometry;

use super::transport::{hybrid_terms, medium_factor, phase_hg};
use super::{flat, Material, Shader};
use crate::math::Vec3;

/// Samples to light together, as columns. Fill the first [`ShadeBatch::len`] entries
/// of `normal`, `view` and `color`, then call [`Shader::shade_gradients`] (volume
/// samples: `normal` holds world gradients) or [`Shader::shade_normals`] (surface
/// samples: unit normals); `color` then holds the lit colours. The buffers are kept
/// between batches, so lighting allocates nothing once they have grown.
#[derive(Clone, Debug, Default)]
pub struct ShadeBatch {
    len: usize,
    /// Per sample: the gradient or unit normal (x, y, z columns); replaced by the unit
    /// normal turned towards the viewer.
    pub normal: [Vec<f32>; 3],
    /// Per sample: the unit vector towards the eye.
    pub view: [Vec<f32>; 3],
    /// Per sample: the unlit linear colour, replaced by the lit one.
    pub color: [Vec<f32>; 3],
    /// Per sample: gradient magnitude, whether it passes the gate, `N·V`, and the
    /// diffuse and specular sums.
    magnitude: Vec<f32>,
    usable: Vec<bool>,
    n_dot_v: Vec<f32>,
    diffuse: Vec<f32>,
    specular: Vec<f32>,
    /// Per light and sample (light-major): `N·L`, the lobe's cosine, the lobe's value.
    n_dot_l: Vec<f32>,
    cos: Vec<f32>,
    lobe: Vec<f32>,
    /// Shadowed lighting ([`Shader::shade_gradients_shadowed`]): per light and sample
    /// (light-major) the transmittance, per sample the ambient occlusion and the
    /// phase sum.
    transmittance: Vec<f32>,
    occlusion: Vec<f32>,
    phase: Vec<f32>,
}

/// The first `n` elements of `v`, grown with zeros if it is shorter (every element
/// below `n` is written before it is read, so stale values need no clearing).
fn first(v: &mut Vec<f32>, n: usize) -> &mut [f32] {
    if v.len() < n {
        v.resize(n, 0.0);
    }
    &mut v[..n]
}

impl ShadeBatch {
    /// Samples in the batch.
    pub fn len(&self) -> usize {
        self.len
    }

    /// Whether the batch holds no sample.
    pub fn is_empty(&self) -> bool {
        self.len == 0
    }

    /// Sets the number of samples to `n`, growing the columns to at least `n` entries
    /// (the entries keep whatever they held: the caller writes the inputs).
    pub fn set_len(&mut self, n: usize) {
        for col in self
            .normal
            .iter_mut()
            .chain(&mut self.view)
            .chain(&mut self.color)
        {
            first(col, n);
        }
        self.len = n;
    }

    /// The columns [`Shader::shade_gradients_shadowed`] reads besides the others, for
    /// `lights` lights (the shader's placed lights): the transmittance of light `i` to
    /// sample `k` at `[i * len + k]`, and each sample's ambient occlusion. Call after
    /// [`ShadeBatch::set_len`]; the caller fills both.
    pub fn shadow_columns(&mut self, lights: usize) -> (&mut [f32], &mut [f32]) {
        let n = self.len;
        (
            first(&mut self.transmittance, n * lights),
            first(&mut self.occlusion, n),
        )
    }
}

impl Shader {
    /// Lights the volume samples of `batch`, whose `normal` columns hold world
    /// gradients: [`Shader::shade`] for each, bit for bit.
    pub fn shade_gradients(&self, batch: &mut ShadeBatch) {
        #[cfg(target_arch = "x86_64")]
        if avx2() {
            // SAFETY: the CPU supports AVX2 (checked at run time just above).
            return unsafe { self.shade_gradients_avx2(batch) };
        }
        self.shade_gradients_body(batch)
    }

    /// Lights the surface samples of `batch`, whose `normal` columns hold unit
    /// normals: [`Shader::shade_normal`] for each, bit for bit.
    pub fn shade_normals(&self, batch: &mut ShadeBatch) {
        #[cfg(target_arch = "x86_64")]
        if avx2() {
            // SAFETY: the CPU supports AVX2 (checked at run time just above).
            return unsafe { self.shade_normals_avx2(batch) };
        }
        self.shade_normals_body(batch)
    }

    /// Lights the volume samples of `batch` (world gradients in `normal`) with each
    /// light scaled by its transmittance and the ambient term by the occlusion
    /// ([`ShadeBatch::shadow_columns`]): [`Shader::shade_shadowed`] for each, bit for
    /// bit.
    pub fn shade_gradients_shadowed(&self, batch: &mut ShadeBatch) {
        #[cfg(target_arch = "x86_64")]
        if avx2() {
            // SAFETY: the CPU supports AVX2 (checked at run time just above).
            return unsafe { self.shade_shadowed_avx2(batch) };
        }
        self.shade_shadowed_body(batch)
    }

    /// [`Shader::shade_gradients_shadowed`] compiled for AVX2.
    ///
    /// # Safety
    /// The CPU must support AVX2.
    #[cfg(target_arch = "x86_64")]
    #[target_feature(enable = "avx2")]
    unsafe fn shade_shadowed_avx2(&self, batch: &mut ShadeBatch) {
        self.shade_shadowed_body(batch)
    }

    #[inline(always)]
    fn shade_shadowed_body(&self, b: &mut ShadeBatch) {
        if !self.material().shade || b.len == 0 {
            return;
        }
        self.gradient_normals(b);
        self.light_columns_shadowed(b);
        let n = b.len;
        let m = self.material();
        let (diffuse, specular, phase) = (&b.diffuse[..n], &b.specular[..n], &b.phase[..n]);
        let (magnitude, usable) = (&b.magnitude[..n], &b.usable[..n]);
        let occlusion = &b.occlusion[..n];
        for col in &mut b.color {
            for k in 0..n {
                let c = col[k];
                let flat = c * medium_factor(m, occlusion[k], phase[k]);
                let w = self.gate_weight(magnitude[k]);
                let sums = [diffuse[k], specular[k], phase[k]];
                let (lit, spec) = hybrid_terms(m, sums, occlusion[k], w);
                let shaded = c * lit + spec;
                col[k] = if usable[k] { shaded } else { flat };
            }
        }
    }

    /// [`Shader::shade_gradients`] compiled for AVX2.
    ///
    /// # Safety
    /// The CPU must support AVX2.
    #[cfg(target_arch = "x86_64")]
    #[target_feature(enable = "avx2")]
    unsafe fn shade_gradients_avx2(&self, batch: &mut ShadeBatch) {
        self.shade_gradients_body(batch)
    }

    /// [`Shader::shade_normals`] compiled for AVX2.
    ///
    /// # Safety
    /// The CPU must support AVX2.
    #[cfg(target_arch = "x86_64")]
    #[target_feature(enable = "avx2")]
    unsafe fn shade_normals_avx2(&self, batch: &mut ShadeBatch) {
        self.shade_normals_body(batch)
    }

    #[inline(always)]
    fn shade_gradients_body(&self, b: &mut ShadeBatch) {
        if !self.material().shade || b.len == 0 {
            return;
        }
        self.gradient_normals(b);
        self.light_columns(b);
        let n = b.len;
        let m = self.material();
        let (diffuse, specular) = (&b.diffuse[..n], &b.specular[..n]);
        let (magnitude, usable) = (&b.magnitude[..n], &b.usable[..n]);
        for col in &mut b.color {
            for k in 0..n {
                let c = col[k];
                let unshaded = c * flat(m);
                let lit = m.ambient + m.diffuse * diffuse[k];
                let shaded = c * lit + m.specular * specular[k];
                let w = self.gate_weight(magnitude[k]);
                let mixed = unshaded + w * (shaded - unshaded);
                col[k] = if usable[k] { mixed } else { unshaded };
            }
        }
    }

    #[inline(always)]
    fn shade_normals_body(&self, b: &mut ShadeBatch) {
        if !self.material().shade || b.len == 0 {
            return;
        }
        self.light_columns(b);
        let n = b.len;
        let m: &Material = self.material();
        let (diffuse, specular) = (&b.diffuse[..n], &b.specular[..n]);
        for col in &mut b.color {
            for (c, (d, s)) in col[..n].iter_mut().zip(diffuse.iter().zip(specular)) {
                *c = *c * (m.ambient + m.diffuse * *d) + m.specular * *s;
            }
        }
    }

    /// Gradients to unit normals (down the gradient), with each sample's magnitude and
    /// whether it passes the gate ([`Shader::shade`]'s test).
    #[inline(always)]
    fn gradient_normals(&self, b: &mut ShadeBatch) {
        let n = b.len;
        let g0 = self.gate;
        let magnitude = first(&mut b.magnitude, n);
        if b.usable.len() < n {
            b.usable.resize(n, false);
        }
        let usable = &mut b.usable[..n];
        let [gx, gy, gz] = &mut b.normal;
        let (gx, gy, gz) = (&mut gx[..n], &mut gy[..n], &mut gz[..n]);
        for k in 0..n {
            let (x, y, z) = (gx[k], gy[k], gz[k]);
            let gm2 = x * x + y * y + z * z;
            usable[k] = gm2 > g0 * g0 && gm2 < f32::INFINITY;
            let gm = gm2.sqrt();
            magnitude[k] = gm;
            let inv = -1.0 / gm;
            (gx[k], gy[k], gz[k]) = (x * inv, y * inv, z * inv);
        }
    }

    /// Turns the unit normals towards the viewer and sums each sample's diffuse and
    /// specular terms over the lights (the scalar form's `sums`).
    #[inline(always)]
    fn light_columns(&self, b: &mut ShadeBatch) {
        let n = b.len;
        let lights = self.world_lights();
        let [nx, ny, nz] = &mut b.normal;
        let (nx, ny, nz) = (&mut nx[..n], &mut ny[..n], &mut nz[..n]);
        let [vx, vy, vz] = &b.view;
        let (vx, vy, vz) = (&vx[..n], &vy[..n], &vz[..n]);
        let n_dot_v = first(&mut b.n_dot_v, n);
        for k in 0..n {
            let d = nx[k] * vx[k] + ny[k] * vy[k] + nz[k] * vz[k];
            let flip = d < 0.0;
            nx[k] = if flip { -nx[k] } else { nx[k] };
            ny[k] = if flip { -ny[k] } else { ny[k] };
            nz[k] = if flip { -nz[k] } else { nz[k] };
            n_dot_v[k] = if flip { -d } else { d };
        }
        let n_dot_l = first(&mut b.n_dot_l, n * lights.len());
        let cos = first(&mut b.cos, n * lights.len());
        for (i, &(l, _)) in lights.iter().enumerate() {
            let (ndl, cos) = (&mut n_dot_l[i * n..][..n], &mut cos[i * n..][..n]);
            for k in 0..n {
                let d = nx[k] * l.x + ny[k] * l.y + nz[k] * l.z;
                ndl[k] = d;
                cos[k] = match self.geometry() {
                    // Phong R·V = 2(N·L)(N·V) - L·V.
                    Geometry::Phong => {
                        2.0 * d * n_dot_v[k] - (l.x * vx[k] + l.y * vy[k] + l.z * vz[k])
                    }
                    // Blinn N·H, H = normalize_or_zero(L + V).
                    Geometry::Blinn => {
                        let h = (l + Vec3::new(vx[k], vy[k], vz[k])).normalize_or_zero();
                        nx[k] * h.x + ny[k] * h.y + nz[k] * h.z
                    }
                };
            }
        }
        let lobe = first(&mut b.lobe, n * lights.len());
        self.specular().eval_slice(cos, lobe);
        let diffuse = first(&mut b.diffuse, n);
        let specular = first(&mut b.specular, n);
        diffuse.fill(0.0);
        specular.fill(0.0);
        for (i, &(_, intensity)) in lights.iter().enumerate() {
            let (ndl, lobe) = (&n_dot_l[i * n..][..n], &lobe[i * n..][..n]);
            for k in 0..n {
                let lit = ndl[k] > 0.0;
                diffuse[k] = if lit {
                    diffuse[k] + intensity * ndl[k]
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
    }
}

impl Shader {
    /// [`Shader`]'s `light_columns` with each light's intensity scaled by its
    /// transmittance, and the phase sum of every sample (the scalar form's
    /// `phase_sum` and `sums_shadowed`, in the same order).
    #[inline(always)]
    fn light_columns_shadowed(&self, b: &mut ShadeBatch) {
        let n = b.len;
        let lights = self.world_lights();
        let count = lights.len();
        let [nx, ny, nz] = &mut b.normal;
        let (nx, ny, nz) = (&mut nx[..n], &mut ny[..n], &mut nz[..n]);
        let [vx, vy, vz] = &b.view;
        let (vx, vy, vz) = (&vx[..n], &vy[..n], &vz[..n]);
        let n_dot_v = first(&mut b.n_dot_v, n);
        for k in 0..n {
            let d = nx[k] * vx[k] + ny[k] * vy[k] + nz[k] * vz[k];
            let flip = d < 0.0;
            nx[k] = if flip { -nx[k] } else { nx[k] };
            ny[k] = if flip { -ny[k] } else { ny[k] };
            nz[k] = if flip { -nz[k] } else { nz[k] };
            n_dot_v[k] = if flip { -d } else { d };
        }
        let transmittance = &b.transmittance[..n * count];
        let n_dot_l = first(&mut b.n_dot_l, n * count);
        let cos = first(&mut b.cos, n * count);
        let phase = first(&mut b.phase, n);
        phase.fill(0.0);
        let g = self.anisotropy();
        for (i, &(l, intensity)) in lights.iter().enumerate() {
            let (ndl, cos) = (&mut n_dot_l[i * n..][..n], &mut cos[i * n..][..n]);
            let t = &transmittance[i * n..][..n];
            for k in 0..n {
                let l_dot_v = l.x * vx[k] + l.y * vy[k] + l.z * vz[k];
                phase[k] += (intensity * t[k]) * phase_hg(g, l_dot_v);
                let d = nx[k] * l.x + ny[k] * l.y + nz[k] * l.z;
                ndl[k] = d;
                cos[k] = match self.geometry() {
                    Geometry::Phong => 2.0 * d * n_dot_v[k] - l_dot_v,
                    Geometry::Blinn => {
                        let h = (l + Vec3::new(vx[k], vy[k], vz[k])).normalize_or_zero();
                        nx[k] * h.x + ny[k] * h.y + nz[k] * h.z
                    }
                };
            }
        }
        let lobe = first(&mut b.lobe, n * count);
        self.specular().eval_slice(cos, lobe);
        let diffuse = first(&mut b.diffuse, n);
        let specular = first(&mut b.specular, n);
        diffuse.fill(0.0);
        specular.fill(0.0);
        for (i, &(_, intensity)) in lights.iter().enumerate() {
            let (ndl, lobe) = (&n_dot_l[i * n..][..n], &lobe[i * n..][..n]);
            let t = &transmittance[i * n..][..n];
            for k in 0..n {
                let lit = ndl[k] > 0.0;
                let it = intensity * t[k];
                diffuse[k] = if lit {
                    diffuse[k] + it * ndl[k]
                } else {
                    diffuse[k]
                };
                specular[k] = if lit {
                    specular[k] + it * lobe[k]
                } else {
                    specular[k]
                };
            }
        }
    }
}

/// Whether the CPU runs the AVX2 form of the batch loops (cached by the standard
/// library after the first call).
#[cfg(target_arch = "x86_64")]
fn avx2() -> bool {
    is_x86_feature_detected!("avx2")
}

#[cfg(test)]
mod tests {
    use glint_lobe::LobeKind;

    use super::*;
    use crate::camera::{Camera, CameraSpec};
    use crate::lighting::Light;

    /// A deterministic spread of values in [-1, 1) (a Weyl sequence).
    fn spread(k: usize, salt: f32) -> f32 {
        let x = (k as f32 * 0.618_034 + salt).fract();
        2.0 * x - 1.0
    }

    fn shaders(gate: f32) -> Vec<Shader> {
        let cam = Camera::frame(&CameraSpec::default(), Vec3::ZERO, 1.0, 8, 8).unwrap();
        let lights = vec![
            Light::HEADLIGHT,
            Light {
                azimuth: 40.0,
                elevation: 25.0,
                intensity: 0.7,
            },
            Light {
                azimuth: -120.0,
                elevation: -10.0,
                intensity: 1.3,
            },
        ];
        let mut out = Vec::new();
        for geometry in [Geometry::Phong, Geometry::Blinn] {
            for kind in [LobeKind::EnergyFit, LobeKind::Exact, LobeKind::Schlick] {
                let s = Shader::new(
                    kind,
                    37.0,
                    4,
                    geometry,
                    Material::default(),
                    lights.clone(),
                    gate,
                )
                .unwrap();
                out.push(s.placed(&cam));
            }
        }
        out
    }

    /// Fills a batch of `n` samples: normals (or gradients scaled by `scale`), views
    /// and colours from deterministic spreads, with a few degenerate normals.
    fn fill(b: &mut ShadeBatch, n: usize, scale: f32) {
        b.set_len(n);
        for k in 0..n {
            let g = Vec3::new(spread(k, 0.1), spread(k, 0.37), spread(k, 0.71)) * scale;
            let g = match k % 17 {
                0 => Vec3::ZERO,
                1 => Vec3::new(f32::NAN, 0.0, 1.0),
                2 => Vec3::new(f32::INFINITY, 0.0, 0.0),
                _ => g,
            };
            let v = Vec3::new(spread(k, 0.5) * 0.3, spread(k, 0.9) * 0.3, 1.0).normalize_or_zero();
            for a in 0..3 {
                b.normal[a][k] = g.get(a);
                b.view[a][k] = v.get(a);
                b.color[a][k] = 0.5 + 0.5 * spread(k, 0.2 * a as f32);
            }
        }
    }

    /// The batch's result for sample `k` against the scalar form, bit for bit.
    fn check(got: &ShadeBatch, want: impl Fn(usize) -> [f32; 3], n: usize, what: &str) {
        for k in 0..n {
            let g = [got.color[0][k], got.color[1][k], got.color[2][k]];
            let w = want(k);
            assert_eq!(
                g.map(f32::to_bits),
                w.map(f32::to_bits),
                "{what}, sample {k}: {g:?} vs {w:?}"
            );
        }
    }

    #[test]
    fn gradient_batches_are_the_scalar_form_bit_for_bit_on_every_path() {
        let n = 300;
        for gate in [0.0, 0.3] {
            for shader in shaders(gate) {
                let mut input = ShadeBatch::default();
                fill(&mut input, n, 2.0);
                let want = |k: usize| {
                    let g = Vec3::new(input.normal[0][k], input.normal[1][k], input.normal[2][k]);
                    let v = Vec3::new(input.view[0][k], input.view[1][k], input.view[2][k]);
                    let c = [input.color[0][k], input.color[1][k], input.color[2][k]];
                    shader.shade(c, g, &shader.for_ray(v))
                };
                let mut b = input.clone();
                shader.shade_gradients_body(&mut b);
                check(&b, want, n, "portable");
                #[cfg(target_arch = "x86_64")]
                if avx2() {
                    let mut b = input.clone();
                    // SAFETY: AVX2 is supported (checked above).
                    unsafe { shader.shade_gradients_avx2(&mut b) };
                    check(&b, want, n, "avx2");
                }
                let mut b = input.clone();
                shader.shade_gradients(&mut b);
                check(&b, want, n, "dispatched");
            }
        }
    }

    #[test]
    fn normal_batches_are_the_scalar_form_bit_for_bit_on_every_path() {
        let n = 300;
        for shader in shaders(0.0) {
            let mut input = ShadeBatch::default();
            fill(&mut input, n, 1.0);
            for k in 0..n {
                let g = Vec3::new(input.normal[0][k], input.normal[1][k], input.normal[2][k]);
                let u = g.normalize_or_zero();
                for a in 0..3 {
                    input.normal[a][k] = u.get(a);
                }
            }
            let want = |k: usize| {
                let u = Vec3::new(input.normal[0][k], input.normal[1][k], input.normal[2][k]);
                let v = Vec3::new(input.view[0][k], input.view[1][k], input.view[2][k]);
                let c = [input.color[0][k], input.color[1][k], input.color[2][k]];
                shader.shade_normal(c, u, v)
            };
            let mut b = input.clone();
            shader.shade_normals_body(&mut b);
            check(&b, want, n, "portable");
            #[cfg(target_arch = "x86_64")]
            if avx2() {
                let mut b = input.clone();
                // SAFETY: AVX2 is supported (checked above).
                unsafe { shader.shade_normals_avx2(&mut b) };
                check(&b, want, n, "avx2");
            }
        }
    }

    #[test]
    fn shadowed_batches_are_the_scalar_form_bit_for_bit_on_every_path() {
        let n = 300;
        for gate in [0.0, 0.3] {
            for (s, shader) in shaders(gate).into_iter().enumerate() {
                let g = [0.0, 0.6, -0.4][s % 3];
                let shader = shader.with_anisotropy(g).unwrap();
                let lights = shader.world_lights().len();
                let mut input = ShadeBatch::default();
                fill(&mut input, n, 2.0);
                let (t, occ) = input.shadow_columns(lights);
                for (i, x) in t.iter_mut().enumerate() {
                    *x = 0.5 + 0.5 * spread(i, 0.33);
                }
                for (k, x) in occ.iter_mut().enumerate() {
                    *x = 0.5 + 0.5 * spread(k, 0.77);
                }
                let (t, occ) = (input.transmittance.clone(), input.occlusion.clone());
                let want = |k: usize| {
                    let g = Vec3::new(input.normal[0][k], input.normal[1][k], input.normal[2][k]);
                    let v = Vec3::new(input.view[0][k], input.view[1][k], input.view[2][k]);
                    let c = [input.color[0][k], input.color[1][k], input.color[2][k]];
                    let tk: Vec<f32> = (0..lights).map(|i| t[i * n + k]).collect();
                    shader.shade_shadowed(c, g, &shader.for_ray(v), &tk, occ[k])
                };
                let mut b = input.clone();
                shader.shade_shadowed_body(&mut b);
                check(&b, want, n, "portable");
                #[cfg(target_arch = "x86_64")]
                if avx2() {
                    let mut b = input.clone();
                    // SAFETY: AVX2 is supported (checked above).
                    unsafe { shader.shade_shadowed_avx2(&mut b) };
                    check(&b, want, n, "avx2");
                }
                let mut b = input.clone();
                shader.shade_gradients_shadowed(&mut b);
                check(&b, want, n, "dispatched");
            }
        }
    }

    #[test]
    fn unshaded_material_leaves_the_colours() {
        let shader = Shader::new(
            LobeKind::EnergyFit,
            20.0,
            4,
            Geometry::Phong,
            Material {
                shade: false,
                ..Material::default()
            },
            vec![Light::HEADLIGHT],
            0.0,
        )
        .unwrap();
        let mut b = ShadeBatch::default();
        fill(&mut b, 20, 1.0);
        let before = b.color.clone();
        shader.shade_gradients(&mut b);
        assert_eq!(b.color, before);
        shader.shade_normals(&mut b);
        assert_eq!(b.color, before);
    }
}
