//! The composite loop on AVX2 + FMA: eight consecutive samples of a ray at a time.
//!
//! Per chunk of eight samples: positions, cell indices, trilinear values and transfer
//! function indices in vector registers; when any of the eight is visible, gradients,
//! normals, the lighting cosines and the lobe (through
//! [`glint_lobe::Lobe::eval_slice`], glint-lobe's SIMD kernels) for the chunk; then
//! the visible samples are composited front to back in order, with early termination
//! at the same sample as the reference loop (`Caster::composite`).
//!
//! No gather instructions: on CPUs with Intel's Gather Data Sampling mitigation (the
//! 2023 microcode for Skylake to Ice Lake, this project's CI machines among them) an
//! eight-lane `vgatherdps` costs about 25 cycles, more than eight scalar loads. Corner
//! pairs along i are adjacent in memory, so each sample's eight values come from four
//! 64-bit loads, and its eight `[value, gradient]` records from four 256-bit loads.
//!
//! Every operation is the reference loop's, in the same order and without FMA
//! contraction, so positions, values, classification and shading are bit-identical to
//! it; only the `exact` and `gauss` lobes differ, by the 2 ulp of glint-lobe's
//! vectorised pow/exp (tested in `tests/render.rs`). Written with `std::arch`
//! intrinsics: stable Rust has no portable SIMD, and the loads need explicit control.

use std::arch::x86_64::*;

use super::{Caster, Ray, RenderStats, TERMINATION_OPACITY};
use crate::field::MACRO_CELL;
use crate::shading::{RayLighting, MAX_LIGHTS};
use glint_lobe::Geometry;

/// Samples per chunk (f32 lanes of an AVX2 register).
const LANES: usize = 8;

/// Whether this CPU can run [`composite`].
pub(super) fn supported() -> bool {
    is_x86_feature_detected!("avx2") && is_x86_feature_detected!("fma")
}

/// Per-lane lighting terms of a chunk, as `Shader::shade` combines them.
struct Lighting8 {
    lit: [f32; LANES],
    spec: [f32; LANES],
    w: [f32; LANES],
    /// Bit j set: lane j has a usable gradient (above the gate, finite).
    valid: u32,
}

/// `a + t (b - a)`, rounded as the scalar code rounds it (no FMA).
#[inline(always)]
unsafe fn lerp(a: __m256, b: __m256, t: __m256) -> __m256 {
    _mm256_add_ps(a, _mm256_mul_ps(t, _mm256_sub_ps(b, a)))
}

/// [`lerp`] on four lanes.
#[inline(always)]
unsafe fn lerp4(a: __m128, b: __m128, t: __m128) -> __m128 {
    _mm_add_ps(a, _mm_mul_ps(t, _mm_sub_ps(b, a)))
}

/// The two f32 at `p` as one 64-bit integer.
#[inline(always)]
unsafe fn pair(p: *const f32) -> i64 {
    p.cast::<i64>().read_unaligned()
}

/// Corners `(i, i+1)` of one row for eight lanes whose row starts are `p[l]`: the
/// first corners in lane order, then the second.
#[inline(always)]
unsafe fn row(p: [*const f32; LANES]) -> (__m256, __m256) {
    // Lanes 0,1,4,5 and 2,3,6,7: the in-lane shuffles below then give lane order.
    let a = _mm256_castsi256_ps(_mm256_set_epi64x(
        pair(p[5]),
        pair(p[4]),
        pair(p[1]),
        pair(p[0]),
    ));
    let b = _mm256_castsi256_ps(_mm256_set_epi64x(
        pair(p[7]),
        pair(p[6]),
        pair(p[3]),
        pair(p[2]),
    ));
    (
        _mm256_shuffle_ps::<0b10_00_10_00>(a, b),
        _mm256_shuffle_ps::<0b11_01_11_01>(a, b),
    )
}

/// `a·b` for vectors given by components, summed left to right like `Vec3::dot`.
#[inline(always)]
unsafe fn dot(a: [__m256; 3], b: [__m256; 3]) -> __m256 {
    _mm256_add_ps(
        _mm256_add_ps(_mm256_mul_ps(a[0], b[0]), _mm256_mul_ps(a[1], b[1])),
        _mm256_mul_ps(a[2], b[2]),
    )
}

/// A chunk's samples located in the grid.
struct Chunk {
    /// Linear index of each sample's corner-000 voxel.
    base: [i32; LANES],
    /// Fractions inside the trilinear cell, per axis.
    t: [__m256; 3],
}

