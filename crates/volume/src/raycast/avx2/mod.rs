//! The composite loops on AVX2 + FMA, in two passes over a tile of rays.
//!
//! March ([`composite_lanes`]): eight rays at a time, one per lane, each lane taking
//! its own ray's next step of the reference loop (`Caster::composite`): a leap out of
//! an empty macro cell or samples (position, cell, trilinear value, transfer-function
//! entry; pre-integrated, the segments ending at them, [`crate::classification::preint`], each lane
//! carrying its ray's last sample as the next segment's front). A vector's loads then
//! belong to eight independent chains, where marching one ray eight samples at a time
//! made each step wait on the one before (and evaluated samples past the ray's end);
//! a lane whose ray stops takes the tile's next ray.
//!
//! The march stops each ray at the same sample as the reference loop. Opacity needs no
//! lighting, so the march only records the samples it keeps: where they are, their
//! colour and their weight.
//!
//! Light: the tile's kept samples, from all its rays, eight at a time: gradients,
//! normals, the lighting cosines; one call of [`glint_lobe::Specular::eval_slice`] (the
//! lobe crate's SIMD kernels) for every sample and light of the tile; then each
//! sample's colour, added to its ray's in sample order. Lighting rays together keeps
//! every vector lane busy (a ray lights about five samples before it terminates) and
//! gives the lobe kernel long slices instead of one short call per chunk.
//!
//! No gather instructions: on CPUs with Intel's Gather Data Sampling mitigation (the
//! 2023 microcode for Skylake to Ice Lake) an eight-lane `vgatherdps` costs about 25
//! cycles, more than eight scalar loads. Corner pairs along i are adjacent in memory,
//! so each sample's eight values come from four 64-bit loads, and its eight 16-bit
//! gradients from four 128-bit loads.
//!
//! Every operation is the reference loop's, in the same order and without FMA
//! contraction, so positions, values, classification and shading are bit-identical to
//! it; only the `exact` and `gauss` lobes differ, by the 2 ulp of glint-lobe's
//! vectorised pow/exp (tested in `tests/render.rs`). Written with `std::arch`
//! intrinsics: stable Rust has no portable SIMD, and the loads need explicit control.

use std::arch::x86_64::*;

use crossbeam_epoch::Guard;

use super::caster::{Caster, Pixels};
use super::TERMINATION_OPACITY;
use crate::classification::{Last, Sampling};
use crate::field::{Filter, MACRO_CELL};
use glint_core::ShadeBatch;
use glint_core::Vec3;
use glint_core::{RenderMode, RenderStats};

/// `[e(0), e(1), e(2)]` with `$a` bound to the axis: per-axis vector code written
/// without closures, which `array::map` would call out of line (its generic body
/// lacks this module's target features, so the intrinsics could not be inlined).
macro_rules! axes {
    (|$a:ident| $e:expr) => {
        [
            {
                let $a = 0usize;
                $e
            },
            {
                let $a = 1usize;
                $e
            },
            {
                let $a = 2usize;
                $e
            },
        ]
    };
}

mod lanes;
mod light;
mod probe;
mod rays;
mod reads;
mod spline;

use lanes::Lanes;
use light::light;
use probe::*;
use rays::LaneRay;
use reads::*;

/// Samples per chunk (f32 lanes of an AVX2 register).
const LANES: usize = 8;

/// Whether this CPU can run [`composite_tile`].
pub(super) fn supported() -> bool {
    is_x86_feature_detected!("avx2") && is_x86_feature_detected!("fma")
}

/// `a + t (b - a)`, rounded as the scalar code rounds it (no FMA).
///
/// # Safety
/// Only for callers compiled with AVX2 (the loops of this module, whose entry checks
/// [`supported`]).
#[inline(always)]
pub(super) unsafe fn lerp(a: __m256, b: __m256, t: __m256) -> __m256 {
    // SAFETY: the caller runs with AVX2 (this function's contract).
    unsafe { _mm256_add_ps(a, _mm256_mul_ps(t, _mm256_sub_ps(b, a))) }
}

/// [`lerp`] on four lanes.
///
/// # Safety
/// Only for callers compiled with AVX2 (the loops of this module, whose entry checks
/// [`supported`]).
#[inline(always)]
pub(super) unsafe fn lerp4(a: __m128, b: __m128, t: __m128) -> __m128 {
    // SAFETY: the caller runs with AVX2 (this function's contract).
    unsafe { _mm_add_ps(a, _mm_mul_ps(t, _mm_sub_ps(b, a))) }
}

