//! The composite loops on AVX2 + FMA, in two passes over a tile of rays.
//!
//! March ([`composite_lanes`]): eight rays at a time, one per lane, each lane taking
//! its own ray's next step of the reference loop (`Caster::composite`): a leap out of
//! an empty macro cell or samples (position, cell, trilinear value, transfer-function
//! entry; pre-integrated, the segments ending at them, [`crate::preint`], each lane
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

use super::caster::{Caster, Pixels, Ray};
use super::TERMINATION_OPACITY;
use crate::field::MACRO_CELL;
use crate::preint::{Last, Sampling};
use glint_core::RenderStats;
use glint_core::ShadeBatch;
use glint_core::Vec3;

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
unsafe fn lerp(a: __m256, b: __m256, t: __m256) -> __m256 {
    // SAFETY: the caller runs with AVX2 (this function's contract).
    unsafe { _mm256_add_ps(a, _mm256_mul_ps(t, _mm256_sub_ps(b, a))) }
}

/// [`lerp`] on four lanes.
///
/// # Safety
/// Only for callers compiled with AVX2 (the loops of this module, whose entry checks
/// [`supported`]).
#[inline(always)]
unsafe fn lerp4(a: __m128, b: __m128, t: __m128) -> __m128 {
    // SAFETY: the caller runs with AVX2 (this function's contract).
    unsafe { _mm_add_ps(a, _mm_mul_ps(t, _mm_sub_ps(b, a))) }
}

