//! The batch form of the lighting model on AVX2: eight samples per step, in two passes
//! over the batch with one call of the lobe's SIMD kernel between them.
//!
//! Pass one, per eight samples: the unit normals (from the gradients, with their
//! magnitudes and which pass the gate; or as given), turned towards the viewer; per
//! light `N·L`, whether the light faces the sample, the diffuse sum, and the lobe's
//! cosine (Phong `2(N·L)(N·V) - L·V`, Blinn `N·H`). Then the lobe at every cosine of
//! every light. Pass two, per eight samples: the specular sum and the colour.
//!
//! Every operation is the scalar form's ([`Shader::shade`], [`Shader::shade_normal`])
//! in the same order, without FMA contraction, so the results are the scalar form's bit
//! for bit (tested in batch.rs). Written with `std::arch` intrinsics: stable Rust has
//! no portable SIMD, and the compiler did not vectorise the per-lane loops of a
//! portable version of these passes (its lighting took 1.6x these instructions on the
//! MNI152 scene, callgrind). No `array::map` with intrinsics: its generic body lacks
//! this module's target features, so they could not be inlined.

use std::arch::x86_64::*;

use glint_lobe::Geometry;

use super::batch::{first, ShadeBatch, LANES};
use super::{flat, Shader};

/// Whether the CPU can run [`shade`] (cached by the standard library).
pub(super) fn supported() -> bool {
    is_x86_feature_detected!("avx2")
}

/// `a·b` for vectors given by components, summed left to right like `Vec3::dot`.
///
/// # Safety
/// The CPU must support AVX2 (the callers of this module are compiled with it).
#[inline(always)]
unsafe fn dot(a: [__m256; 3], b: [__m256; 3]) -> __m256 {
    // SAFETY: AVX2 (this function's contract).
    unsafe {
        _mm256_add_ps(
            _mm256_add_ps(_mm256_mul_ps(a[0], b[0]), _mm256_mul_ps(a[1], b[1])),
            _mm256_mul_ps(a[2], b[2]),
        )
    }
}

/// The three columns' eight values at `k`.
///
/// # Safety
/// AVX2; each column holds at least `k + 8` values.
#[inline(always)]
unsafe fn load3(cols: &[Vec<f32>; 3], k: usize) -> [__m256; 3] {
    // SAFETY: the caller's contract covers the eight reads from each column.
    unsafe {
        [
            _mm256_loadu_ps(cols[0].as_ptr().add(k)),
            _mm256_loadu_ps(cols[1].as_ptr().add(k)),
            _mm256_loadu_ps(cols[2].as_ptr().add(k)),
        ]
    }
}

/// Lane `l`'s bit of an eight-bit mask `m`, as a vector mask (all ones or zero).
///
/// # Safety
/// The CPU must support AVX2.
#[inline(always)]
unsafe fn lane_mask(m: u8) -> __m256 {
    // SAFETY: AVX2 (this function's contract).
    unsafe {
        let lane_bits = _mm256_setr_epi32(1, 2, 4, 8, 16, 32, 64, 128);
        let v = _mm256_and_si256(_mm256_set1_epi32(i32::from(m)), lane_bits);
        _mm256_castsi256_ps(_mm256_cmpeq_epi32(v, lane_bits))
    }
}

/// Lights `b` (volume samples with gradients in `normal` when `gradients`, else
/// surface samples with unit normals) as the scalar form does, eight at a time.
///
/// # Safety
/// The CPU must support AVX2 ([`supported`]).
#[target_feature(enable = "avx2")]
pub(super) unsafe fn shade(shader: &Shader, b: &mut ShadeBatch, gradients: bool) {
    let padded = b.padded();
    let chunks = padded / LANES;
    let lights = shader.world_lights().len();
    let s = &mut b.scratch;
    first(&mut s.magnitude, padded, 0.0);
    first(&mut s.diffuse, padded, 0.0);
    first(&mut s.valid, chunks, 0);
    first(&mut s.cos, padded * lights, 0.0);
    first(&mut s.facing, chunks * lights, 0);
    for c in 0..chunks {
        // SAFETY: AVX2 (this function's contract); `set_len` made every column and
        // the scratch above hold whole chunks, so chunk `c` is inside each.
        unsafe { cosines(shader, b, c, gradients) };
    }
    let s = &mut b.scratch;
    let lobe = first(&mut s.lobe, padded * lights, 0.0);
    shader
        .specular()
        .eval_slice(&s.cos[..padded * lights], lobe);
    for c in 0..chunks {
        // SAFETY: as above.
        unsafe { colours(shader, b, c, gradients) };
    }
}

