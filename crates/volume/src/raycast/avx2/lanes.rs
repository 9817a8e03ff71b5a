//! The state of eight rays marched one per lane, and their steps.

use std::arch::x86_64::*;

use crossbeam_epoch::Guard;

use super::*;

/// The state of eight rays marched one per lane ([`composite_lanes`]), by component.
#[derive(Default)]
pub(super) struct Lanes {
    /// Bit `l`: lane `l` holds a ray.
    pub(super) live: u8,
    pub(super) o: [[f32; LANES]; 3],
    pub(super) d: [[f32; LANES]; 3],
    /// [`Ray::inv_dk`].
    pub(super) inv_dk: [[f32; LANES]; 3],
    /// [`Ray::face_up`], as all-ones or zero.
    pub(super) up: [[i32; LANES]; 3],
    pub(super) j: [f32; LANES],
    /// Next sample, and the last.
    pub(super) k: [i32; LANES],
    pub(super) k1: [i32; LANES],
    pub(super) alpha: [f32; LANES],
    pub(super) id: [u32; LANES],
    /// Pre-integrated sampling: the last sample read and its table coordinate (the
    /// front of the next segment; `i32::MIN` for none), and the segment cache.
    pub(super) prev_k: [i32; LANES],
    pub(super) prev_u: [f32; LANES],
    pub(super) last: [Last; LANES],
    /// A brick could not be built (the cache is full of bricks in use): the tile is
    /// given up and rendered by the reference loop.
    pub(super) failed: bool,
    /// The lanes' last bricks (per fetch of the tricubic filter as well).
    pub(super) memo: Memos,
}

impl Lanes {
    /// Starts `ray` in lane `l`.
    #[inline(always)]
    pub(super) fn set(&mut self, l: usize, ray: &LaneRay) {
        for a in 0..3 {
            self.o[a][l] = ray.o[a];
            self.d[a][l] = ray.d[a];
            self.inv_dk[a][l] = ray.inv_dk[a];
            self.up[a][l] = ray.up[a];
        }
        self.j[l] = ray.j;
        self.k[l] = ray.k0;
        self.k1[l] = ray.k1;
        self.alpha[l] = 0.0;
        self.id[l] = ray.id;
        self.prev_k[l] = i32::MIN;
        self.last[l] = Last::default();
        self.live |= 1 << l;
    }

    /// The lanes' rays `(o, d, j)`, next samples and last samples, as vectors.
    ///
    /// # Safety
    /// The CPU must support AVX2 (inlined into [`composite_lanes`]).
    #[inline(always)]
    pub(super) unsafe fn rays(&self) -> (([__m256; 3], [__m256; 3], __m256), __m256i, __m256i) {
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
    pub(super) unsafe fn advance(&mut self, k_next: __m256i, k1: __m256i, ended: u8) -> u8 {
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
    pub(super) unsafe fn step<const CUBIC: bool>(
        &mut self,
        c: &Caster,
        inv: &Invariants,
        kept: &mut Kept,
        stats: &mut RenderStats,
        guard: &Guard,
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
                let Some(first) =
                    probe::<CUBIC>(c, inv, (p, ijk), (samples, &mut self.memo), guard)
                else {
                    self.failed = true;
                    return 0;
                };
                ended |= self.keep_hits(c.lut, kept, samples & first.opaque, &first, stats);
                if second != 0 {
                    let (p2, ijk2) = positions(inv, ray, k_plus);
                    let Some(next) =
                        probe::<CUBIC>(c, inv, (p2, ijk2), (second, &mut self.memo), guard)
                    else {
                        self.failed = true;
                        return 0;
                    };
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
    /// sample before ([`crate::classification::preint`]). Where sample k lies in a visible cell, the
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
    pub(super) unsafe fn segment_step<const CUBIC: bool>(
        &mut self,
        c: &Caster,
        inv: &Invariants,
        kept: &mut Kept,
        stats: &mut RenderStats,
        guard: &Guard,
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
                let Some(first) =
                    reads_at::<CUBIC>(c, inv, (p0, ijk0, first_k), (reads, &mut self.memo), guard)
                else {
                    self.failed = true;
                    return 0;
                };
                let second = if seconds != 0 {
                    match reads_at::<CUBIC>(
                        c,
                        inv,
                        (p1, ijk1, second_k),
                        (seconds, &mut self.memo),
                        guard,
                    ) {
                        Some(r) => r,
                        None => {
                            self.failed = true;
                            return 0;
                        }
                    }
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
    pub(super) fn keep_segments(
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
    pub(super) fn read(
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
            (r.base[l], r.brick[l]),
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
    pub(super) unsafe fn keep_hits(
        &mut self,
        lut: &crate::classification::Lut,
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
                    (probe.base[l], probe.brick[l]),
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
    pub(super) unsafe fn leap(
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
