//! Tricubic B-spline reconstruction ([`super::Filter::Tricubic`]) of the field's values
//! and its analytic gradient.
//!
//! The uniform cubic B-spline is C2 where trilinear interpolation is only C0, so a close
//! zoom no longer shows the voxel grid (the head CT's 1.5 mm slices as stair steps on
//! the skull), and its derivative is C1 where central differences interpolated
//! trilinearly are C0. It *approximates* rather than interpolates: at a voxel it gives
//! `(v[i-1] + 4 v[i] + v[i+1]) / 6` per axis, a slight blur (Catmull-Rom would
//! interpolate, but its negative lobes overshoot the samples, and a sample outside its
//! taps' range would break the macro-cell bounds below).
//!
//! A sample at `i + t` (cell `i`, fraction `t`) weighs the voxels `i-1 ..= i+2` per
//! axis (clamped to the volume, as a texture with clamp-to-edge addressing), with
//! non-negative weights that sum to one: the value lies within the (min, max) of its
//! 4^3 taps, so the macro cells' ranges over one voxel more on every side (the taps
//! reach one voxel beyond the cell) bound it (`prepare::cell_ranges`); the path
//! tracer's majorants and empty-space skipping stay upper bounds.
//!
//! Three evaluations, the same spline up to float rounding:
//! - inside a brick (the 4^3 taps in one brick's voxels: 14 of 16 cells per axis, two
//!   thirds of the samples), the 64 taps directly, separably (x, then y, then z), and
//!   the gradient from the same loads with the derivative weights;
//! - elsewhere (the taps span bricks or reach past the volume), the 64 taps gathered
//!   from the bricks holding them (`Field::gathered`, clamped to the volume), the
//!   same arithmetic;
//! - when a brick cannot be built (the cache is full), Sigg and Hadwiger's eight
//!   trilinear fetches ("Fast third-order texture filtering", GPU Gems 2, ch. 20,
//!   2005): per axis the pairs of taps `w0 v0 + w1 v1` are one linear fetch at
//!   `i - 1 + w1 / (w0 + w1)` weighted by `w0 + w1` (both weights are non-negative,
//!   so the position lies between the pair), so the spline is eight trilinear
//!   samples, each inside one brick ([`Field::value_at`]'s bricks need no wider
//!   apron). The derivative along an axis takes the derivative weights there (both of
//!   each pair have the same sign), so the gradient is 24 more.
//!
//! The scalar evaluations read the 64 taps once for the value and all three
//! derivatives. The AVX2 ray caster reads them too, as 16 rows of four per sample,
//! eight samples at a time, for the march's values and the kept samples' gradients
//! (`raycast::avx2::spline`; the same spline up to float rounding). The frame cost is
//! in docs/lighting.md, "Smooth reconstruction".

use crossbeam_epoch::Guard;

use super::brick::{BRICK, BRICK_ROW, BRICK_SLICE};
use super::{Field, Loc};
use glint_core::Vec3;

/// The cubic B-spline's weights of the taps at `-1, 0, 1, 2` from a cell's lower
/// corner, at fraction `t` (non-negative, summing to one).
#[inline(always)]
pub(crate) fn weights(t: f32) -> [f32; 4] {
    let s = 1.0 - t;
    let (t2, t3) = (t * t, t * t * t);
    [
        s * s * s / 6.0,
        (3.0 * t3 - 6.0 * t2 + 4.0) / 6.0,
        (-3.0 * t3 + 3.0 * t2 + 3.0 * t + 1.0) / 6.0,
        t3 / 6.0,
    ]
}

/// The derivatives of [`weights`] in `t` (the first two non-positive, the last two
/// non-negative, summing to zero).
#[inline(always)]
pub(crate) fn derivatives(t: f32) -> [f32; 4] {
    let s = 1.0 - t;
    [
        -0.5 * s * s,
        1.5 * t * t - 2.0 * t,
        -1.5 * t * t + t + 0.5,
        0.5 * t * t,
    ]
}