/// Pass one for chunk `c`: the normals turned towards the viewer and, per light, the
/// facing lanes, the diffuse sum and the lobe's cosine.
///
/// # Safety
/// AVX2; the batch's columns and scratch hold chunk `c`.
#[inline(always)]
unsafe fn cosines(shader: &Shader, b: &mut ShadeBatch, c: usize, gradients: bool) {
    // SAFETY: this function's contract covers every load and store below (chunk `c`
    // of columns and scratch sized for whole chunks) and the CPU features.
    unsafe {
        let k = c * LANES;
        let padded = b.padded();
        let zero = _mm256_setzero_ps();
        let g = load3(&b.normal, k);
        let view = load3(&b.view, k);
        let s = &mut b.scratch;
        let mut nrm = g;
        if gradients {
            let g0 = shader.gate;
            let gm2 = dot(g, g);
            let ok = _mm256_and_ps(
                _mm256_cmp_ps::<_CMP_GT_OQ>(gm2, _mm256_set1_ps(g0 * g0)),
                _mm256_cmp_ps::<_CMP_LT_OQ>(gm2, _mm256_set1_ps(f32::INFINITY)),
            );
            s.valid[c] = _mm256_movemask_ps(ok) as u8;
            let gm = _mm256_sqrt_ps(gm2);
            _mm256_storeu_ps(s.magnitude.as_mut_ptr().add(k), gm);
            // The normal points from high to low values, out of dense structures.
            let inv = _mm256_div_ps(_mm256_set1_ps(-1.0), gm);
            nrm = [
                _mm256_mul_ps(g[0], inv),
                _mm256_mul_ps(g[1], inv),
                _mm256_mul_ps(g[2], inv),
            ];
        }
        // Two-sided: flipped to face the viewer.
        let mut n_dot_v = dot(nrm, view);
        let flip = _mm256_and_ps(
            _mm256_cmp_ps::<_CMP_LT_OQ>(n_dot_v, zero),
            _mm256_set1_ps(-0.0),
        );
        nrm = [
            _mm256_xor_ps(nrm[0], flip),
            _mm256_xor_ps(nrm[1], flip),
            _mm256_xor_ps(nrm[2], flip),
        ];
        n_dot_v = _mm256_xor_ps(n_dot_v, flip);
        let mut dif = zero;
        for (i, &(l, intensity)) in shader.world_lights().iter().enumerate() {
            let lv = [
                _mm256_set1_ps(l.x),
                _mm256_set1_ps(l.y),
                _mm256_set1_ps(l.z),
            ];
            let n_dot_l = dot(nrm, lv);
            let faces = _mm256_cmp_ps::<_CMP_GT_OQ>(n_dot_l, zero);
            dif = _mm256_blendv_ps(
                dif,
                _mm256_add_ps(dif, _mm256_mul_ps(_mm256_set1_ps(intensity), n_dot_l)),
                faces,
            );
            let cv = match shader.geometry() {
                Geometry::Phong => _mm256_sub_ps(
                    _mm256_mul_ps(_mm256_mul_ps(_mm256_set1_ps(2.0), n_dot_l), n_dot_v),
                    dot(lv, view),
                ),
                Geometry::Blinn => {
                    // H = normalize_or_zero(L + V): zero unless the length is finite
                    // and positive.
                    let sum = [
                        _mm256_add_ps(lv[0], view[0]),
                        _mm256_add_ps(lv[1], view[1]),
                        _mm256_add_ps(lv[2], view[2]),
                    ];
                    let len = _mm256_sqrt_ps(dot(sum, sum));
                    let usable = _mm256_and_ps(
                        _mm256_cmp_ps::<_CMP_GT_OQ>(len, zero),
                        _mm256_cmp_ps::<_CMP_LT_OQ>(len, _mm256_set1_ps(f32::INFINITY)),
                    );
                    let inv_len = _mm256_div_ps(_mm256_set1_ps(1.0), len);
                    let h = [
                        _mm256_and_ps(_mm256_mul_ps(sum[0], inv_len), usable),
                        _mm256_and_ps(_mm256_mul_ps(sum[1], inv_len), usable),
                        _mm256_and_ps(_mm256_mul_ps(sum[2], inv_len), usable),
                    ];
                    dot(nrm, h)
                }
            };
            _mm256_storeu_ps(s.cos.as_mut_ptr().add(i * padded + k), cv);
            s.facing[i * (padded / LANES) + c] = _mm256_movemask_ps(faces) as u8;
        }
        _mm256_storeu_ps(s.diffuse.as_mut_ptr().add(k), dif);
    }
}