/// The two f32 at `p` as one 64-bit integer.
///
/// # Safety
/// `p` and `p + 1` must be readable f32 (alignment is not required).
#[inline(always)]
pub(super) unsafe fn pair(p: *const f32) -> i64 {
    // SAFETY: the caller guarantees 8 readable bytes at `p`; no alignment is assumed.
    unsafe { p.cast::<i64>().read_unaligned() }
}

/// Corners `(i, i+1)` of one row for eight lanes whose row starts are `p[l] + off`: the
/// first corners in lane order, then the second.
///
/// # Safety
/// Each `p[l] + off` and the f32 after it must be readable, and the CPU must support
/// AVX2 (as for the other helpers of this module).
#[inline(always)]
pub(super) unsafe fn row(p: [*const f32; LANES], off: usize) -> (__m256, __m256) {
    // SAFETY: this function's `# Safety` contract, which its callers uphold,
    // covers every unsafe operation below (CPU features, pointer ranges).
    unsafe {
        let at = |l: usize| pair(p[l].add(off));
        // Lanes 0,1,4,5 and 2,3,6,7: the in-lane shuffles below then give lane order.
        let a = _mm256_castsi256_ps(_mm256_set_epi64x(at(5), at(4), at(1), at(0)));
        let b = _mm256_castsi256_ps(_mm256_set_epi64x(at(7), at(6), at(3), at(2)));
        (
            _mm256_shuffle_ps::<0b10_00_10_00>(a, b),
            _mm256_shuffle_ps::<0b11_01_11_01>(a, b),
        )
    }
}

/// A sample a tile's ray keeps: one record, so keeping a sample is one push.
#[derive(Clone, Copy)]
#[repr(C)]
pub(super) struct Sample {
    /// The sample's segment ([`crate::classification::preint`]): linear colour and opacity (first, so
    /// [`light`] loads it as one vector).
    pub(super) rgba: [f32; 4],
    /// Fractions inside the trilinear cell, per axis.
    pub(super) t: [f32; 3],
    /// Front-to-back weight `(1 - alpha) alpha_sample`.
    pub(super) weight: f32,
    /// The sample's corner-000 voxel in the brick pool (valid while the tile's guard
    /// lives).
    pub(super) base: i32,
    /// The grid index of the brick holding that voxel: with the voxel's place in its
    /// slot (`base` modulo the slot size) it gives the sample's grid cell, which the
    /// `shadows` model's light volumes are indexed by ([`light`]).
    pub(super) brick: i32,
    /// The ray's index in the tile.
    pub(super) ray: u32,
}

/// The samples a tile's rays keep, in ray order and, within a ray, sample order.
#[derive(Default)]
pub(super) struct Kept(Vec<Sample>);

impl Kept {
    #[inline(always)]
    pub(super) fn len(&self) -> usize {
        self.0.len()
    }

    #[inline(always)]
    pub(super) fn clear(&mut self) {
        self.0.clear();
    }

    /// Pads to a whole number of vectors with copies of the first sample (lit, then
    /// ignored).
    #[inline(always)]
    pub(super) fn pad(&mut self) {
        while !self.len().is_multiple_of(LANES) {
            self.0.push(self.0[0]);
        }
    }
}

/// Per-thread buffers of [`composite_tile`], kept from tile to tile so a tile
/// allocates nothing.
#[derive(Default)]
pub(super) struct Scratch {
    pub(super) views: Vec<Vec3>,
    /// The tile's rays that meet a visible cell, in pixel order
    /// ([`Scratch::tile_rays`]).
    pub(super) rays: Vec<LaneRay>,
    pub(super) colors: Vec<[f32; 3]>,
    pub(super) kept: Kept,
    pub(super) light: ShadeBatch,
}

/// Resizes `v` to `n` copies of `x` without giving back its capacity.
#[inline(always)]
pub(super) fn refill<T: Copy>(v: &mut Vec<T>, n: usize, x: T) {
    v.clear();
    v.resize(n, x);
}