/// Front-to-back compositing of `ray`: the same result as `Caster::composite`.
///
/// # Safety
/// The CPU must support AVX2 and FMA ([`supported`]).
#[target_feature(enable = "avx2,fma")]
pub(super) unsafe fn composite(
    c: &Caster,
    ray: &Ray,
    lighting: &RayLighting,
    stats: &mut RenderStats,
) -> ([f32; 3], f32) {
    let f = c.field;
    let [nx, ny, nz] = f.dims;
    let sxy = nx * ny;
    let cd = f.cell_dims;
    let lanes = _mm256_setr_ps(0.0, 1.0, 2.0, 3.0, 4.0, 5.0, 6.0, 7.0);
    let dt = _mm256_set1_ps(c.dt);
    let o = [ray.o.x, ray.o.y, ray.o.z].map(|x| _mm256_set1_ps(x));
    let d = [ray.d.x, ray.d.y, ray.d.z].map(|x| _mm256_set1_ps(x));
    let hi = [nx, ny, nz].map(|n| _mm256_set1_ps((n - 2) as f32));
    let (zero, one) = (_mm256_setzero_ps(), _mm256_set1_ps(1.0));
    // Every index fits in i32: MAX_FIELD_VOXELS is 2^28.
    let (nxv, sxyv) = (_mm256_set1_epi32(nx as i32), _mm256_set1_epi32(sxy as i32));
    let lut = c.lut;
    let (lut_lo, lut_scale) = (_mm256_set1_ps(lut.lo), _mm256_set1_ps(lut.scale));
    let (half, lut_max) = (
        _mm256_set1_ps(0.5),
        _mm256_set1_ps((crate::tf::LUT_SIZE - 1) as f32),
    );
    let values = f.values.as_ptr();
    let m = &c.shader.material;
    let flat = m.ambient + m.diffuse;

    let mut color = [0.0f32; 3];
    let mut alpha = 0.0f32;
    let mut k = ray.k0;
    let mut cached_cell = usize::MAX;
    let mut dist = 0;
    while k <= ray.k1 {
        // Positions o + d t with t = k dt, as `Ray::at` computes them.
        let t = _mm256_mul_ps(_mm256_add_ps(_mm256_set1_ps(k as f32), lanes), dt);
        let p = [0, 1, 2].map(|a| _mm256_add_ps(o[a], _mm256_mul_ps(d[a], t)));
        // `Field::locate`: clamp to the cells, truncate, fractions clamped to [0, 1]
        // (max/min put 0 for NaN, as f32::max/min do).
        let ijk =
            [0, 1, 2].map(|a| _mm256_cvttps_epi32(_mm256_min_ps(_mm256_max_ps(p[a], zero), hi[a])));
        // Empty-space skipping is decided by the chunk's first sample; the others
        // need no test, since a sample in an inactive cell has zero opacity anyway.
        let c0 = ijk.map(|v| _mm256_cvtsi256_si32(v) as usize / MACRO_CELL);
        let cell = c0[0] + cd[0] * (c0[1] + cd[1] * c0[2]);
        if cell != cached_cell {
            cached_cell = cell;
            dist = c.distance[cell];
        }
        if dist != 0 {
            stats.skips += 1;
            k = c.leap(ray, c0, dist, k);
            continue;
        }
        let n = (ray.k1 - k + 1).min(LANES as i64) as usize;
        stats.samples += n as u64;
        let fr = [0, 1, 2].map(|a| {
            let t = _mm256_sub_ps(p[a], _mm256_cvtepi32_ps(ijk[a]));
            _mm256_min_ps(_mm256_max_ps(t, zero), one)
        });
        let mut chunk = Chunk {
            base: [0; LANES],
            t: fr,
        };
        _mm256_storeu_si256(
            chunk.base.as_mut_ptr().cast(),
            _mm256_add_epi32(
                ijk[0],
                _mm256_add_epi32(
                    _mm256_mullo_epi32(ijk[1], nxv),
                    _mm256_mullo_epi32(ijk[2], sxyv),
                ),
            ),
        );
        // Trilinear values. SAFETY: the indices are clamped to [0, dims-2] above, so
        // base + sxy + nx + 1 < nx ny nz.
        let at = |off: usize| chunk.base.map(|b| values.add(b as usize + off));
        let (c000, c100) = row(at(0));
        let (c010, c110) = row(at(nx));
        let (c001, c101) = row(at(sxy));
        let (c011, c111) = row(at(sxy + nx));
        let x00 = lerp(c000, c100, fr[0]);
        let x10 = lerp(c010, c110, fr[0]);
        let x01 = lerp(c001, c101, fr[0]);
        let x11 = lerp(c011, c111, fr[0]);
        let y0 = lerp(x00, x10, fr[1]);
        let y1 = lerp(x01, x11, fr[1]);
        let v = lerp(y0, y1, fr[2]);
        // `Lut::index`, then the opacities.
        let x = _mm256_add_ps(_mm256_mul_ps(_mm256_sub_ps(v, lut_lo), lut_scale), half);
        let mut li = [0i32; LANES];
        _mm256_storeu_si256(
            li.as_mut_ptr().cast(),
            _mm256_cvttps_epi32(_mm256_min_ps(_mm256_max_ps(x, zero), lut_max)),
        );
        let mut mask = 0u32;
        for (j, &i) in li.iter().enumerate().take(n) {
            mask |= ((lut.alpha_at(i as usize) > 0.0) as u32) << j;
        }
        if mask != 0 {
            // Opacity first: it needs no shading, and it tells which of the visible
            // samples the ray composites before it terminates (the others are never
            // lit). The same operations in the same order as the reference loop.
            let mut weight = [0.0f32; LANES];
            let mut used = 0u32;
            let mut a = alpha;
            while mask != 0 {
                let j = mask.trailing_zeros() as usize;
                mask &= mask - 1;
                let w = (1.0 - a) * lut.alpha_at(li[j] as usize);
                weight[j] = w;
                used |= 1 << j;
                a += w;
                if a >= TERMINATION_OPACITY {
                    break;
                }
            }
            let shade = if m.shade {
                Some(light8(c, &chunk, used, lighting))
            } else {
                None
            };
            stats.shaded += u64::from(used.count_ones());
            while used != 0 {
                let j = used.trailing_zeros() as usize;
                used &= used - 1;
                let e = lut.entry_at(li[j] as usize);
                let rgb = match &shade {
                    None => [e[0], e[1], e[2]],
                    Some(s) if s.valid & (1 << j) == 0 => [e[0] * flat, e[1] * flat, e[2] * flat],
                    Some(s) => {
                        let mut out = [0.0f32; 3];
                        for ch in 0..3 {
                            let shaded = e[ch] * s.lit[j] + s.spec[j];
                            let unshaded = e[ch] * flat;
                            out[ch] = unshaded + s.w[j] * (shaded - unshaded);
                        }
                        out
                    }
                };
                let w = weight[j];
                color[0] += w * rgb[0];
                color[1] += w * rgb[1];
                color[2] += w * rgb[2];
            }
            alpha = a;
            if alpha >= TERMINATION_OPACITY {
                return (color, alpha);
            }
        }
        k += n as i64;
    }
    (color, alpha)
}

