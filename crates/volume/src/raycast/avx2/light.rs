//! The kept samples' gradients, lit in glint-core's batch form and composited.

use std::arch::x86_64::*;

use glint_core::MAX_LIGHTS;

use super::*;
use crate::clip::IndexClip;
use crate::field::brick::{BRICK, BRICK_ROW, BRICK_SLICE, BRICK_VOXELS};
use crate::field::Loc;
use crate::light::ShadowField;

/// Trilinear world gradients of the kept samples `r0 .. r0 + 8`, as
/// `Field::gradient_at` computes them, in component order.
///
/// # Safety
/// AVX2 must be available; the samples must come from clamped positions.
#[target_feature(enable = "avx2,fma")]
pub(super) unsafe fn gradients(c: &Caster, kept: &Kept, r0: usize) -> [__m256; 3] {
    // SAFETY: this function's `# Safety` contract, which its callers uphold,
    // covers every unsafe operation below (CPU features, pointer ranges).
    unsafe {
        let f = c.field;
        let (nx, sxy) = (BRICK_ROW, BRICK_SLICE);
        let data = f.cache.gradients();
        let mut g = [_mm_setzero_ps(); LANES];
        for (j, gj) in g.iter_mut().enumerate() {
            let r = r0 + j;
            // One 128-bit load holds voxels (i, i+1) of a row: [gx, gy, gz, 0] twice, as
            // i16, converted exactly to f32.
            // SAFETY: the base is a voxel of a brick slot whose cell lies in the slot (the
            // tile's guard keeps the slot), so base + sxy + nx + 1 is in the pool.
            let s = kept.0.get_unchecked(r);
            let p = data.add(s.base as usize);
            let v = |off: usize| {
                _mm256_cvtepi32_ps(_mm256_cvtepi16_epi32(_mm_loadu_si128(p.add(off).cast())))
            };
            let (v00, v10, v01, v11) = (v(0), v(nx), v(sxy), v(sxy + nx));
            // Two rows' lerps along i in one vector: [first corners of rows a | b] to
            // [second corners of rows a | b].
            let tx = _mm256_set1_ps(s.t[0]);
            let x0 = lerp(
                _mm256_permute2f128_ps::<0x20>(v00, v10),
                _mm256_permute2f128_ps::<0x31>(v00, v10),
                tx,
            );
            let x1 = lerp(
                _mm256_permute2f128_ps::<0x20>(v01, v11),
                _mm256_permute2f128_ps::<0x31>(v01, v11),
                tx,
            );
            // [x00 | x01] to [x10 | x11] along j, then the two halves along k.
            let y = lerp(
                _mm256_permute2f128_ps::<0x20>(x0, x1),
                _mm256_permute2f128_ps::<0x31>(x0, x1),
                _mm256_set1_ps(s.t[1]),
            );
            *gj = lerp4(
                _mm256_castps256_ps128(y),
                _mm256_extractf128_ps::<1>(y),
                _mm_set1_ps(s.t[2]),
            );
        }
        // Transpose the eight [gx, gy, gz, 0] records into gx, gy, gz vectors, scaled as
        // `Field::gradient_at` scales them.
        let r = |a: usize, b: usize| _mm256_insertf128_ps::<1>(_mm256_castps128_ps256(g[a]), g[b]);
        let (r0, r1, r2, r3) = (r(0, 4), r(1, 5), r(2, 6), r(3, 7));
        let t0 = _mm256_unpacklo_ps(r0, r1); // gx0 gx1 gy0 gy1 | gx4 gx5 gy4 gy5
        let t1 = _mm256_unpackhi_ps(r0, r1); // gz0 gz1 0 0 | ...
        let t2 = _mm256_unpacklo_ps(r2, r3);
        let t3 = _mm256_unpackhi_ps(r2, r3);
        let scale = _mm256_set1_ps(f.gradient_scale);
        [
            _mm256_mul_ps(_mm256_shuffle_ps::<0b01_00_01_00>(t0, t2), scale),
            _mm256_mul_ps(_mm256_shuffle_ps::<0b11_10_11_10>(t0, t2), scale),
            _mm256_mul_ps(_mm256_shuffle_ps::<0b01_00_01_00>(t1, t3), scale),
        ]
    }
}