/// Lane `l`'s bit of an eight-bit mask `m`, as a vector mask (all ones or zero).
///
/// # Safety
/// The CPU must support AVX2 (the loops of this module).
#[inline(always)]
pub(super) unsafe fn lane_mask(m: u8) -> __m256i {
    // SAFETY: the caller runs with AVX2 (this function's contract).
    unsafe {
        let lane_bits = _mm256_setr_epi32(1, 2, 4, 8, 16, 32, 64, 128);
        let v = _mm256_and_si256(_mm256_set1_epi32(i32::from(m)), lane_bits);
        _mm256_cmpeq_epi32(v, lane_bits)
    }
}

impl Scratch {
    /// Sets up the rays of the tile `px` (`n` pixels) eight at a time
    /// ([`rays::rays8`]), before any is marched, keeping those that meet a visible cell
    /// in pixel order.
    ///
    /// # Safety
    /// The CPU must support AVX2 (inlined into [`composite_lanes`]).
    #[inline(always)]
    pub(super) unsafe fn tile_rays(&mut self, c: &Caster, px: &Pixels, n: usize) {
        self.rays.clear();
        for i0 in (0..n).step_by(LANES) {
            // SAFETY: this function's contract; i0 is a multiple of 8 below n, which
            // is at most TILE * TILE.
            unsafe { rays::rays8(c, px, (i0, n), &mut self.rays, &mut self.views) };
        }
    }

    /// Starts a tile of `n` rays: no kept samples, zero colours, and `n` zero
    /// opacities appended to `alpha`. Returns where the tile's opacities start.
    #[inline(always)]
    pub(super) fn begin(&mut self, n: usize, alpha: &mut Vec<f32>) -> usize {
        refill(&mut self.views, n, Vec3::ZERO);
        refill(&mut self.colors, n, [0.0; 3]);
        self.kept.clear();
        let start = alpha.len();
        alpha.resize(start + n, 0.0);
        start
    }
}

/// Ends a tile: lights its kept samples, then writes each pixel's colour over the
/// background by its opacity (`alpha`, the tile's).
///
/// # Safety
/// The CPU must support AVX2 and FMA ([`supported`]).
#[target_feature(enable = "avx2,fma")]
pub(super) unsafe fn finish(
    c: &Caster,
    scratch: &mut Scratch,
    alpha: &[f32],
    rgb: &mut Vec<[f32; 3]>,
    guard: &Guard,
) {
    let Scratch {
        views,
        colors,
        kept,
        light: buffers,
        ..
    } = scratch;
    if kept.len() > 0 {
        // SAFETY: this function's contract.
        unsafe { light(c, kept, views, colors, (buffers, guard)) };
    }
    let bg = c.frame.background;
    for (col, &op) in colors.iter().zip(alpha) {
        rgb.push([
            col[0] + (1.0 - op) * bg[0],
            col[1] + (1.0 - op) * bg[1],
            col[2] + (1.0 - op) * bg[2],
        ]);
    }
}

/// Composites the rays of the tile `px` front to back: the same pixels as
/// `Caster::tile`. When a brick cannot be built (the brick cache is full of bricks in
/// use), the tile's partial results are dropped and the reference loop renders it
/// (its reads fall back to bricks built outside the cache).
///
/// # Safety
/// The CPU must support AVX2 and FMA ([`supported`]).
pub(super) unsafe fn composite_tile(
    c: &Caster,
    px: &Pixels,
    scratch: &mut Scratch,
    (rgb, alpha): (&mut Vec<[f32; 3]>, &mut Vec<f32>),
    stats: &mut RenderStats,
    guard: &Guard,
) {
    let (start, before) = (alpha.len(), *stats);
    // SAFETY: the caller upholds the same contract. One loop per sampling, so neither
    // carries the other's code.
    let done = unsafe {
        let out = (&mut *rgb, &mut *alpha);
        match (c.sampling, c.field.filter()) {
            (Sampling::PreIntegrated, Filter::Trilinear) => {
                composite_lanes::<true, false>(c, px, scratch, out, stats, guard)
            }
            (Sampling::Point, Filter::Trilinear) => {
                composite_lanes::<false, false>(c, px, scratch, out, stats, guard)
            }
            (Sampling::PreIntegrated, Filter::Tricubic) => {
                composite_lanes::<true, true>(c, px, scratch, out, stats, guard)
            }
            (Sampling::Point, Filter::Tricubic) => {
                composite_lanes::<false, true>(c, px, scratch, out, stats, guard)
            }
        }
    };
    if !done {
        alpha.truncate(start);
        *stats = before;
        c.tile(px, rgb, alpha, stats, guard);
    }
}

