//! The lighting model's shadowed batch form: [`Shader::shade_shadowed`] over columns
//! of samples, each light scaled by its transmittance to the sample and the ambient
//! term by the sample's occlusion, with the Henyey-Greenstein medium response (the
//! `shadows` lighting model). Every loop performs the scalar form's operations in the
//! same order (no FMA contraction), so a batch gives the scalar form bit for bit
//! (tested below); on x86-64 the loops are compiled a second time for AVX2 and chosen
//! at run time (the compiler vectorises them; the hand-written AVX2 kernel of
//! [`avx2`](super::avx2) serves the `local` model only).

use glint_lobe::Geometry;

use super::batch::{first, ShadeBatch};
use super::transport::{hybrid_terms, medium_factor, phase_hg};
use super::Shader;
use crate::math::Vec3;

impl ShadeBatch {
    /// The columns [`Shader::shade_gradients_shadowed`] reads besides the others, for
    /// `lights` lights (the shader's placed lights): the transmittance of light `i` to
    /// sample `k` at `[i * len + k]`, and each sample's ambient occlusion. Call after
    /// [`ShadeBatch::set_len`]; the caller fills both.
    pub fn shadow_columns(&mut self, lights: usize) -> (&mut [f32], &mut [f32]) {
        let n = self.len;
        let s = &mut self.shadow;
        (
            first(&mut s.transmittance, n * lights, 0.0),
            first(&mut s.occlusion, n, 0.0),
        )
    }
}

impl Shader {
    /// Lights the volume samples of `batch` (world gradients in `normal`) with each
    /// light scaled by its transmittance and the ambient term by the occlusion
    /// ([`ShadeBatch::shadow_columns`]): [`Shader::shade_shadowed`] for each, bit for
    /// bit.
    pub fn shade_gradients_shadowed(&self, batch: &mut ShadeBatch) {
        #[cfg(target_arch = "x86_64")]
        if std::is_x86_feature_detected!("avx2") {
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
        self.gradient_normals_shadowed(b);
        self.light_columns_shadowed(b);
        let n = b.len;
        let m = self.material();
        let (diffuse, specular, phase) = (
            &b.shadow.diffuse[..n],
            &b.shadow.specular[..n],
            &b.shadow.phase[..n],
        );
        let (magnitude, usable) = (&b.shadow.magnitude[..n], &b.shadow.usable[..n]);
        let occlusion = &b.shadow.occlusion[..n];
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

    /// Gradients to unit normals (down the gradient), with each sample's magnitude and
    /// whether it passes the gate ([`Shader::shade`]'s test).
    #[inline(always)]
    fn gradient_normals_shadowed(&self, b: &mut ShadeBatch) {
        let n = b.len;
        let g0 = self.gate;
        let magnitude = first(&mut b.shadow.magnitude, n, 0.0);
        if b.shadow.usable.len() < n {
            b.shadow.usable.resize(n, false);
        }
        let usable = &mut b.shadow.usable[..n];
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

    /// [`Shader`]'s `light_columns` with each light's intensity scaled by its
    /// transmittance, and the phase sum of every sample (the scalar form's
    /// `Shader::phase_sum` and `Shader::light_sums`, in the same order).
    #[inline(always)]
    fn light_columns_shadowed(&self, b: &mut ShadeBatch) {
        let n = b.len;
        let lights = self.world_lights();
        let count = lights.len();
        let [nx, ny, nz] = &mut b.normal;
        let (nx, ny, nz) = (&mut nx[..n], &mut ny[..n], &mut nz[..n]);
        let [vx, vy, vz] = &b.view;
        let (vx, vy, vz) = (&vx[..n], &vy[..n], &vz[..n]);
        let n_dot_v = first(&mut b.shadow.n_dot_v, n, 0.0);
        for k in 0..n {
            let d = nx[k] * vx[k] + ny[k] * vy[k] + nz[k] * vz[k];
            let flip = d < 0.0;
            nx[k] = if flip { -nx[k] } else { nx[k] };
            ny[k] = if flip { -ny[k] } else { ny[k] };
            nz[k] = if flip { -nz[k] } else { nz[k] };
            n_dot_v[k] = if flip { -d } else { d };
        }
        let transmittance = &b.shadow.transmittance[..n * count];
        let n_dot_l = first(&mut b.shadow.n_dot_l, n * count, 0.0);
        let cos = first(&mut b.shadow.cos, n * count, 0.0);
        let phase = first(&mut b.shadow.phase, n, 0.0);
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
        let lobe = first(&mut b.shadow.lobe, n * count, 0.0);
        self.specular().eval_slice(cos, lobe);
        let diffuse = first(&mut b.shadow.diffuse, n, 0.0);
        let specular = first(&mut b.shadow.specular, n, 0.0);
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

#[cfg(test)]
mod tests {

    use super::*;
    use crate::lighting::fixtures::{check, fill, shaders, spread};

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
                let (t, occ) = (
                    input.shadow.transmittance.clone(),
                    input.shadow.occlusion.clone(),
                );
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
                if std::is_x86_feature_detected!("avx2") {
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
}