/// Trilinear world gradients of the lanes in `mask` (zero in the others), as
/// `Field::gradient_at` computes them, in component order.
///
/// # Safety
/// AVX2 must be available; `chunk` must come from clamped positions.
#[inline(always)]
unsafe fn gradients(c: &Caster, chunk: &Chunk, mut mask: u32) -> [__m256; 3] {
    let f = c.field;
    let [nx, ny, _] = f.dims;
    let sxy = nx * ny;
    let data = f.data.as_ptr().cast::<f32>();
    let mut t = [[0.0f32; LANES]; 3];
    for (a, v) in chunk.t.iter().enumerate() {
        _mm256_storeu_ps(t[a].as_mut_ptr(), *v);
    }
    let mut g = [_mm_setzero_ps(); LANES];
    while mask != 0 {
        let j = mask.trailing_zeros() as usize;
        mask &= mask - 1;
        // One 256-bit load holds voxels (i, i+1) of a row: [value, gx, gy, gz] twice.
        // SAFETY: as for the values, with four f32 per voxel.
        let p = data.add(4 * chunk.base[j] as usize);
        let x = |off: usize| {
            let r = _mm256_loadu_ps(p.add(4 * off));
            lerp4(
                _mm256_castps256_ps128(r),
                _mm256_extractf128_ps::<1>(r),
                _mm_set1_ps(t[0][j]),
            )
        };
        let (x00, x10, x01, x11) = (x(0), x(nx), x(sxy), x(sxy + nx));
        let ty = _mm_set1_ps(t[1][j]);
        let y0 = lerp4(x00, x10, ty);
        let y1 = lerp4(x01, x11, ty);
        g[j] = lerp4(y0, y1, _mm_set1_ps(t[2][j]));
    }
    // Transpose the eight [value, gx, gy, gz] records into gx, gy, gz vectors.
    let r = |a: usize, b: usize| _mm256_insertf128_ps::<1>(_mm256_castps128_ps256(g[a]), g[b]);
    let (r0, r1, r2, r3) = (r(0, 4), r(1, 5), r(2, 6), r(3, 7));
    let t0 = _mm256_unpacklo_ps(r0, r1); // v0 v1 gx0 gx1 | v4 v5 gx4 gx5
    let t1 = _mm256_unpackhi_ps(r0, r1); // gy0 gy1 gz0 gz1 | ...
    let t2 = _mm256_unpacklo_ps(r2, r3);
    let t3 = _mm256_unpackhi_ps(r2, r3);
    [
        _mm256_shuffle_ps::<0b11_10_11_10>(t0, t2),
        _mm256_shuffle_ps::<0b01_00_01_00>(t1, t3),
        _mm256_shuffle_ps::<0b11_10_11_10>(t1, t3),
    ]
}