/// The tricubic B-spline's world gradients of the kept samples `r0 .. r0 + 8`
/// (`Field::gradient_at`: the index-space derivatives from one read of each sample's
/// 64 taps, [`super::spline::gradients`], mapped by the inverse transpose of the
/// affine's 3x3 part), in component order. Samples whose taps reach past the volume
/// take the scalar evaluation.
///
/// # Safety
/// AVX2 and FMA must be available; `kept` holds at least `r0 + 8` samples from clamped
/// positions.
#[inline(always)]
unsafe fn cubic_gradients(c: &Caster, kept: &Kept, r0: usize, guard: &Guard) -> [__m256; 3] {
    let f = c.field;
    let mut cell = [[0i32; LANES]; 3];
    let mut t = [[0.0f32; LANES]; 3];
    for (j, s) in kept.0[r0..r0 + LANES].iter().enumerate() {
        let ijk = grid_cell(f.brick_dims, s);
        for a in 0..3 {
            // Cells fit in i32: the grid's dimensions do (Field::new checks).
            (cell[a][j], t[a][j]) = (ijk[a] as i32, s.t[a]);
        }
    }
    // SAFETY: AVX2 and FMA (this function's contract); each load reads a whole array
    // of eight; the cells are clamped ones (kept samples').
    unsafe {
        let ijk = axes!(|a| _mm256_loadu_si256(cell[a].as_ptr().cast()));
        let fr = axes!(|a| _mm256_loadu_ps(t[a].as_ptr()));
        let (g, edge) =
            super::spline::gradients(c, (ijk, fr), guard).unwrap_or(([[0.0; LANES]; 3], u8::MAX));
        let g = axes!(|a| _mm256_loadu_ps(g[a].as_ptr()));
        let m = &f.recipe.to_world_gradient;
        let world = axes!(|r| {
            let x = _mm256_mul_ps(_mm256_set1_ps(m[r][0]), g[0]);
            let y = _mm256_mul_ps(_mm256_set1_ps(m[r][1]), g[1]);
            let z = _mm256_mul_ps(_mm256_set1_ps(m[r][2]), g[2]);
            _mm256_add_ps(_mm256_add_ps(x, y), z)
        });
        if edge == 0 {
            return world;
        }
        let mut out = [[0.0f32; LANES]; 3];
        for a in 0..3 {
            _mm256_storeu_ps(out[a].as_mut_ptr(), world[a]);
        }
        for (j, s) in kept.0[r0..r0 + LANES].iter().enumerate() {
            if edge & (1 << j) != 0 {
                let loc = Loc {
                    ijk: grid_cell(f.brick_dims, s),
                    t: s.t,
                };
                let v = f.gradient_at(&loc, guard);
                (out[0][j], out[1][j], out[2][j]) = (v.x, v.y, v.z);
            }
        }
        axes!(|a| _mm256_loadu_ps(out[a].as_ptr()))
    }
}

/// Lights the `kept` samples of a tile whose rays have the view vectors `views`, and
/// adds each one's colour times its weight to its ray's entry of `colors`, in order:
/// their gradients (eight at a time, [`gradients`]), views and colours gathered into
/// `batch`, lit by glint-core's lighting model in its batch form
/// ([`glint_core::Shader::shade_gradients`], which is `Shader::shade` bit for bit), as
/// the reference loop lights and composites them one at a time.
///
/// # Safety
/// AVX2 and FMA must be available; the samples must come from clamped positions.
#[target_feature(enable = "avx2,fma")]
pub(super) unsafe fn light(
    c: &Caster,
    kept: &mut Kept,
    views: &[Vec3],
    colors: &mut [[f32; 3]],
    (batch, guard): (&mut ShadeBatch, &Guard),
) {
    let n = kept.len();
    if !c.shader.material().shade {
        for s in &kept.0 {
            let col = &mut colors[s.ray as usize];
            for (c, x) in col.iter_mut().zip(s.rgba) {
                *c += s.weight * x;
            }
        }
        return;
    }
    kept.pad();
    let padded = kept.len();
    batch.set_len(padded);
    for r0 in (0..padded).step_by(LANES) {
        // SAFETY: this function's contract (AVX2; clamped sample positions); the
        // columns hold `padded` entries, so each store of eight at r0 stays inside,
        // and `kept` holds `padded` samples.
        unsafe { gather(c, kept, views, (batch, guard), r0) };
    }
    if let Some(clip) = c.clip {
        cut_faces(c, clip, kept, batch);
    }
    match c.shadows {
        None => c.shader.shade_gradients(batch),
        Some(shadows) => {
            shadow_columns(c, shadows, kept, batch);
            c.shader.shade_gradients_shadowed(batch);
        }
    }
    // In sample order, as the reference loop adds them.
    let [r, g, b] = &batch.color;
    for (s, ((r, g), b)) in kept.0[..n].iter().zip(r.iter().zip(g).zip(b)) {
        let col = &mut colors[s.ray as usize];
        col[0] += s.weight * r;
        col[1] += s.weight * g;
        col[2] += s.weight * b;
    }
}

