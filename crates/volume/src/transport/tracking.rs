//! Free paths and transmittance through the medium: delta tracking (Woodcock et al.,
//! "Techniques used in the GEM code for Monte Carlo neutronics calculations in
//! reactors and other systems of complex geometry", 1965) and ratio tracking (Novák,
//! Selle and Jarosz, "Residual ratio tracking for estimating attenuation in
//! participating media", SIGGRAPH Asia 2014), each against a piecewise-constant
//! majorant: the macro-cell grid walked cell by cell (Amanatides and Woo, "A fast voxel
//! traversal algorithm for ray tracing", Eurographics 1987), as pbrt-v4's
//! `DDAMajorantIterator` (src/pbrt/media.h) walks its grid. Empty cells cost one step
//! of the walk; a cell's tentative collisions come at its own majorant's rate.

use glint_core::Vec3;

use super::rng::Rng;
use crate::classification::Medium;
use crate::clip::IndexClip;
use crate::field::{clip_ray, Field, MACRO_CELL};

/// A ray in the field's index space: `o + d t`, `t` in mm (`d` is in index units per
/// mm, as the ray caster's rays are).
#[derive(Clone, Copy, Debug)]
pub(crate) struct IndexRay {
    pub(crate) o: Vec3,
    pub(crate) d: Vec3,
}

impl IndexRay {
    /// The index-space ray of the world ray from `origin` along the unit `dir`.
    pub(crate) fn from_world(field: &Field, origin: Vec3, dir: Vec3) -> IndexRay {
        let w = |v: Vec3| [v.x as f64, v.y as f64, v.z as f64];
        let o = field.world_to_index(w(origin));
        IndexRay {
            o: Vec3::new(o[0] as f32, o[1] as f32, o[2] as f32),
            d: field.index_offset(o, w(origin + dir)),
        }
    }

    /// The point at `t` mm.
    #[inline(always)]
    pub(crate) fn at(&self, t: f32) -> Vec3 {
        self.o + self.d * t
    }

    /// Where the ray is inside the box of voxel centres `[0, dims-1]`, clipped to
    /// `[t0, t1]`: `None` when it misses.
    pub(crate) fn clip(&self, dims: [usize; 3], t0: f32, t1: f32) -> Option<(f32, f32)> {
        let hi = dims.map(|n| (n - 1) as f32);
        clip_ray(self.o, self.d, ([0.0; 3], hi), (t0, t1)).filter(|(a, b)| a < b)
    }
}

/// The macro cells a clipped ray crosses, in order, with the ray parameters where it
/// enters and leaves each.
pub(crate) struct CellWalk {
    cell: [i32; 3],
    step: [i32; 3],
    /// Parameter at which the ray crosses the next cell face along each axis.
    next: [f32; 3],
    delta: [f32; 3],
    t: f32,
    end: f32,
    dims: [i32; 3],
}

impl CellWalk {
    /// The walk of `ray` over `[t0, t1]` (inside the volume's box) through a grid of
    /// `dims` cells of [`MACRO_CELL`] voxels.
    pub(crate) fn new(ray: &IndexRay, t0: f32, t1: f32, dims: [usize; 3]) -> CellWalk {
        let b = MACRO_CELL as f32;
        let p = ray.at(t0);
        let dims = dims.map(|d| d as i32);
        let mut walk = CellWalk {
            cell: [0; 3],
            step: [0; 3],
            next: [f32::INFINITY; 3],
            delta: [f32::INFINITY; 3],
            t: t0,
            end: t1,
            dims,
        };
        for (a, &n) in dims.iter().enumerate() {
            let c = ((p.get(a) / b).floor() as i32).clamp(0, n - 1);
            walk.cell[a] = c;
            let (o, d) = (ray.o.get(a), ray.d.get(a));
            if d > 0.0 {
                walk.step[a] = 1;
                walk.next[a] = ((c + 1) as f32 * b - o) / d;
                walk.delta[a] = b / d;
            } else if d < 0.0 {
                walk.step[a] = -1;
                walk.next[a] = (c as f32 * b - o) / d;
                walk.delta[a] = -b / d;
            }
        }
        walk
    }