/// `sum w[a] x[a]`.
#[inline(always)]
fn dot(w: &[f32; 4], x: [f32; 4]) -> f32 {
    w[0] * x[0] + w[1] * x[1] + w[2] * x[2] + w[3] * x[3]
}

/// The spline's value and, with `GRAD`, its index-space gradient from the 64 taps
/// `at(a + 4 b + 16 c)` (tap `a, b, c` at offsets `a - 1, b - 1, c - 1` from the cell's
/// corner), fractions `t`.
#[inline(always)]
fn block<const GRAD: bool>(at: impl Fn(usize) -> f32, t: [f32; 3]) -> (f32, [f32; 3]) {
    let [wx, wy, wz] = t.map(weights);
    let [dx, dy, dz] = if GRAD {
        t.map(derivatives)
    } else {
        [[0.0; 4]; 3]
    };
    // Along x: each of the 16 rows to its value (and its x derivative).
    let mut rows = [[0.0f32; 4]; 4];
    let mut rows_dx = [[0.0f32; 4]; 4];
    for c in 0..4 {
        for b in 0..4 {
            let o = 4 * b + 16 * c;
            let x = [at(o), at(o + 1), at(o + 2), at(o + 3)];
            rows[c][b] = dot(&wx, x);
            if GRAD {
                rows_dx[c][b] = dot(&dx, x);
            }
        }
    }
    // Along y, then z.
    let slices = rows.map(|r| dot(&wy, r));
    let value = dot(&wz, slices);
    if !GRAD {
        return (value, [0.0; 3]);
    }
    let gx = dot(&wz, rows_dx.map(|r| dot(&wy, r)));
    let gy = dot(&wz, rows.map(|r| dot(&dy, r)));
    let gz = dot(&dz, slices);
    (value, [gx, gy, gz])
}

impl Field {
    /// The brick offset of the 4^3 taps of `loc` when they all lie in one built brick
    /// (and inside the volume): the pointer offset of tap (0, 0, 0).
    #[inline(always)]
    fn cubic_block(&self, loc: &Loc, guard: &Guard) -> Option<usize> {
        let inside = (0..3).all(|a| {
            let (i, l) = (loc.ijk[a], loc.ijk[a] & (BRICK - 1));
            l >= 1 && l + 2 <= BRICK && i + 2 < self.dims[a]
        });
        if !inside {
            return None;
        }
        let (b, coords, local) = self.brick_of(loc);
        let o = self.cache.offset(b, coords, &self.recipe, guard)?;
        Some(o as usize + local - 1 - BRICK_ROW - BRICK_SLICE)
    }

    /// The tricubic B-spline value at a located sample.
    #[inline(always)]
    pub(crate) fn cubic_value_at(&self, loc: &Loc, guard: &Guard) -> f32 {
        match self.cubic_block(loc, guard) {
            Some(base) => block::<false>(|o| self.tap(base, o), loc.t).0,
            None => match self.gathered(loc, guard) {
                Some(taps) => block::<false>(|o| taps[o], loc.t).0,
                None => self.fetched(loc, guard, [false; 3]),
            },
        }
    }

    /// The tricubic B-spline's analytic world gradient at a located sample (index-space
    /// derivatives mapped by the inverse transpose of the affine's 3x3 part): its three
    /// derivatives from one read of the 64 taps.
    #[inline(always)]
    pub(crate) fn cubic_gradient_at(&self, loc: &Loc, guard: &Guard) -> Vec3 {
        let g = match self.cubic_block(loc, guard) {
            Some(base) => block::<true>(|o| self.tap(base, o), loc.t).1,
            None => match self.gathered(loc, guard) {
                Some(taps) => block::<true>(|o| taps[o], loc.t).1,
                None => [
                    self.fetched(loc, guard, [true, false, false]),
                    self.fetched(loc, guard, [false, true, false]),
                    self.fetched(loc, guard, [false, false, true]),
                ],
            },
        };
        let m = &self.recipe.to_world_gradient;
        let row = |r: usize| m[r][0] * g[0] + m[r][1] * g[1] + m[r][2] * g[2];
        Vec3::new(row(0), row(1), row(2))
    }