/// The two f32 at `p` as one 64-bit integer.
///
/// # Safety
/// `p` and `p + 1` must be readable f32 (alignment is not required).
#[inline(always)]
unsafe fn pair(p: *const f32) -> i64 {
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
unsafe fn row(p: [*const f32; LANES], off: usize) -> (__m256, __m256) {
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
struct Sample {
    /// The sample's segment ([`crate::preint`]): linear colour and opacity (first, so
    /// [`light`] loads it as one vector).
    rgba: [f32; 4],
    /// Fractions inside the trilinear cell, per axis.
    t: [f32; 3],
    /// Front-to-back weight `(1 - alpha) alpha_sample`.
    weight: f32,
    /// Linear index of the sample's corner-000 voxel.
    base: i32,
    /// The ray's index in the tile.
    ray: u32,
}

/// The samples a tile's rays keep, in ray order and, within a ray, sample order.
#[derive(Default)]
struct Kept(Vec<Sample>);

impl Kept {
    fn len(&self) -> usize {
        self.0.len()
    }

    fn clear(&mut self) {
        self.0.clear();
    }

    /// Pads to a whole number of vectors with copies of the first sample (lit, then
    /// ignored).
    fn pad(&mut self) {
        while !self.len().is_multiple_of(LANES) {
            self.0.push(self.0[0]);
        }
    }
}

/// Per-thread buffers of [`composite_tile`], kept from tile to tile so a tile
/// allocates nothing.
#[derive(Default)]
pub(super) struct Scratch {
    views: Vec<Vec3>,
    colors: Vec<[f32; 3]>,
    kept: Kept,
    light: ShadeBatch,
}

/// Resizes `v` to `n` copies of `x` without giving back its capacity.
fn refill<T: Copy>(v: &mut Vec<T>, n: usize, x: T) {
    v.clear();
    v.resize(n, x);
}

/// The ray of the tile's pixel `i` (row-major in the tile) when it meets a visible
/// cell, its view vector recorded in `views[i]`.
#[inline(always)]
fn pixel_ray(c: &Caster, px: &Pixels, i: usize, views: &mut [Vec3]) -> Option<Ray> {
    let tw = px.xs.1 - px.xs.0;
    let (x, y) = (px.xs.0 + i % tw, px.ys.0 + i / tw);
    let (ray, view) = c.ray(x as f32, y as f32, (px.start[i], px.end[i]))?;
    views[i] = view;
    Some(ray)
}

/// Lane `l`'s bit of an eight-bit mask `m`, as a vector mask (all ones or zero).
///
/// # Safety
/// The CPU must support AVX2 (the loops of this module).
#[inline(always)]
unsafe fn lane_mask(m: u8) -> __m256i {
    // SAFETY: the caller runs with AVX2 (this function's contract).
    unsafe {
        let lane_bits = _mm256_setr_epi32(1, 2, 4, 8, 16, 32, 64, 128);
        let v = _mm256_and_si256(_mm256_set1_epi32(i32::from(m)), lane_bits);
        _mm256_cmpeq_epi32(v, lane_bits)
    }
}

impl Scratch {
    /// Starts a tile of `n` rays: no kept samples, zero colours, and `n` zero
    /// opacities appended to `alpha`. Returns where the tile's opacities start.
    fn begin(&mut self, n: usize, alpha: &mut Vec<f32>) -> usize {
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
unsafe fn finish(c: &Caster, scratch: &mut Scratch, alpha: &[f32], rgb: &mut Vec<[f32; 3]>) {
    let Scratch {
        views,
        colors,
        kept,
        light: buffers,
    } = scratch;
    if kept.len() > 0 {
        // SAFETY: this function's contract.
        unsafe { light(c, kept, views, colors, buffers) };
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
/// `Caster::tile`.
///
/// # Safety
/// The CPU must support AVX2 and FMA ([`supported`]).
pub(super) unsafe fn composite_tile(
    c: &Caster,
    px: &Pixels,
    scratch: &mut Scratch,
    rgb: &mut Vec<[f32; 3]>,
    alpha: &mut Vec<f32>,
    stats: &mut RenderStats,
) {
    // SAFETY: the caller upholds the same contract. One loop per sampling, so neither
    // carries the other's code.
    unsafe {
        if c.sampling == Sampling::PreIntegrated {
            composite_lanes::<true>(c, px, scratch, rgb, alpha, stats)
        } else {
            composite_lanes::<false>(c, px, scratch, rgb, alpha, stats)
        }
    }
}

/// Eight rays marched together, one per lane: each lane takes the reference loop's
/// next step of its own ray (a leap out of an empty macro cell, or samples:
/// [`Lanes::step`] for point sampling, [`Lanes::segment_step`] pre-integrated when
/// `PRE`), so a vector's loads belong to eight independent chains. A lane whose ray
/// ends takes the tile's next ray.
///
/// # Safety
/// The CPU must support AVX2 and FMA ([`supported`]).
#[target_feature(enable = "avx2,fma")]
unsafe fn composite_lanes<const PRE: bool>(
    c: &Caster,
    px: &Pixels,
    scratch: &mut Scratch,
    rgb: &mut Vec<[f32; 3]>,
    alpha: &mut Vec<f32>,
    stats: &mut RenderStats,
) {
    // SAFETY: this function's `# Safety` contract, which its callers uphold,
    // covers every unsafe operation below (CPU features, pointer ranges).
    unsafe {
        let n = (px.xs.1 - px.xs.0) * (px.ys.1 - px.ys.0);
        let start = scratch.begin(n, alpha);
        let Scratch { views, kept, .. } = &mut *scratch;
        let inv = Invariants::new(c);
        let mut lanes = Lanes::default();
        let mut next = 0;
        loop {
            // Fill the idle lanes with the next rays that meet a visible cell.
            let mut idle = !lanes.live;
            while idle != 0 && next < n {
                let l = idle.trailing_zeros() as usize;
                idle &= idle - 1;
                while lanes.live & (1 << l) == 0 && next < n {
                    let i = next;
                    next += 1;
                    if let Some(ray) = pixel_ray(c, px, i, views) {
                        lanes.set(l, &ray, i as u32);
                    }
                }
            }
            if lanes.live == 0 {
                break;
            }
            let ended = if PRE {
                lanes.segment_step(c, &inv, kept, stats)
            } else {
                lanes.step(c, &inv, kept, stats)
            };
            for l in (0..LANES).filter(|l| ended & (1 << l) != 0) {
                alpha[start + lanes.id[l] as usize] = lanes.alpha[l];
            }
        }
        finish(c, scratch, &alpha[start..], rgb);
    }
}

/// The state of eight rays marched one per lane ([`composite_lanes`]), by component.
#[derive(Default)]
struct Lanes {
    /// Bit `l`: lane `l` holds a ray.
    live: u8,
    o: [[f32; LANES]; 3],
    d: [[f32; LANES]; 3],
    /// [`Ray::inv_dk`].
    inv_dk: [[f32; LANES]; 3],
    /// [`Ray::face_up`], as all-ones or zero.
    up: [[i32; LANES]; 3],
    j: [f32; LANES],
    /// Next sample, and the last.
    k: [i32; LANES],
    k1: [i32; LANES],
    alpha: [f32; LANES],
    id: [u32; LANES],
    /// Pre-integrated sampling: the last sample read and its table coordinate (the
    /// front of the next segment; `i32::MIN` for none), and the segment cache.
    prev_k: [i32; LANES],
    prev_u: [f32; LANES],
    last: [Last; LANES],
}

impl Lanes {
    /// Starts `ray` (the tile's ray `id`) in lane `l`.
    fn set(&mut self, l: usize, ray: &Ray, id: u32) {
        for a in 0..3 {
            self.o[a][l] = ray.o.get(a);
            self.d[a][l] = ray.d.get(a);
            self.inv_dk[a][l] = ray.inv_dk[a];
            self.up[a][l] = if ray.face_up[a] { -1 } else { 0 };
        }
        self.j[l] = ray.j;
        // Sample indices are exact in f32 below 2^24 (as `Ray::t` assumes), so within
        // i32; a longer ray is cut there.
        self.k[l] = ray.k0.clamp(-(1 << 24), 1 << 24) as i32;
        self.k1[l] = ray.k1.clamp(-(1 << 24), 1 << 24) as i32;
        self.alpha[l] = 0.0;
        self.id[l] = id;
        self.prev_k[l] = i32::MIN;
        self.last[l] = Last::default();
        self.live |= 1 << l;
    }

    /// The lanes' rays `(o, d, j)`, next samples and last samples, as vectors.
    ///
    /// # Safety
    /// The CPU must support AVX2 (inlined into [`composite_lanes`]).
    #[inline(always)]
    unsafe fn rays(&self) -> (([__m256; 3], [__m256; 3], __m256), __m256i, __m256i) {
        // SAFETY: the caller runs with AVX2 (this function's contract); the loads read
        // whole arrays of eight.
        unsafe {
            let ld = |v: &[f32; LANES]| _mm256_loadu_ps(v.as_ptr());
            let ldi = |v: &[i32; LANES]| _mm256_loadu_si256(v.as_ptr().cast());
            (
                (
                    axes!(|a| ld(&self.o[a])),
                    axes!(|a| ld(&self.d[a])),
                    ld(&self.j),
                ),
                ldi(&self.k),
                ldi(&self.k1),
            )
        }
    }

    /// Ends a step: the next samples `k_next`; the lanes `ended` (full opacity) and
    /// those past their last sample `k1` become idle. Returns them.
    ///
    /// # Safety
    /// The CPU must support AVX2 (inlined into [`composite_lanes`]).
    #[inline(always)]
    unsafe fn advance(&mut self, k_next: __m256i, k1: __m256i, ended: u8) -> u8 {
        // SAFETY: the caller runs with AVX2 (this function's contract); the store
        // writes the whole array of eight.
        unsafe {
            _mm256_storeu_si256(self.k.as_mut_ptr().cast(), k_next);
            let past =
                _mm256_movemask_ps(_mm256_castsi256_ps(_mm256_cmpgt_epi32(k_next, k1))) as u8;
            let ended = (ended | past) & self.live;
            self.live &= !ended;
            ended
        }
    }

    /// One step of every live lane: a leap where the sample lies in an empty macro
    /// cell (`Caster::leap`, lane by lane in vectors), else the sample. Returns the
    /// lanes whose rays ended, now idle.
    ///
    /// # Safety
    /// The CPU must support AVX2 and FMA (inlined into [`composite_lanes`]).
    #[inline(always)]
    unsafe fn step(
        &mut self,
        c: &Caster,
        inv: &Invariants,
        kept: &mut Kept,
        stats: &mut RenderStats,
    ) -> u8 {
        // SAFETY: this function's `# Safety` contract, which its callers uphold,
        // covers every unsafe operation below (CPU features, pointer ranges).
        unsafe {
            let (ray, k, k1) = self.rays();
            // Sample k's position and cell per lane: `Ray::t`, `Ray::at` and
            // `Field::locate`, as the reference loop computes them.
            let (p, ijk) = positions(inv, ray, k);
            let (cells, dist, visible) = cell_distances(c, inv, ijk);
            let leaps = !visible & self.live;
            let samples = self.live & !leaps;
            let mut ended = 0u8;
            let k_plus = _mm256_add_epi32(k, _mm256_set1_epi32(1));
            let mut k_next = k_plus;
            if leaps != 0 {
                stats.skips += u64::from(leaps.count_ones());
                k_next = self.leap(k, k_next, cells, dist, leaps);
            }
            if samples != 0 {
                // Each sampling lane takes samples k and k + 1 (when k + 1 <= k1): a
                // second sample in an empty cell has no opacity, so taking it changes
                // nothing, and the pair halves the step's fixed work per sample.
                let last = _mm256_cmpgt_epi32(k_plus, k1);
                let second = samples & !(_mm256_movemask_ps(_mm256_castsi256_ps(last)) as u8);
                stats.samples += u64::from(samples.count_ones() + second.count_ones());
                let first = probe(c, inv, p, ijk);
                ended |= self.keep_hits(c.lut, kept, samples & first.opaque, &first, stats);
                if second != 0 {
                    let (p2, ijk2) = positions(inv, ray, k_plus);
                    let next = probe(c, inv, p2, ijk2);
                    ended |=
                        self.keep_hits(c.lut, kept, second & next.opaque & !ended, &next, stats);
                    // All ones is -1: subtracting it steps the second-sample lanes once more.
                    k_next = _mm256_sub_epi32(k_next, lane_mask(second));
                }
            }
            self.advance(k_next, k1, ended)
        }
    }

    /// [`Lanes::step`] for pre-integrated sampling, the reference loop's step with
    /// segments (`Caster::composite`): each sample composites the segment from the
    /// sample before ([`crate::preint`]). Where sample k lies in a visible cell, the
    /// segment ending at k, its front read first as sample k - 1 when that was not
    /// read (after a leap, or at the ray's start: `Caster::before`), and when the
    /// front was known the segment ending at k + 1 too (as [`Lanes::step`] takes a
    /// second sample). Where sample k lies in an empty cell, the segment ending at k
    /// when sample k - 1 was read (it may leave a visible cell), then the leap.
    /// Returns the lanes whose rays ended, now idle.
    ///
    /// # Safety
    /// The CPU must support AVX2 and FMA (inlined into [`composite_lanes`]).
    #[inline(always)]
    unsafe fn segment_step(
        &mut self,
        c: &Caster,
        inv: &Invariants,
        kept: &mut Kept,
        stats: &mut RenderStats,
    ) -> u8 {
        // SAFETY: this function's `# Safety` contract, which its callers uphold,
        // covers every unsafe operation below (CPU features, pointer ranges).
        unsafe {
            let (ray, k, k1) = self.rays();
            let one = _mm256_set1_epi32(1);
            let k_before = _mm256_sub_epi32(k, one);
            let prev_k = _mm256_loadu_si256(self.prev_k.as_ptr().cast());
            let known_v = _mm256_cmpeq_epi32(prev_k, k_before);
            let known = _mm256_movemask_ps(_mm256_castsi256_ps(known_v)) as u8 & self.live;
            // The two reads of a lane: k - 1 and k where the front is unknown, else k
            // and k + 1. Sample k's cell decides between sampling and leaping.
            let first_k = _mm256_blendv_epi8(k_before, k, known_v);
            let second_k = _mm256_add_epi32(first_k, one);
            let (p0, ijk0) = positions(inv, ray, first_k);
            let (p1, ijk1) = positions(inv, ray, second_k);
            let ijk_k = axes!(|a| _mm256_blendv_epi8(ijk1[a], ijk0[a], known_v));
            let (cells, dist, visible) = cell_distances(c, inv, ijk_k);
            let visible = visible & self.live;
            let leaps = self.live & !visible;
            let beyond = _mm256_movemask_ps(_mm256_castsi256_ps(_mm256_cmpgt_epi32(second_k, k1)));
            let reads = visible | (leaps & known);
            let seconds = visible & !(beyond as u8);
            let mut k_next = _mm256_add_epi32(k, one);
            if leaps != 0 {
                stats.skips += u64::from(leaps.count_ones());
                k_next = self.leap(k, k_next, cells, dist, leaps);
            }
            let mut ended = 0u8;
            if reads != 0 {
                let first = reads_at(inv, p0, ijk0, first_k);
                let second = if seconds != 0 {
                    reads_at(inv, p1, ijk1, second_k)
                } else {
                    first
                };
                ended =
                    self.keep_segments(c, kept, stats, [&first, &second], (reads, known, seconds));
                // All ones is -1: lanes that read k and k + 1 step once more.
                k_next = _mm256_sub_epi32(k_next, lane_mask(known & seconds));
            }
            self.advance(k_next, k1, ended)
        }
    }

    /// [`Lanes::segment_step`]'s segments: lanes `reads` have read their first
    /// sample, lanes `seconds` their second as well; a lane in `known` composites the
    /// segment from its last read to the first, every lane in `seconds` the one from
    /// its first to its second. Returns the lanes whose rays reached full opacity.
    #[inline(always)]
    fn keep_segments(
        &mut self,
        c: &Caster,
        kept: &mut Kept,
        stats: &mut RenderStats,
        [first, second]: [&Reads; 2],
        (reads, known, seconds): (u8, u8, u8),
    ) -> u8 {
        let mut ended = 0u8;
        let mut m = reads;
        while m != 0 {
            let l = m.trailing_zeros() as usize;
            m &= m - 1;
            let bit = 1u8 << l;
            let front = (known & bit != 0).then_some(self.prev_u[l]);
            if self.read(c, l, front, first, kept, stats)
                || (seconds & bit != 0 && self.read(c, l, Some(first.u[l]), second, kept, stats))
            {
                ended |= bit;
            }
        }
        ended
    }

    /// Lane `l`'s read `r`: the segment to it from `front` when that is known, kept if
    /// it has opacity; the read becomes the lane's last. Returns whether the ray
    /// reached full opacity.
    #[inline(always)]
    fn read(
        &mut self,
        c: &Caster,
        l: usize,
        front: Option<f32>,
        r: &Reads,
        kept: &mut Kept,
        stats: &mut RenderStats,
    ) -> bool {
        stats.samples += 1;
        (self.prev_k[l], self.prev_u[l]) = (r.k[l], r.u[l]);
        let Some(f) = front else {
            return false;
        };
        let Some(rgba) = c.lut.pre.segment(f, r.u[l], &mut self.last[l]) else {
            return false;
        };
        let t = [r.t[0][l], r.t[1][l], r.t[2][l]];
        keep(
            kept,
            (&mut self.alpha[l], self.id[l]),
            r.base[l],
            t,
            rgba,
            stats,
        )
    }

    /// Keeps the samples of `probe` in the lanes `hits`; returns the lanes whose rays
    /// reached full opacity.
    ///
    /// # Safety
    /// The CPU must support AVX2 (inlined into [`composite_lanes`]).
    #[inline(always)]
    unsafe fn keep_hits(
        &mut self,
        lut: &crate::lut::Lut,
        kept: &mut Kept,
        mut hits: u8,
        probe: &Probe,
        stats: &mut RenderStats,
    ) -> u8 {
        let mut ended = 0u8;
        if hits == 0 {
            return ended;
        }
        // SAFETY: the caller runs with AVX2 (this function's contract).
        unsafe {
            let mut t = [[0.0f32; LANES]; 3];
            for (a, v) in probe.fr.iter().enumerate() {
                _mm256_storeu_ps(t[a].as_mut_ptr(), *v);
            }
            while hits != 0 {
                let l = hits.trailing_zeros() as usize;
                hits &= hits - 1;
                // SAFETY: the entry index was clamped to the table.
                let rgba = *lut.entries.get_unchecked(probe.li[l] as usize);
                let tl = [t[0][l], t[1][l], t[2][l]];
                if keep(
                    kept,
                    (&mut self.alpha[l], self.id[l]),
                    probe.base[l],
                    tl,
                    rgba,
                    stats,
                ) {
                    ended |= 1 << l;
                }
            }
        }
        ended
    }

    /// `Caster::leap` for the lanes `leaps` (the others keep `k_next`): past the cube
    /// of empty cells of radius `dist - 1` around `cells`, at least one sample on.
    ///
    /// # Safety
    /// The CPU must support AVX2 (inlined into [`composite_lanes`]).
    #[inline(always)]
    unsafe fn leap(
        &self,
        k: __m256i,
        k_next: __m256i,
        cells: [__m256i; 3],
        dist: __m256i,
        leaps: u8,
    ) -> __m256i {
        // SAFETY: the caller runs with AVX2 (this function's contract).
        unsafe {
            let ld = |v: &[f32; LANES]| _mm256_loadu_ps(v.as_ptr());
            let r = _mm256_sub_epi32(dist, _mm256_set1_epi32(1));
            let mc = MACRO_CELL as i32;
            let mut q = _mm256_set1_ps(f32::INFINITY);
            for (a, &cell) in cells.iter().enumerate() {
                let up = _mm256_loadu_si256(self.up[a].as_ptr().cast());
                let above = _mm256_add_epi32(_mm256_add_epi32(cell, r), _mm256_set1_epi32(1));
                let below = _mm256_max_epi32(_mm256_sub_epi32(cell, r), _mm256_setzero_si256());
                let face = _mm256_cvtepi32_ps(_mm256_mullo_epi32(
                    _mm256_blendv_epi8(below, above, up),
                    _mm256_set1_epi32(mc),
                ));
                let x = _mm256_mul_ps(_mm256_sub_ps(face, ld(&self.o[a])), ld(&self.inv_dk[a]));
                // `q.min(x)`: a NaN x leaves q (MINPS returns its second operand).
                q = _mm256_min_ps(x, q);
            }
            // `ceil_i64(q - j - 1/64).max(k + 1)`, the argument clamped to +-2^25 to fit
            // i32: sample indices stay within +-2^24, so a clamped value ends the ray
            // (or gives k + 1) just as the unclamped one does.
            let y = _mm256_sub_ps(_mm256_sub_ps(q, ld(&self.j)), _mm256_set1_ps(1.0 / 64.0));
            let lim = (1 << 25) as f32;
            let y = _mm256_max_ps(_mm256_min_ps(y, _mm256_set1_ps(lim)), _mm256_set1_ps(-lim));
            let kk = _mm256_cvttps_epi32(y);
            let up = _mm256_castps_si256(_mm256_cmp_ps::<_CMP_LT_OQ>(_mm256_cvtepi32_ps(kk), y));
            let kk = _mm256_sub_epi32(kk, up);
            let leapt = _mm256_max_epi32(kk, _mm256_add_epi32(k, _mm256_set1_epi32(1)));
            _mm256_blendv_epi8(k_next, leapt, lane_mask(leaps))
        }
    }
}

/// One sample per lane, as [`Lanes::keep_segments`] uses it.
#[derive(Clone, Copy)]
struct Reads {
    /// Fractions inside the trilinear cell, per axis.
    t: [[f32; LANES]; 3],
    /// Corner-000 voxel.
    base: [i32; LANES],
    /// Table coordinate (`Lut::position` of the trilinear value).
    u: [f32; LANES],
    /// Sample index.
    k: [i32; LANES],
}

/// The samples at positions `p` (cells `ijk`, clamped) with sample indices `k`.
///
/// # Safety
/// The CPU must support AVX2 (inlined into [`composite_lanes`]); `ijk` must be
/// clamped to the field's cells.
#[inline(always)]
unsafe fn reads_at(inv: &Invariants, p: [__m256; 3], ijk: [__m256i; 3], k: __m256i) -> Reads {
    // SAFETY: this function's `# Safety` contract, which its callers uphold,
    // covers every unsafe operation below (CPU features, pointer ranges).
    unsafe {
        let (fr, base, uv) = values_at(inv, p, ijk);
        let mut r = Reads {
            t: [[0.0; LANES]; 3],
            base,
            u: [0.0; LANES],
            k: [0; LANES],
        };
        for (a, v) in fr.iter().enumerate() {
            _mm256_storeu_ps(r.t[a].as_mut_ptr(), *v);
        }
        _mm256_storeu_ps(r.u.as_mut_ptr(), uv);
        _mm256_storeu_si256(r.k.as_mut_ptr().cast(), k);
        r
    }
}

/// The macro cells of the cells `ijk` (one per lane), their distance-map entries, and
/// the lanes whose cell is visible (entry 0).
///
/// # Safety
/// The CPU must support AVX2 (inlined into [`composite_lanes`]); `ijk` must be
/// clamped to the field's cells.
#[inline(always)]
unsafe fn cell_distances(
    c: &Caster,
    inv: &Invariants,
    ijk: [__m256i; 3],
) -> ([__m256i; 3], __m256i, u8) {
    // SAFETY: this function's `# Safety` contract, which its callers uphold,
    // covers every unsafe operation below (CPU features, pointer ranges).
    unsafe {
        let cd = inv.cd;
        let cells = axes!(|a| _mm256_srli_epi32::<2>(ijk[a]));
        const _: () = assert!(MACRO_CELL == 4, "the shift above divides by MACRO_CELL");
        let cell = _mm256_add_epi32(
            cells[0],
            _mm256_mullo_epi32(
                _mm256_set1_epi32(cd[0] as i32),
                _mm256_add_epi32(
                    cells[1],
                    _mm256_mullo_epi32(_mm256_set1_epi32(cd[1] as i32), cells[2]),
                ),
            ),
        );
        // Scalar loads, not a gather (see the module's notes).
        let mut ci = [0i32; LANES];
        _mm256_storeu_si256(ci.as_mut_ptr().cast(), cell);
        let mut dist = [0i32; LANES];
        for (d, &i) in dist.iter_mut().zip(&ci) {
            // SAFETY: positions are clamped to the cells, so each index is a cell.
            *d = i32::from(*c.distance.get_unchecked(i as usize));
        }
        let dist = _mm256_loadu_si256(dist.as_ptr().cast());
        let visible = _mm256_cmpeq_epi32(dist, _mm256_setzero_si256());
        (
            cells,
            dist,
            _mm256_movemask_ps(_mm256_castsi256_ps(visible)) as u8,
        )
    }
}

/// Sample `k` per lane of rays `(o, d, j)`: its position and cell, as `Ray::t`,
/// `Ray::at` and `Field::locate` compute them in the reference loop.
///
/// # Safety
/// The CPU must support AVX2 (inlined into [`composite_lanes`]).
#[inline(always)]
unsafe fn positions(
    inv: &Invariants,
    (o, d, j): ([__m256; 3], [__m256; 3], __m256),
    k: __m256i,
) -> ([__m256; 3], [__m256i; 3]) {
    // SAFETY: the caller runs with AVX2 (this function's contract).
    unsafe {
        let Invariants { dt, hi, zero, .. } = *inv;
        let t = _mm256_mul_ps(_mm256_add_ps(_mm256_cvtepi32_ps(k), j), dt);
        let p = axes!(|a| _mm256_add_ps(o[a], _mm256_mul_ps(d[a], t)));
        let ijk = axes!(|a| _mm256_cvttps_epi32(_mm256_min_ps(_mm256_max_ps(p[a], zero), hi[a])));
        (p, ijk)
    }
}

/// One sample per lane: its table entry, corner voxel, cell fractions, and which
/// lanes' entries have opacity.
struct Probe {
    li: [i32; LANES],
    base: [i32; LANES],
    fr: [__m256; 3],
    opaque: u8,
}

/// For eight samples at positions `p` in the cells `ijk` (clamped to `[0, dims-2]`):
/// their fractions in the cell, their corner voxels' indices, and their table
/// coordinates (`Lut::position` of the trilinear value), with the reference loop's
/// arithmetic.
///
/// # Safety
/// The CPU must support AVX2; `ijk` must be clamped as said.
#[inline(always)]
unsafe fn values_at(
    inv: &Invariants,
    p: [__m256; 3],
    ijk: [__m256i; 3],
) -> ([__m256; 3], [i32; LANES], __m256) {
    // SAFETY: this function's `# Safety` contract, which its callers uphold,
    // covers every unsafe operation below (CPU features, pointer ranges).
    unsafe {
        let Invariants {
            nx,
            sxy,
            zero,
            one,
            nxv,
            sxyv,
            lut_lo,
            lut_scale,
            half,
            lut_max,
            values,
            ..
        } = *inv;
        let fr = axes!(|a| {
            let t = _mm256_sub_ps(p[a], _mm256_cvtepi32_ps(ijk[a]));
            _mm256_min_ps(_mm256_max_ps(t, zero), one)
        });
        let mut base = [0i32; LANES];
        _mm256_storeu_si256(
            base.as_mut_ptr().cast(),
            _mm256_add_epi32(
                ijk[0],
                _mm256_add_epi32(
                    _mm256_mullo_epi32(ijk[1], nxv),
                    _mm256_mullo_epi32(ijk[2], sxyv),
                ),
            ),
        );
        // SAFETY: base + sxy + nx + 1 < nx ny nz, the cells being clamped.
        let mut ptrs = [values; LANES];
        for (p, &b) in ptrs.iter_mut().zip(&base) {
            *p = values.add(b as usize);
        }
        let (c000, c100) = row(ptrs, 0);
        let (c010, c110) = row(ptrs, nx);
        let (c001, c101) = row(ptrs, sxy);
        let (c011, c111) = row(ptrs, sxy + nx);
        let x00 = lerp(c000, c100, fr[0]);
        let x10 = lerp(c010, c110, fr[0]);
        let x01 = lerp(c001, c101, fr[0]);
        let x11 = lerp(c011, c111, fr[0]);
        let y0 = lerp(x00, x10, fr[1]);
        let y1 = lerp(x01, x11, fr[1]);
        let v = lerp(y0, y1, fr[2]);
        let x = _mm256_add_ps(_mm256_mul_ps(_mm256_sub_ps(v, lut_lo), lut_scale), half);
        (fr, base, _mm256_min_ps(_mm256_max_ps(x, zero), lut_max))
    }
}

/// Reads the samples at positions `p` (cells `ijk`, clamped) for every lane: the
/// reference loop's trilinear value and `Lut::index`.
///
/// # Safety
/// The CPU must support AVX2 (inlined into [`composite_lanes`]).
#[inline(always)]
unsafe fn probe(c: &Caster, inv: &Invariants, p: [__m256; 3], ijk: [__m256i; 3]) -> Probe {
    // SAFETY: this function's `# Safety` contract, which its callers uphold,
    // covers every unsafe operation below (CPU features, pointer ranges).
    unsafe {
        let (fr, base, uv) = values_at(inv, p, ijk);
        let mut li = [0i32; LANES];
        _mm256_storeu_si256(li.as_mut_ptr().cast(), _mm256_cvttps_epi32(uv));
        let mut opaque = 0u8;
        for (l, &i) in li.iter().enumerate() {
            // SAFETY: the index was clamped to the table.
            opaque |= *c.lut.opaque.get_unchecked(i as usize) << l;
        }
        Probe {
            li,
            base,
            fr,
            opaque,
        }
    }
}

/// The lane steps' values that are the same for every ray of a frame, computed once per
/// tile: the loop then keeps them in registers or on the stack. Read from the caster
/// at each step, they were reloaded and recomputed after every push of a kept sample
/// (a call that may reallocate, after which the compiler cannot assume the field
/// unchanged).
#[derive(Clone, Copy)]
struct Invariants {
    nx: usize,
    sxy: usize,
    cd: [usize; 3],
    dt: __m256,
    /// The last cell's corner per axis, `dims - 2`.
    hi: [__m256; 3],
    zero: __m256,
    one: __m256,
    nxv: __m256i,
    sxyv: __m256i,
    lut_lo: __m256,
    lut_scale: __m256,
    half: __m256,
    lut_max: __m256,
    values: *const f32,
}

impl Invariants {
    /// # Safety
    /// The CPU must support AVX2 (inlined into [`composite_lanes`]).
    #[inline(always)]
    unsafe fn new(c: &Caster) -> Invariants {
        // SAFETY: the caller runs with AVX2 (this function's contract).
        unsafe {
            let f = c.field;
            let [nx, ny, _] = f.dims;
            let sxy = nx * ny;
            Invariants {
                nx,
                sxy,
                cd: f.cell_dims,
                dt: _mm256_set1_ps(c.dt),
                hi: axes!(|a| _mm256_set1_ps((f.dims[a] - 2) as f32)),
                zero: _mm256_setzero_ps(),
                one: _mm256_set1_ps(1.0),
                // Every index fits in i32: MAX_FIELD_VOXELS is 2^28.
                nxv: _mm256_set1_epi32(nx as i32),
                sxyv: _mm256_set1_epi32(sxy as i32),
                lut_lo: _mm256_set1_ps(c.lut.lo),
                lut_scale: _mm256_set1_ps(c.lut.scale),
                half: _mm256_set1_ps(0.5),
                lut_max: _mm256_set1_ps((crate::preint::LUT_SIZE - 1) as f32),
                values: f.values.as_ptr(),
            }
        }
    }
}

/// Records a composited sample of the ray `id` whose opacity so far is `alpha` (voxel
/// `base`, fractions `t`, its segment's colour and opacity) and adds its opacity as
/// the reference loop does, in the same order. Returns whether the ray is now opaque
/// enough to stop.
#[inline(always)]
fn keep(
    kept: &mut Kept,
    (alpha, id): (&mut f32, u32),
    base: i32,
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
        ray: id,
    });
    stats.shaded += 1;
    *alpha += w;
    *alpha >= TERMINATION_OPACITY
}

/// Trilinear world gradients of the kept samples `r0 .. r0 + 8`, as
/// `Field::gradient_at` computes them, in component order.
///
/// # Safety
/// AVX2 must be available; the samples must come from clamped positions.
#[target_feature(enable = "avx2,fma")]
unsafe fn gradients(c: &Caster, kept: &Kept, r0: usize) -> [__m256; 3] {
    // SAFETY: this function's `# Safety` contract, which its callers uphold,
    // covers every unsafe operation below (CPU features, pointer ranges).
    unsafe {
        let f = c.field;
        let [nx, ny, _] = f.dims;
        let sxy = nx * ny;
        let data = f.gradients.as_ptr();
        let mut g = [_mm_setzero_ps(); LANES];
        for (j, gj) in g.iter_mut().enumerate() {
            let r = r0 + j;
            // One 128-bit load holds voxels (i, i+1) of a row: [gx, gy, gz, 0] twice, as
            // i16, converted exactly to f32.
            // SAFETY: the base is clamped to [0, dims-2] per axis, so base + sxy + nx + 1
            // is a voxel.
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
unsafe fn light(
    c: &Caster,
    kept: &mut Kept,
    views: &[Vec3],
    colors: &mut [[f32; 3]],
    batch: &mut ShadeBatch,
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
        // columns hold `padded` entries, so each store of eight at r0 stays inside.
        unsafe {
            let g = gradients(c, kept, r0);
            for (col, g) in batch.normal.iter_mut().zip(g) {
                _mm256_storeu_ps(col.as_mut_ptr().add(r0), g);
            }
        }
    }
    for (k, s) in kept.0.iter().enumerate() {
        let v = views[s.ray as usize];
        for a in 0..3 {
            batch.view[a][k] = v.get(a);
            batch.color[a][k] = s.rgba[a];
        }
    }
    c.shader.shade_gradients(batch);
    // In sample order, as the reference loop adds them.
    let [r, g, b] = &batch.color;
    for (k, s) in kept.0[..n].iter().enumerate() {
        let col = &mut colors[s.ray as usize];
        col[0] += s.weight * r[k];
        col[1] += s.weight * g[k];
        col[2] += s.weight * b[k];
    }
}