    /// The next cell (linear index) and the parameters where the ray enters and
    /// leaves it; `None` past the end.
    #[inline(always)]
    pub(crate) fn next_cell(&mut self) -> Option<(usize, f32, f32)> {
        if self.t >= self.end {
            return None;
        }
        let a = if self.next[0] <= self.next[1] && self.next[0] <= self.next[2] {
            0
        } else if self.next[1] <= self.next[2] {
            1
        } else {
            2
        };
        let [cx, cy, cz] = self.cell;
        let [dx, dy, _] = self.dims;
        let idx = (cx + dx * (cy + dy * cz)) as usize;
        let enter = self.t;
        let leave = self.next[a].min(self.end).max(enter);
        self.t = leave;
        self.cell[a] += self.step[a];
        self.next[a] += self.delta[a];
        if self.cell[a] < 0 || self.cell[a] >= self.dims[a] {
            self.end = leave;
        }
        Some((idx, enter, leave))
    }
}

/// Transmittance below which ratio tracking plays Russian roulette (survival 1/2,
/// weight doubled): unbiased, and it stops paths through dense matter early.
const ROULETTE_BELOW: f32 = 0.1;

/// The medium of a field: what tracking reads.
#[derive(Clone, Copy)]
pub(crate) struct Tracker<'a> {
    pub(crate) field: &'a Field,
    pub(crate) medium: &'a Medium,
    /// The frame's clip: what it cuts away is empty (no collision, no extinction).
    pub(crate) clip: Option<&'a IndexClip>,
}

impl Tracker<'_> {
    /// The part of `[t0, t1]` where `ray` is inside the volume's box and kept by the
    /// clip: the majorant walk covers nothing else (`None` when that is empty).
    #[inline]
    fn kept(&self, ray: &IndexRay, t0: f32, t1: f32) -> Option<(f32, f32)> {
        let (t0, t1) = ray.clip(self.field.dims(), t0, t1)?;
        match self.clip {
            None => Some((t0, t1)),
            Some(c) => Some(c.interval(ray.o, ray.d, (t0, t1))).filter(|(a, b)| a < b),
        }
    }

    /// Delta tracking along `ray` over `[t0, t1]`: the parameter of the first real
    /// collision, drawn with density `σ(t) exp(-∫σ)`, or `None` when the ray leaves
    /// `[t0, t1]` first (probability: the transmittance).
    pub(crate) fn free_path(&self, ray: &IndexRay, t0: f32, t1: f32, rng: &mut Rng) -> Option<f32> {
        let (t0, t1) = self.kept(ray, t0, t1)?;
        let mut walk = CellWalk::new(ray, t0, t1, self.medium.cell_dims);
        while let Some((cell, a, b)) = walk.next_cell() {
            let mu = self.medium.majorant[cell];
            if mu <= 0.0 {
                continue;
            }
            let mut t = a;
            loop {
                t += rng.exponential() / mu;
                if t >= b {
                    break;
                }
                let s = self.medium.sigma_at(self.field, ray.at(t));
                if rng.uniform() * mu < s {
                    return Some(t);
                }
            }
        }
        None
    }

    /// Ratio tracking along `ray` over `[t0, t1]`: an unbiased estimate of the
    /// transmittance `exp(-∫σ)`, in `[0, 1]` up to the roulette's doubling.
    pub(crate) fn transmittance(&self, ray: &IndexRay, t0: f32, t1: f32, rng: &mut Rng) -> f32 {
        let Some((t0, t1)) = self.kept(ray, t0, t1) else {
            return 1.0;
        };
        let mut walk = CellWalk::new(ray, t0, t1, self.medium.cell_dims);
        let mut tr = 1.0f32;
        while let Some((cell, a, b)) = walk.next_cell() {
            let mu = self.medium.majorant[cell];
            if mu <= 0.0 {
                continue;
            }
            let mut t = a;
            loop {
                t += rng.exponential() / mu;
                if t >= b {
                    break;
                }
                let s = self.medium.sigma_at(self.field, ray.at(t));
                tr *= 1.0 - (s / mu).min(1.0);
                if tr <= 0.0 {
                    return 0.0;
                }
                if tr < ROULETTE_BELOW {
                    if rng.uniform() < 0.5 {
                        return 0.0;
                    }
                    tr *= 2.0;
                }
            }
        }
        tr
    }
}