    /// The 64 taps of `loc` (`a + 4 b + 16 c`) when they span bricks or reach past the
    /// volume: each tap's voxel clamped to the volume (clamp-to-edge, as the eight
    /// fetches clamp), read from the brick holding it. The taps reach at most two
    /// bricks per axis, so at most eight slot look-ups. `None` when a brick could not
    /// be built (the cache is full of bricks in use).
    #[cold]
    #[inline(never)]
    fn gathered(&self, loc: &Loc, guard: &Guard) -> Option<[f32; 64]> {
        let bd = self.brick_dims;
        // Per axis and tap: its brick along the axis, its voxel in the brick, and
        // whether the brick is the first tap's.
        let mut brick = [[0usize; 4]; 3];
        let mut local = [[0usize; 4]; 3];
        let mut other = [[0usize; 4]; 3];
        for a in 0..3 {
            for n in 0..4 {
                let v = (loc.ijk[a] + n).saturating_sub(1).min(self.dims[a] - 1);
                // Voxel `v` lies in brick `v / BRICK` or, at the volume's far face, as
                // the last brick's apron.
                let b = (v >> super::brick::BRICK_SHIFT).min(bd[a] - 1);
                brick[a][n] = b;
                local[a][n] = v - b * BRICK;
                other[a][n] = usize::from(b != brick[a][0]);
            }
        }
        let mut slots = [None::<usize>; 8];
        let values = self.cache.values();
        let mut taps = [0.0f32; 64];
        for c in 0..4 {
            for b in 0..4 {
                for a in 0..4 {
                    let key = other[0][a] + 2 * other[1][b] + 4 * other[2][c];
                    let off = match slots[key] {
                        Some(o) => o,
                        None => {
                            let coords = [brick[0][a], brick[1][b], brick[2][c]];
                            let bi = coords[0] + bd[0] * (coords[1] + bd[1] * coords[2]);
                            let o = self.cache.offset(bi, coords, &self.recipe, guard)? as usize;
                            slots[key] = Some(o);
                            o
                        }
                    };
                    let at =
                        off + local[0][a] + BRICK_ROW * local[1][b] + BRICK_SLICE * local[2][c];
                    // SAFETY: the slot is built and valid while the guard lives; the
                    // voxel's place is inside the brick (local <= BRICK per axis).
                    taps[a + 4 * b + 16 * c] = unsafe { *values.add(at) };
                }
            }
        }
        Some(taps)
    }

    /// Tap `o` (`a + 4 b + 16 c`) of the block at slot offset `base`.
    #[inline(always)]
    fn tap(&self, base: usize, o: usize) -> f32 {
        let (a, b, c) = (o & 3, (o >> 2) & 3, o >> 4);
        // SAFETY: `cubic_block` checked that the block lies in a built slot, valid
        // while the guard lives.
        unsafe {
            *self
                .cache
                .values()
                .add(base + a + BRICK_ROW * b + BRICK_SLICE * c)
        }
    }

    /// The spline (or, along the axes in `derive`, its derivative) at `loc` from eight
    /// trilinear fetches (Sigg and Hadwiger 2005; see the module's notes).
    #[cold]
    #[inline(never)]
    pub(super) fn fetched(&self, loc: &Loc, guard: &Guard, derive: [bool; 3]) -> f32 {
        // Per axis: the two fetch positions and their weights.
        let pairs: [[(f32, f32); 2]; 3] = [0, 1, 2].map(|a| {
            let t = loc.t[a];
            let w = if derive[a] {
                derivatives(t)
            } else {
                weights(t)
            };
            let i = loc.ijk[a] as f32;
            let (g0, g1) = (w[0] + w[1], w[2] + w[3]);
            [(i - 1.0 + w[1] / g0, g0), (i + 1.0 + w[3] / g1, g1)]
        });
        let mut sum = 0.0;
        for (z, wz) in pairs[2] {
            for (y, wy) in pairs[1] {
                for (x, wx) in pairs[0] {
                    let v = self.linear_value_at(&self.locate(Vec3::new(x, y, z)), guard);
                    sum += wx * wy * wz * v;
                }
            }
        }
        sum
    }
}