/// Gradients and lighting of a chunk: `Shader::shade`'s terms for the lanes in `mask`.
///
/// # Safety
/// AVX2 and FMA must be available; `chunk` must come from clamped positions.
#[target_feature(enable = "avx2,fma")]
unsafe fn light8(c: &Caster, chunk: &Chunk, mask: u32, ray: &RayLighting) -> Lighting8 {
    let shader = c.shader;
    let m = &shader.material;
    let grad = gradients(c, chunk, mask);
    let zero = _mm256_setzero_ps();
    let gm2 = dot(grad, grad);
    let g0 = shader.gate;
    let valid = _mm256_and_ps(
        _mm256_cmp_ps::<_CMP_GT_OQ>(gm2, _mm256_set1_ps(g0 * g0)),
        _mm256_cmp_ps::<_CMP_LT_OQ>(gm2, _mm256_set1_ps(f32::INFINITY)),
    );
    let gm = _mm256_sqrt_ps(gm2);
    let inv = _mm256_div_ps(_mm256_set1_ps(-1.0), gm);
    let mut n = grad.map(|g| _mm256_mul_ps(g, inv));
    let view = [ray.view.x, ray.view.y, ray.view.z].map(|x| _mm256_set1_ps(x));
    let mut n_dot_v = dot(n, view);
    // Two-sided lighting: flip normals that face away from the viewer.
    let sign = _mm256_set1_ps(-0.0);
    let back = _mm256_cmp_ps::<_CMP_LT_OQ>(n_dot_v, zero);
    let flip = _mm256_and_ps(back, sign);
    n = n.map(|x| _mm256_xor_ps(x, flip));
    n_dot_v = _mm256_xor_ps(n_dot_v, flip);

    let count = ray.count;
    let mut cos = [0.0f32; LANES * MAX_LIGHTS];
    let mut lit_mask = [zero; MAX_LIGHTS];
    let mut diffuse = zero;
    for (i, &(l, intensity, l_dot_v, h)) in ray.lights[..count].iter().enumerate() {
        let lv = [l.x, l.y, l.z].map(|x| _mm256_set1_ps(x));
        let n_dot_l = dot(n, lv);
        let facing = _mm256_cmp_ps::<_CMP_GT_OQ>(n_dot_l, zero);
        let iv = _mm256_set1_ps(intensity);
        diffuse = _mm256_blendv_ps(
            diffuse,
            _mm256_add_ps(diffuse, _mm256_mul_ps(iv, n_dot_l)),
            facing,
        );
        let cv = match shader.geometry {
            Geometry::Phong => _mm256_sub_ps(
                _mm256_mul_ps(_mm256_mul_ps(_mm256_set1_ps(2.0), n_dot_l), n_dot_v),
                _mm256_set1_ps(l_dot_v),
            ),
            Geometry::Blinn => dot(n, [h.x, h.y, h.z].map(|x| _mm256_set1_ps(x))),
        };
        _mm256_storeu_ps(cos.as_mut_ptr().add(i * LANES), cv);
        lit_mask[i] = facing;
    }
    let mut lobe = [0.0f32; LANES * MAX_LIGHTS];
    shader
        .lobe
        .eval_slice(&cos[..count * LANES], &mut lobe[..count * LANES]);
    let mut specular = zero;
    for (i, &(_, intensity, _, _)) in ray.lights[..count].iter().enumerate() {
        let s = _mm256_loadu_ps(lobe.as_ptr().add(i * LANES));
        specular = _mm256_blendv_ps(
            specular,
            _mm256_add_ps(specular, _mm256_mul_ps(_mm256_set1_ps(intensity), s)),
            lit_mask[i],
        );
    }
    let lit = _mm256_add_ps(
        _mm256_set1_ps(m.ambient),
        _mm256_mul_ps(_mm256_set1_ps(m.diffuse), diffuse),
    );
    let spec = _mm256_mul_ps(_mm256_set1_ps(m.specular), specular);
    let w = if g0 > 0.0 {
        let g0v = _mm256_set1_ps(g0);
        _mm256_min_ps(
            _mm256_div_ps(_mm256_sub_ps(gm, g0v), g0v),
            _mm256_set1_ps(1.0),
        )
    } else {
        _mm256_set1_ps(1.0)
    };
    let mut out = Lighting8 {
        lit: [0.0; LANES],
        spec: [0.0; LANES],
        w: [0.0; LANES],
        valid: _mm256_movemask_ps(valid) as u32,
    };
    _mm256_storeu_ps(out.lit.as_mut_ptr(), lit);
    _mm256_storeu_ps(out.spec.as_mut_ptr(), spec);
    _mm256_storeu_ps(out.w.as_mut_ptr(), w);
    out
}