/// Eight rays marched together, one per lane: each lane takes the reference loop's
/// next step of its own ray (a leap out of an empty macro cell, or samples:
/// [`Lanes::step`] for point sampling, [`Lanes::segment_step`] pre-integrated when
/// `PRE`; the tricubic B-spline's values when `CUBIC`), so a vector's loads belong to
/// eight independent chains. A lane whose ray ends takes the tile's next ray. Returns `false`, leaving `rgb` as it was, when a
/// brick could not be built.
///
/// # Safety
/// The CPU must support AVX2 and FMA ([`supported`]).
#[target_feature(enable = "avx2,fma")]
pub(super) unsafe fn composite_lanes<const PRE: bool, const CUBIC: bool>(
    c: &Caster,
    px: &Pixels,
    scratch: &mut Scratch,
    (rgb, alpha): (&mut Vec<[f32; 3]>, &mut Vec<f32>),
    stats: &mut RenderStats,
    guard: &Guard,
) -> bool {
    // SAFETY: this function's `# Safety` contract, which its callers uphold,
    // covers every unsafe operation below (CPU features, pointer ranges).
    unsafe {
        let n = (px.xs.1 - px.xs.0) * (px.ys.1 - px.ys.0);
        let start = scratch.begin(n, alpha);
        scratch.tile_rays(c, px, n);
        let Scratch { kept, rays, .. } = &mut *scratch;
        let inv = Invariants::new(c);
        let mut lanes = Lanes::default();
        let mut next = 0;
        loop {
            // Fill the idle lanes with the next rays.
            let mut idle = !lanes.live;
            while idle != 0 && next < rays.len() {
                let l = idle.trailing_zeros() as usize;
                idle &= idle - 1;
                lanes.set(l, rays.get_unchecked(next));
                next += 1;
            }
            if lanes.live == 0 {
                break;
            }
            let ended = if PRE {
                lanes.segment_step::<CUBIC>(c, &inv, kept, stats, guard)
            } else {
                lanes.step::<CUBIC>(c, &inv, kept, stats, guard)
            };
            if lanes.failed {
                return false;
            }
            for l in (0..LANES).filter(|l| ended & (1 << l) != 0) {
                alpha[start + lanes.id[l] as usize] = lanes.alpha[l];
            }
        }
        finish(c, scratch, &alpha[start..], rgb, guard);
        true
    }
}

/// Records a composited sample of the ray `id` whose opacity so far is `alpha` (voxel
/// `base` in the pool, in the grid's brick `brick`, fractions `t`, its segment's colour
/// and opacity) and adds its opacity as the reference loop does, in the same order.
/// Returns whether the ray is now opaque enough to stop.
#[inline(always)]
pub(super) fn keep(
    kept: &mut Kept,
    (alpha, id): (&mut f32, u32),
    (base, brick): (i32, i32),
    t: [f32; 3],
    rgba: [f32; 4],
    stats: &mut RenderStats,
) -> bool {
    let w = (1.0 - *alpha) * rgba[3];
    kept.0.push(Sample {
        rgba,
        t,
        weight: w,
        base,
        brick,
        ray: id,
    });
    stats.shaded += 1;
    *alpha += w;
    *alpha >= TERMINATION_OPACITY
}

impl Caster<'_> {
    /// [`Caster::tile`] compiled for AVX2 and FMA, with composite rays marched and
    /// lit by the SIMD loops of this module (no FMA contraction anywhere, so results are
    /// the scalar loop's).
    ///
    /// # Safety
    /// The CPU must support AVX2 and FMA.
    #[target_feature(enable = "avx2,fma")]
    pub(super) unsafe fn tile_avx2(
        &self,
        px: &Pixels,
        scratch: &mut Scratch,
        rgb: &mut Vec<[f32; 3]>,
        alpha: &mut Vec<f32>,
        stats: &mut RenderStats,
        guard: &Guard,
    ) {
        // SAFETY: this function's `# Safety` contract, which its callers uphold,
        // covers every unsafe operation below (CPU features, pointer ranges).
        unsafe {
            if self.mode == RenderMode::Composite {
                composite_tile(self, px, scratch, (rgb, alpha), stats, guard)
            } else {
                self.tile(px, rgb, alpha, stats, guard)
            }
        }
    }
}
