//! The lighting model's batch form: many samples lit at once, as columns (structure of
//! arrays). On x86-64 with AVX2 ([`avx2`](super::avx2)) eight samples go through
//! each step at once and the lobe is evaluated by one call of its SIMD kernel
//! ([`glint_lobe::Specular::eval_slice`]) for every sample and light; every step is
//! the scalar form's operation in the same order (no FMA contraction), so a batch gives
//! [`Shader::shade`](super::Shader::shade) and [`Shader::shade_normal`](super::Shader::shade_normal) bit for bit (tested below). Elsewhere
//! the batch is lit one sample at a time by the scalar form itself.

use crate::math::Vec3;

/// Lanes of a chunk: the AVX2 kernel takes this many samples at a time.
pub(super) const LANES: usize = 8;

/// Samples to light together, as columns. Fill the first [`ShadeBatch::len`] entries
/// of `normal`, `view` and `color`, then call [`Shader::shade_gradients`](super::Shader::shade_gradients) (volume
/// samples: `normal` holds world gradients) or [`Shader::shade_normals`](super::Shader::shade_normals) (surface
/// samples: unit normals); `color` then holds the lit colours. The buffers are kept
/// between batches, so lighting allocates nothing once they have grown; the columns
/// hold whole chunks of eight samples (entries past the length are computed and
/// ignored).
#[derive(Clone, Debug, Default)]
pub struct ShadeBatch {
    pub(super) len: usize,
    /// Per sample: the gradient or the unit normal (x, y, z columns).
    pub normal: [Vec<f32>; 3],
    /// Per sample: the unit vector towards the eye.
    pub view: [Vec<f32>; 3],
    /// Per sample: the unlit linear colour, replaced by the lit one.
    pub color: [Vec<f32>; 3],
    /// The AVX2 kernel's intermediate values.
    pub(super) scratch: Scratch,
    /// The shadowed form's columns ([`Shader::shade_gradients_shadowed`]).
    pub(super) shadow: super::scratch::ShadowScratch,
}

/// Intermediate values of the AVX2 kernel, kept between batches.
#[derive(Clone, Debug, Default)]
pub(super) struct Scratch {
    /// Per sample: the gradient magnitude and the diffuse sum.
    pub(super) magnitude: Vec<f32>,
    pub(super) diffuse: Vec<f32>,
    /// Per chunk: the lanes with a usable gradient.
    pub(super) valid: Vec<u8>,
    /// Per light and sample (light-major): the lobe's cosine, then its value.
    pub(super) cos: Vec<f32>,
    pub(super) lobe: Vec<f32>,
    /// Per light and chunk: the lanes the light faces.
    pub(super) facing: Vec<u8>,
}

/// The first `n` elements of `v`, grown with `x` if it is shorter (every element below
/// `n` is written before it is read, so stale values need no clearing).
pub(super) fn first<T: Copy>(v: &mut Vec<T>, n: usize, x: T) -> &mut [T] {
    if v.len() < n {
        v.resize(n, x);
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

    /// Sets the number of samples to `n`, growing the columns to at least `n` entries,
    /// rounded up to whole chunks (the entries keep whatever they held: the caller
    /// writes the inputs).
    pub fn set_len(&mut self, n: usize) {
        let padded = n.next_multiple_of(LANES);
        for col in self
            .normal
            .iter_mut()
            .chain(&mut self.view)
            .chain(&mut self.color)
        {
            first(col, padded, 0.0);
        }
        self.len = n;
    }

    /// The samples rounded up to whole chunks.
    pub(super) fn padded(&self) -> usize {
        self.len.next_multiple_of(LANES)
    }

    /// Sample `k`'s normal (or gradient), view and colour.
    pub(super) fn sample(&self, k: usize) -> (Vec3, Vec3, [f32; 3]) {
        let v3 = |c: &[Vec<f32>; 3]| Vec3::new(c[0][k], c[1][k], c[2][k]);
        let color = [self.color[0][k], self.color[1][k], self.color[2][k]];
        (v3(&self.normal), v3(&self.view), color)
    }

    pub(super) fn set_color(&mut self, k: usize, rgb: [f32; 3]) {
        for (col, x) in self.color.iter_mut().zip(rgb) {
            col[k] = x;
        }
    }
}

#[cfg(test)]
mod tests {
    use glint_lobe::LobeKind;

    use super::*;
    use crate::lighting::fixtures::{check, fill, shaders};

    use crate::lighting::Light;
    use crate::lighting::Material;
    use crate::lighting::Shader;
    use glint_lobe::Geometry;

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
                shader.shade_scalar(&mut b, true);
                check(&b, want, n, "portable");
                #[cfg(target_arch = "x86_64")]
                if super::super::avx2::supported() {
                    let mut b = input.clone();
                    // SAFETY: AVX2 is supported (checked above).
                    unsafe { super::super::avx2::shade(&shader, &mut b, true) };
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
            shader.shade_scalar(&mut b, false);
            check(&b, want, n, "portable");
            #[cfg(target_arch = "x86_64")]
            if super::super::avx2::supported() {
                let mut b = input.clone();
                // SAFETY: AVX2 is supported (checked above).
                unsafe { super::super::avx2::shade(&shader, &mut b, false) };
                check(&b, want, n, "avx2");
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