/// Stores the gradients, view vectors and colours of the kept samples `r0 .. r0 + 8`
/// into the batch's columns.
///
/// # Safety
/// AVX2 and FMA must be available; `kept` holds at least `r0 + 8` samples from clamped
/// positions; the batch's columns hold at least `r0 + 8` entries.
#[inline(always)]
unsafe fn gather(
    c: &Caster,
    kept: &Kept,
    views: &[Vec3],
    (batch, guard): (&mut ShadeBatch, &Guard),
    r0: usize,
) {
    // SAFETY: this function's contract covers the reads of `kept` and the stores into
    // the columns, and the CPU features.
    unsafe {
        let g = if c.field.filter().is_trilinear() {
            gradients(c, kept, r0)
        } else {
            cubic_gradients(c, kept, r0, guard)
        };
        let samples = kept.0.get_unchecked(r0..r0 + LANES);
        let v: [Vec3; LANES] = std::array::from_fn(|j| views[samples[j].ray as usize]);
        let view = [
            _mm256_setr_ps(
                v[0].x, v[1].x, v[2].x, v[3].x, v[4].x, v[5].x, v[6].x, v[7].x,
            ),
            _mm256_setr_ps(
                v[0].y, v[1].y, v[2].y, v[3].y, v[4].y, v[5].y, v[6].y, v[7].y,
            ),
            _mm256_setr_ps(
                v[0].z, v[1].z, v[2].z, v[3].z, v[4].z, v[5].z, v[6].z, v[7].z,
            ),
        ];
        // The eight samples' [r, g, b, alpha], transposed to r, g, b.
        let e = |j: usize| _mm_loadu_ps(samples[j].rgba.as_ptr());
        let q = |a: usize, b: usize| _mm256_insertf128_ps::<1>(_mm256_castps128_ps256(e(a)), e(b));
        let (q0, q1, q2, q3) = (q(0, 4), q(1, 5), q(2, 6), q(3, 7));
        let t0 = _mm256_unpacklo_ps(q0, q1); // r0 r1 g0 g1 | r4 r5 g4 g5
        let t1 = _mm256_unpackhi_ps(q0, q1); // b0 b1 a0 a1 | ...
        let t2 = _mm256_unpacklo_ps(q2, q3);
        let t3 = _mm256_unpackhi_ps(q2, q3);
        let base = [
            _mm256_shuffle_ps::<0b01_00_01_00>(t0, t2),
            _mm256_shuffle_ps::<0b11_10_11_10>(t0, t2),
            _mm256_shuffle_ps::<0b01_00_01_00>(t1, t3),
        ];
        for a in 0..3 {
            _mm256_storeu_ps(batch.normal[a].as_mut_ptr().add(r0), g[a]);
            _mm256_storeu_ps(batch.view[a].as_mut_ptr().add(r0), view[a]);
            _mm256_storeu_ps(batch.color[a].as_mut_ptr().add(r0), base[a]);
        }
    }
}

/// The grid cell of a kept sample: its brick's corner in the grid plus the corner
/// voxel's place in the brick, which is its place in the slot (slots start at
/// multiples of [`BRICK_VOXELS`], laid out as rows of [`BRICK_ROW`] and slices of
/// [`BRICK_SLICE`]).
#[inline(always)]
fn grid_cell(brick_dims: [usize; 3], s: &Sample) -> [usize; 3] {
    let (b, v) = (s.brick as usize, s.base as usize % BRICK_VOXELS);
    let bricks = [
        b % brick_dims[0],
        b / brick_dims[0] % brick_dims[1],
        b / (brick_dims[0] * brick_dims[1]),
    ];
    let local = [v % BRICK_ROW, v / BRICK_ROW % BRICK_ROW, v / BRICK_SLICE];
    std::array::from_fn(|a| bricks[a] * BRICK + local[a])
}

/// Replaces the gradients of the `kept` samples on cut faces as the reference loop's
/// `Caster::add` does ([`IndexClip::cut_gradient`]), at each sample's index-space
/// position ([`grid_cell`] plus its fractions).
fn cut_faces(c: &Caster, clip: &IndexClip, kept: &Kept, batch: &mut ShadeBatch) {
    let brick_dims = c.field.brick_dims;
    for (k, s) in kept.0.iter().enumerate().take(batch.len()) {
        let n = &mut batch.normal;
        let g = Vec3::new(n[0][k], n[1][k], n[2][k]);
        // A strong gradient is kept wherever the sample lies: no position needed.
        if !clip.weak(g) {
            continue;
        }
        let [i, j, kk] = grid_cell(brick_dims, s);
        let p = Vec3::new(i as f32 + s.t[0], j as f32 + s.t[1], kk as f32 + s.t[2]);
        let g = clip.cut_gradient(p, g);
        (n[0][k], n[1][k], n[2][k]) = (g.x, g.y, g.z);
    }
}

/// Fills `batch`'s transmittance and occlusion columns for the `kept` samples from
/// the light volumes, at each sample's index-space position: its grid cell's corner
/// ([`grid_cell`]) plus its fractions, as the reference loop's `Caster::add` computes
/// it from the located sample.
fn shadow_columns(c: &Caster, shadows: &ShadowField, kept: &Kept, batch: &mut ShadeBatch) {
    let n = batch.len();
    let lights = shadows.lights();
    let brick_dims = c.field.brick_dims;
    let (t, occlusion) = batch.shadow_columns(lights);
    let mut tl = [1.0f32; MAX_LIGHTS];
    for (k, s) in kept.0.iter().enumerate().take(n) {
        let [i, j, kk] = grid_cell(brick_dims, s);
        let p = Vec3::new(i as f32 + s.t[0], j as f32 + s.t[1], kk as f32 + s.t[2]);
        occlusion[k] = shadows.at(p, &mut tl);
        for (l, &x) in tl[..lights].iter().enumerate() {
            t[l * n + k] = x;
        }
    }
}