/// Pass two for chunk `c`: the specular sum over the facing lights, and the colour
/// (a volume sample's blended with the flat one by the gate's weight, flat where the
/// gradient is not usable).
///
/// # Safety
/// AVX2; the batch's columns and scratch hold chunk `c`; pass one has run.
#[inline(always)]
unsafe fn colours(shader: &Shader, b: &mut ShadeBatch, c: usize, gradients: bool) {
    // SAFETY: this function's contract covers every load and store below and the CPU
    // features.
    unsafe {
        let k = c * LANES;
        let padded = b.padded();
        let m = shader.material();
        let s = &b.scratch;
        let mut specular = _mm256_setzero_ps();
        for (i, &(_, intensity)) in shader.world_lights().iter().enumerate() {
            let v = _mm256_loadu_ps(s.lobe.as_ptr().add(i * padded + k));
            specular = _mm256_blendv_ps(
                specular,
                _mm256_add_ps(specular, _mm256_mul_ps(_mm256_set1_ps(intensity), v)),
                lane_mask(s.facing[i * (padded / LANES) + c]),
            );
        }
        let lit = _mm256_add_ps(
            _mm256_set1_ps(m.ambient),
            _mm256_mul_ps(
                _mm256_set1_ps(m.diffuse),
                _mm256_loadu_ps(s.diffuse.as_ptr().add(k)),
            ),
        );
        let spec = _mm256_mul_ps(_mm256_set1_ps(m.specular), specular);
        let (weight, usable) = if gradients {
            let g0 = shader.gate;
            let one = _mm256_set1_ps(1.0);
            let w = if g0 > 0.0 {
                let gm = _mm256_loadu_ps(s.magnitude.as_ptr().add(k));
                let g0v = _mm256_set1_ps(g0);
                _mm256_min_ps(_mm256_div_ps(_mm256_sub_ps(gm, g0v), g0v), one)
            } else {
                one
            };
            (w, lane_mask(s.valid[c]))
        } else {
            (_mm256_setzero_ps(), _mm256_setzero_ps())
        };
        let flat_v = _mm256_set1_ps(flat(m));
        for col in &mut b.color {
            let p = col.as_mut_ptr().add(k);
            let base = _mm256_loadu_ps(p);
            let shaded = _mm256_add_ps(_mm256_mul_ps(base, lit), spec);
            let out = if gradients {
                let unshaded = _mm256_mul_ps(base, flat_v);
                let mixed = _mm256_add_ps(
                    unshaded,
                    _mm256_mul_ps(weight, _mm256_sub_ps(shaded, unshaded)),
                );
                _mm256_blendv_ps(unshaded, mixed, usable)
            } else {
                shaded
            };
            _mm256_storeu_ps(p, out);
        }
    }
}
