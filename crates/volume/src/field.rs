//! The volume prepared for ray casting: its samples (kept in their stored type by the
//! [`Source`]), the voxel-to-world transform and its inverse, a macro-cell grid of
//! value ranges for empty-space skipping, and the reconstruction values and world
//! gradients in bricks built on first use ([`brick`]) and kept in a bounded cache
//! ([`cache`]).
//!
//! Building a field makes one streaming pass over the volume ([`prepare`]: value range,
//! macro cells, the gradients' quantisation step, robust range); a brick's values and
//! gradients are computed only when a ray, a classification or a caller reads a sample
//! in it, with the same arithmetic as a whole-volume pass, so images are bit for bit
//! those of a field that computed everything up front.

use std::cell::RefCell;
use std::path::Path;
use std::sync::atomic::{AtomicU64, Ordering};
use std::sync::{Arc, OnceLock};

use crossbeam_epoch::Guard;
use glint_io::zarr::Stream;
use glint_io::{IoError, ReadOptions, Volume};

use glint_core::RenderError;
use glint_core::Timings;
use glint_core::Vec3;
use glint_io::affine::{inverse3, linear_part, mul3, transpose3, Mat3};

pub(crate) mod brick;
mod budget;
pub(crate) mod cache;
mod cubic;
mod filter;
mod prepare;
mod source;
#[cfg(test)]
mod tests;

use brick::{brick_dims, Recipe, BRICK, BRICK_ROW, BRICK_SHIFT, BRICK_SLICE, BRICK_VOXELS};
pub use budget::{memory_limit, set_memory_limit, MIN_BRICK_SLOTS, PROCESS_OVERHEAD};
use cache::BrickCache;
pub use source::Source;

/// Largest voxel count the caster accepts: 2^33 (a 2048 x 2048 x 2048 volume). Memory,
/// not this, bounds what renders: the samples stay in their stored type and bricks are
/// built where rays go ([`memory_limit`]).
pub const MAX_FIELD_VOXELS: usize = 1 << 33;

/// Edge of a macro cell in voxels (Levoy 1990, "Efficient ray tracing of volume data",
/// skips empty space with a pyramid of such blocks; here two levels: cells of 4 voxels
/// and blocks of 4^3 cells).
pub const MACRO_CELL: usize = 4;

/// Where a sample falls: the trilinear cell's lower corner and the fractions inside the
/// cell.
#[derive(Clone, Copy, Debug)]
pub(crate) struct Loc {
    pub ijk: [usize; 3],
    pub t: [f32; 3],
}

/// Share of the memory limit ([`budget::memory_limit`]) an OME-Zarr level's chunk cache
/// may take at most: a quarter, the rest left to the bricks and other fields.
const CHUNK_CACHE_SHARE: u64 = 4;

/// Opens level [`ReadOptions::level`] of the OME-Zarr store at `path` as a source
/// that decodes chunks as bricks need them ([`Stream`]): its chunk cache holds two
/// layers of chunks per rayon thread, at most a quarter of the memory limit.
pub fn open_zarr(path: &Path, options: &ReadOptions) -> Result<Stream, IoError> {
    Stream::open(
        path,
        options,
        budget::memory_limit() / CHUNK_CACHE_SHARE,
        rayon::current_num_threads(),
    )
}

/// Fields built so far, to tell their bricks apart in the per-thread fallback cache.
static FIELDS: AtomicU64 = AtomicU64::new(0);

/// A scalar field on a regular grid with gradients, built lazily in bricks.
///
/// Voxel `(i, j, k)` has its physical value (prefiltered, [`Prefilter`]) and its
/// gradient in world units (value per mm, RAS+), by central differences on the grid
/// (one-sided at the faces) mapped through the inverse transpose of the affine's linear
/// part. Gradients are stored as 16-bit integers times one scale for the volume (the
/// largest component maps to 32767), with an error below 1e-4 of the largest gradient
/// (VTK's ray casters keep 16 bits for the whole direction and 8 for the magnitude).
pub struct Field {
    pub(crate) dims: [usize; 3],
    /// World gradient per integer step of the stored gradients.
    pub(crate) gradient_scale: f32,
    /// Voxel index to world (3x3 part and translation).
    pub(crate) to_world: Mat3,
    pub(crate) origin: [f64; 3],
    /// World to voxel index (3x3 part).
    pub(crate) to_index: Mat3,
    pub(crate) min_spacing: f64,
    pub(crate) range: (f32, f32),
    /// [`Field::robust_range`].
    pub(crate) robust: (f32, f32),
    /// Macro-cell grid dimensions and per-cell (min, max) of the values a sample in
    /// the cell can interpolate.
    pub(crate) cell_dims: [usize; 3],
    pub(crate) cells: Vec<(f32, f32)>,
    /// Bricks along each axis.
    pub(crate) brick_dims: [usize; 3],
    /// How bricks are built, and where they are kept.
    pub(crate) recipe: Recipe,
    pub(crate) cache: BrickCache,
    /// How long each step of building took.
    timings: Timings,
    /// The filter applied to the values.
    prefilter: Prefilter,
    /// How samples are reconstructed between voxels.
    filter: Filter,
    /// The trilinear macro cells while [`Field::cells`] holds the tricubic ones.
    linear_cells: Option<Vec<(f32, f32)>>,
    /// [`Field::values`], made on first call.
    whole: OnceLock<Vec<f32>>,
    id: u64,
    _reservation: budget::Reservation,
}

/// How the samples are filtered before trilinear reconstruction (a scene's
/// `prefilter`).
#[derive(
    Clone,
    Copy,
    Debug,
    Default,
    PartialEq,
    Eq,
    Hash,
    serde::Serialize,
    serde::Deserialize,
    strum::EnumString,
    strum::IntoStaticStr,
    strum::Display,
    strum::VariantNames,
    strum::VariantArray,
)]
#[serde(rename_all = "lowercase")]
#[strum(serialize_all = "lowercase", ascii_case_insensitive, parse_err_ty = glint_core::RenderError, parse_err_fn = glint_core::unknown_name::<Self>)]
pub enum Prefilter {
    /// The values as stored: trilinear interpolation of the data itself.
    None,
    /// A `[1 2 1] / 4` binomial along each axis (a Gaussian of sigma 0.71 voxel, up to
    /// its tails) before gradients and interpolation. Trilinear interpolation is only
    /// C0: where a surface crosses the voxel grid at a shallow angle, its kinks at the
    /// voxel faces draw contour lines one voxel apart ("wood grain" rings, issue 12).
    /// Low-passing the data first shrinks the kinks with the second differences they
    /// come from, at the cost of a slight blur, the trade of approximating
    /// reconstruction filters such as the cubic B-spline (Marschner and Lobb 1994, "An
    /// evaluation of reconstruction filters for volume rendering"), for the price of
    /// one pass over the volume at load time and nothing per frame.
    #[default]
    Binomial,
}

impl Prefilter {
    /// Every prefilter, the default first.
    pub const ALL: &'static [Prefilter] = <Prefilter as strum::VariantArray>::VARIANTS;

    /// The names users type, in the order of [`Prefilter::ALL`].
    pub const NAMES: &'static [&'static str] = <Prefilter as strum::VariantNames>::VARIANTS;

    /// The name scenes and the command line use.
    pub fn name(self) -> &'static str {
        self.into()
    }
}

impl glint_lobe::names::Named for Prefilter {
    const WHAT: &'static str = "prefilter";
}

/// How the field is reconstructed between voxels (a scene's `filter`), for its values
/// and its gradients, in every lighting model.
#[derive(
    Clone,
    Copy,
    Debug,
    Default,
    PartialEq,
    Eq,
    Hash,
    serde::Serialize,
    serde::Deserialize,
    strum::EnumString,
    strum::IntoStaticStr,
    strum::Display,
    strum::VariantNames,
    strum::VariantArray,
)]
#[serde(rename_all = "lowercase")]
#[strum(serialize_all = "lowercase", ascii_case_insensitive, parse_err_ty = glint_core::RenderError, parse_err_fn = glint_core::unknown_name::<Self>)]
pub enum Filter {
    /// Trilinear interpolation of the eight voxels around a sample, and of their
    /// gradients (central differences): C0, so a close zoom shows the voxel grid.
    #[default]
    Trilinear,
    /// The uniform cubic B-spline of the 4^3 voxels around a sample (Sigg and
    /// Hadwiger, "Fast third-order texture filtering", GPU Gems 2, ch. 20), and its
    /// analytic gradient: C2, no stair steps at a close zoom. It smooths (it does not
    /// pass through the samples: a lone bright voxel comes out at 8/27 of its
    /// height), and stays within the range of its taps (no overshoot).
    Tricubic,
}

impl Filter {
    /// Every filter, the default first.
    pub const ALL: &'static [Filter] = <Filter as strum::VariantArray>::VARIANTS;

    /// The names users type, in the order of [`Filter::ALL`].
    pub const NAMES: &'static [&'static str] = <Filter as strum::VariantNames>::VARIANTS;

    /// The name scenes and the command line use.
    pub fn name(self) -> &'static str {
        self.into()
    }

    /// Whether this is the default, trilinear (a scene leaves it out of its JSON).
    pub fn is_trilinear(&self) -> bool {
        *self == Filter::Trilinear
    }
}

impl glint_lobe::names::Named for Filter {
    const WHAT: &'static str = "filter";
}

impl Field {
    /// Prepares `volume` for rendering, its values as stored ([`Prefilter::None`]; a
    /// scene's default is [`Prefilter::Binomial`]). The samples are copied; see
    /// [`Field::shared`] to share them.
    pub fn new(volume: &Volume) -> Result<Field, RenderError> {
        Field::with_prefilter(volume, Prefilter::None)
    }

    /// Prepares `volume` for rendering (a copy of its samples; [`Field::shared`] keeps
    /// the caller's).
    ///
    /// Errors when a dimension is below 2 (nothing to interpolate between), the volume
    /// exceeds [`MAX_FIELD_VOXELS`] or the memory limit ([`memory_limit`]), or the affine
    /// is singular or not finite. NaN samples are replaced by the volume's minimum.
    pub fn with_prefilter(volume: &Volume, prefilter: Prefilter) -> Result<Field, RenderError> {
        Field::shared(Arc::new(volume.clone()), prefilter)
    }

    /// [`Field::with_prefilter`] of a shared volume: the field reads its samples, in
    /// their stored type, when it builds bricks; no copy is made.
    pub fn shared(volume: Arc<Volume>, prefilter: Prefilter) -> Result<Field, RenderError> {
        checked_count(volume.dims, volume.samples.len())?;
        Field::from_source(volume, prefilter, &|_, _| {})
    }

    /// A field of any [`Source`]. `progress` is called with the slices done and the
    /// slices in all during the pass over the volume (from worker threads).
    pub fn from_source(
        source: Arc<dyn Source>,
        prefilter: Prefilter,
        progress: &(dyn Fn(u64, u64) + Sync),
    ) -> Result<Field, RenderError> {
        let dims = source.dims();
        checked_count(dims, None)?;
        let (to_world, origin, to_index, min_spacing) = placement(&source.affine())?;
        let brick_dims = brick_dims(dims);
        let bricks: usize = brick_dims.iter().product();
        let cell_count: usize = dims.iter().map(|d| (d - 1).div_ceil(MACRO_CELL)).product();
        // Samples, macro cells (8 bytes each), the page table (4 per brick) and the
        // classification's distance map (1 per cell) with its two working arrays while
        // it is computed (the visible cells, the padded distances: 1 per cell each;
        // `raycast/cells.rs`).
        let fixed = source.resident_bytes() + 11 * cell_count as u64 + 4 * bricks as u64;
        let pass = prepare::pass_bytes(dims, rayon::current_num_threads());
        let (reservation, slots) = budget::reserve(fixed, pass, bricks)?;
        // Gradient in index space g_idx; world gradient = A^-T g_idx (chain rule on
        // f(x) = f_idx(A^-1 (x - o))).
        let grad_to_world = transpose3(&to_index).map(|row| row.map(|x| x as f32));
        let mut recipe = Recipe {
            source: source.clone(),
            dims,
            prefilter,
            fill: None,
            to_world_gradient: grad_to_world,
            inv_scale: 1.0,
            axis_aligned: None,
        };
        let mut timings = Timings::default();
        let total = dims[2] as u64;
        let done = AtomicU64::new(0);
        let tick = |n: u64| progress(done.fetch_add(n, Ordering::Relaxed) + n, total);
        // The pass measures the range itself; a source that holds NaN or infinities
        // (they are replaced by the minimum before filtering, so the minimum must be
        // known first) takes a pass for its finite range and the pass again. Float
        // volumes that could hold them but do not (most) read the volume once.
        let mut p = timings.time("field: prepare", || prepare::prepare(&recipe, None, &tick))?;
        if !p.finite {
            let r = timings.time("field: range", || prepare::finite_range(&recipe))?;
            recipe.fill = Some(r.0);
            done.store(0, Ordering::Relaxed);
            p = timings.time("field: prepare", || {
                prepare::prepare(&recipe, Some(r), &tick)
            })?;
        }
        let gradient_scale = filter::gradient_scale(p.largest);
        recipe.inv_scale = 1.0 / gradient_scale;
        // Values (prefiltered: within the range) below a quarter of f32's largest have
        // finite differences, which the diagonal bricks' gradients need.
        let bounded = p.range.0.abs().max(p.range.1.abs()) <= f32::MAX / 4.0;
        recipe.axis_aligned = prepare::diagonal(&recipe.to_world_gradient).filter(|_| bounded);
        let cache = BrickCache::new(bricks, slots).ok_or_else(|| {
            RenderError::Volume(format!("cannot allocate a pool of {slots} bricks"))
        })?;
        if let Some(problem) = source.problem() {
            return Err(RenderError::Volume(problem));
        }
        Ok(Field {
            timings,
            prefilter,
            filter: Filter::Trilinear,
            linear_cells: None,
            dims,
            gradient_scale,
            to_world,
            origin,
            to_index,
            min_spacing,
            range: p.range,
            robust: p.robust,
            cell_dims: p.cell_dims,
            cells: p.cells,
            brick_dims,
            recipe,
            cache,
            whole: OnceLock::new(),
            id: FIELDS.fetch_add(1, Ordering::Relaxed),
            _reservation: reservation,
        })
    }

    /// How long the steps of building took (the range when the source may hold NaN, the
    /// pass over the volume), for `--timings` reports.
    pub fn timings(&self) -> &Timings {
        &self.timings
    }

    /// The filter applied to the values before gradients and interpolation.
    pub fn prefilter(&self) -> Prefilter {
        self.prefilter
    }

    /// How samples are reconstructed between voxels.
    pub fn filter(&self) -> Filter {
        self.filter
    }

    /// This field reconstructed with `filter`: the same bricks (nothing is rebuilt);
    /// for [`Filter::Tricubic`] the macro cells' ranges are taken over one voxel more
    /// on every side (a tricubic sample reads one voxel beyond its cell; a pass over
    /// the source), so what bounds the values (empty-space skipping,
    /// the path tracer's majorants) still does.
    pub fn with_filter(mut self, filter: Filter) -> Field {
        if filter == self.filter {
            return self;
        }
        match filter {
            Filter::Tricubic => {
                let cubic = prepare::cell_ranges(&self.recipe, 1);
                self.linear_cells = Some(std::mem::replace(&mut self.cells, cubic));
            }
            Filter::Trilinear => {
                if let Some(cells) = self.linear_cells.take() {
                    self.cells = cells;
                }
            }
        }
        self.filter = filter;
        self
    }

    /// The reconstruction values (the samples after the prefilter, NaN replaced by the
    /// minimum), i fastest: e.g. for extracting the isosurface the renderer shows.
    /// Computed on the first call and kept (4 bytes per voxel).
    pub fn values(&self) -> &[f32] {
        self.whole.get_or_init(|| {
            let [nx, ny, nz] = self.dims;
            let mut out = Vec::with_capacity(nx * ny * nz);
            for z0 in (0..nz).step_by(16) {
                let z1 = (z0 + 16).min(nz) - 1;
                out.extend(self.recipe.values([0, 0, z0], [nx - 1, ny - 1, z1]));
            }
            out
        })
    }

    /// Bricks built so far and bricks evicted from the cache to make room, for reports.
    pub fn brick_counts(&self) -> (u64, u64) {
        self.cache.counts()
    }

    /// Bricks of the volume, and how many the cache holds now.
    pub fn bricks(&self) -> (usize, usize) {
        (self.brick_dims.iter().product(), self.cache.used())
    }

    /// The first problem the source met while bricks were built (a chunk that could
    /// not be read), if any.
    pub fn problem(&self) -> Option<String> {
        self.recipe.source.problem()
    }

    /// Makes room in the brick cache before a frame (evicts the oldest bricks when it
    /// is nearly full). Call it from a thread that is not rendering.
    pub(crate) fn make_room(&self) {
        self.cache.make_room();
    }

    /// The voxel-to-world affine, 4x4 row-major.
    pub fn affine(&self) -> [[f64; 4]; 4] {
        let mut affine = [[0.0; 4]; 4];
        for (r, row) in affine.iter_mut().take(3).enumerate() {
            row[..3].copy_from_slice(&self.to_world[r]);
            row[3] = self.origin[r];
        }
        affine[3][3] = 1.0;
        affine
    }

    /// Samples along i, j, k.
    pub fn dims(&self) -> [usize; 3] {
        self.dims
    }

    /// The smallest voxel spacing in mm: one "voxel" of step length.
    pub fn min_spacing(&self) -> f64 {
        self.min_spacing
    }

    /// Minimum and maximum finite value.
    pub fn range(&self) -> (f32, f32) {
        self.range
    }

    /// The 0.5th and 99.5th percentiles of the values ([`glint_io::robust_range`], on a
    /// regular subsample): a range that a few outlier voxels cannot stretch, for scaling
    /// presets and ramps. Within [`Field::range`].
    pub fn robust_range(&self) -> (f32, f32) {
        self.robust
    }

    /// The macro-cell grid: its dimensions and, per cell (i fastest), the (min, max)
    /// of the values a sample inside the cell's box can take (with the field's
    /// [`Filter`]). Cell `c` spans
    /// voxels `c·MACRO_CELL ..= (c+1)·MACRO_CELL` along each axis (clipped to the
    /// volume). Light transport bounds its extinction per cell by these ranges.
    pub fn macro_cells(&self) -> ([usize; 3], &[(f32, f32)]) {
        (self.cell_dims, &self.cells)
    }

    /// World position (mm) of a continuous voxel index.
    pub fn index_to_world(&self, p: [f64; 3]) -> [f64; 3] {
        let w = mul3(&self.to_world, p);
        [
            w[0] + self.origin[0],
            w[1] + self.origin[1],
            w[2] + self.origin[2],
        ]
    }

    /// Continuous voxel index of a world position.
    pub fn world_to_index(&self, w: [f64; 3]) -> [f64; 3] {
        mul3(
            &self.to_index,
            [
                w[0] - self.origin[0],
                w[1] - self.origin[1],
                w[2] - self.origin[2],
            ],
        )
    }

    /// A world direction expressed in voxel index units.
    pub fn direction_to_index(&self, d: [f64; 3]) -> [f64; 3] {
        mul3(&self.to_index, d)
    }

    /// The index-space vector, in f32, from the index position `from` to the world
    /// point `to`: the difference of two index positions. Light transport turns its
    /// world directions into index units per mm so ([`Field::index_direction`], and a
    /// ray's direction from its origin).
    pub(crate) fn index_offset(&self, from: [f64; 3], to: [f64; 3]) -> Vec3 {
        let e = self.world_to_index(to);
        Vec3::new(
            (e[0] - from[0]) as f32,
            (e[1] - from[1]) as f32,
            (e[2] - from[2]) as f32,
        )
    }

    /// The index-space direction (index units per mm, f32) of the world direction
    /// `v`: [`Field::index_offset`] from the world origin's index position to `v`.
    pub(crate) fn index_direction(&self, v: Vec3) -> Vec3 {
        let origin = self.world_to_index([0.0; 3]);
        self.index_offset(origin, [v.x as f64, v.y as f64, v.z as f64])
    }

    /// The trilinear cell holding `p` (index units, inside `[0, dims-1]`; outside
    /// points are clamped to the border cells).
    #[inline(always)]
    pub(crate) fn locate(&self, p: Vec3) -> Loc {
        let [nx, ny, nz] = self.dims;
        // Clamp in float first: then the value is finite (f32::max/min drop NaN) and
        // within 0..=dims-2, which makes the unchecked conversion sound and saves the
        // saturating conversion's checks in the innermost loop.
        let fx = p.x.max(0.0).min((nx - 2) as f32);
        let fy = p.y.max(0.0).min((ny - 2) as f32);
        let fz = p.z.max(0.0).min((nz - 2) as f32);
        // SAFETY: fx, fy, fz are finite and in [0, dims-2] (see above).
        let (i, j, k) = unsafe {
            (
                fx.to_int_unchecked::<u32>() as usize,
                fy.to_int_unchecked::<u32>() as usize,
                fz.to_int_unchecked::<u32>() as usize,
            )
        };
        Loc {
            ijk: [i, j, k],
            t: [
                (p.x - i as f32).clamp(0.0, 1.0),
                (p.y - j as f32).clamp(0.0, 1.0),
                (p.z - k as f32).clamp(0.0, 1.0),
            ],
        }
    }

    /// Index of the macro cell holding a located sample (every voxel the sample reads
    /// lies in that cell).
    #[inline(always)]
    pub(crate) fn cell_index(&self, loc: &Loc) -> usize {
        let cd = self.cell_dims;
        let [i, j, k] = loc.ijk.map(|x| x / MACRO_CELL);
        i + cd[0] * (j + cd[1] * k)
    }

    /// The brick of a located sample (index and coordinates) and the sample's corner
    /// voxel inside it.
    #[inline(always)]
    pub(crate) fn brick_of(&self, loc: &Loc) -> (usize, [usize; 3], usize) {
        let bd = self.brick_dims;
        let b = loc.ijk.map(|x| x >> BRICK_SHIFT);
        let l = loc.ijk.map(|x| x & (BRICK - 1));
        (
            b[0] + bd[0] * (b[1] + bd[1] * b[2]),
            b,
            l[0] + BRICK_ROW * l[1] + BRICK_SLICE * l[2],
        )
    }

    /// The stored sample of voxel `ijk` in physical units (the source's value after
    /// its rescale, before the prefilter: what a radiology viewer shows for the
    /// voxel); `None` off the grid.
    pub fn sample(&self, ijk: [usize; 3]) -> Option<f32> {
        if (0..3).any(|a| ijk[a] >= self.dims[a]) {
            return None;
        }
        let mut out = [0.0f32];
        self.recipe
            .source
            .read(ijk.map(|i| i as isize), [1, 1, 1], &mut out);
        Some(out[0])
    }

    /// The value at `p` (index units), reconstructed with the field's [`Filter`].
    #[inline(always)]
    pub fn value(&self, p: Vec3) -> f32 {
        self.value_at(&self.locate(p), &crossbeam_epoch::pin())
    }

    /// The world gradient at `p` (index units), reconstructed with the field's
    /// [`Filter`].
    #[inline(always)]
    pub fn gradient(&self, p: Vec3) -> Vec3 {
        self.gradient_at(&self.locate(p), &crossbeam_epoch::pin())
    }

    /// [`Field::value`] for a caller that holds a guard across many samples (a tile).
    #[inline(always)]
    pub(crate) fn value_in(&self, p: Vec3, guard: &Guard) -> f32 {
        self.value_at(&self.locate(p), guard)
    }

    /// [`Field::gradient`] for a caller that holds a guard across many samples.
    #[inline(always)]
    pub(crate) fn gradient_in(&self, p: Vec3, guard: &Guard) -> Vec3 {
        self.gradient_at(&self.locate(p), guard)
    }

    /// The value at a located sample, with the field's [`Filter`].
    #[inline(always)]
    pub(crate) fn value_at(&self, loc: &Loc, guard: &Guard) -> f32 {
        if self.filter == Filter::Tricubic {
            return self.cubic_value_at(loc, guard);
        }
        self.linear_value_at(loc, guard)
    }

    /// The world gradient at a located sample, with the field's [`Filter`].
    #[inline(always)]
    pub(crate) fn gradient_at(&self, loc: &Loc, guard: &Guard) -> Vec3 {
        if self.filter == Filter::Tricubic {
            return self.cubic_gradient_at(loc, guard);
        }
        self.linear_gradient_at(loc, guard)
    }

    /// Trilinear value at a located sample.
    #[inline(always)]
    pub(crate) fn linear_value_at(&self, loc: &Loc, guard: &Guard) -> f32 {
        let (b, coords, local) = self.brick_of(loc);
        match self.cache.offset(b, coords, &self.recipe, guard) {
            // SAFETY: the offset is a built slot's, valid while `guard` lives; local
            // plus the far corner's offset stays inside the slot.
            Some(o) => unsafe { trilinear(self.cache.values().add(o as usize + local), loc.t) },
            None => self.with_spare(b, coords, |v, _| {
                // SAFETY: as above, in the spare brick.
                unsafe { trilinear(v.as_ptr().add(local), loc.t) }
            }),
        }
    }

    /// Trilinear world gradient at a located sample: the stored integers interpolated
    /// in f32 (exact conversions), then scaled.
    #[inline(always)]
    pub(crate) fn linear_gradient_at(&self, loc: &Loc, guard: &Guard) -> Vec3 {
        let (b, coords, local) = self.brick_of(loc);
        let g = match self.cache.offset(b, coords, &self.recipe, guard) {
            // SAFETY: as in `value_at`.
            Some(o) => unsafe {
                trilinear_gradient(self.cache.gradients().add(o as usize + local), loc.t)
            },
            None => self.with_spare(b, coords, |_, g| {
                // SAFETY: as in `value_at`.
                unsafe { trilinear_gradient(g.as_ptr().add(local), loc.t) }
            }),
        };
        let s = self.gradient_scale;
        Vec3::new(g[0] * s, g[1] * s, g[2] * s)
    }

    /// Calls `f` with brick `b` built outside the cache (when the cache is full of
    /// bricks in use): a few per thread are kept, most recent first.
    #[cold]
    #[inline(never)]
    fn with_spare<R>(
        &self,
        b: usize,
        coords: [usize; 3],
        f: impl FnOnce(&[f32], &[[i16; 4]]) -> R,
    ) -> R {
        /// Spare bricks kept per thread.
        const SPARES: usize = 8;
        type Spare = (u64, usize, Vec<f32>, Vec<[i16; 4]>);
        thread_local! {
            static SPARE: RefCell<Vec<Spare>> = const { RefCell::new(Vec::new()) };
        }
        SPARE.with(|s| {
            let mut s = s.borrow_mut();
            let hit = s.iter().position(|e| e.0 == self.id && e.1 == b);
            let entry = match hit {
                Some(i) => s.remove(i),
                None => {
                    let mut v = vec![0.0; BRICK_VOXELS];
                    let mut g = vec![[0i16; 4]; BRICK_VOXELS];
                    self.recipe.build(coords, &mut v, &mut g);
                    (self.id, b, v, g)
                }
            };
            let r = f(&entry.2, &entry.3);
            s.insert(0, entry);
            s.truncate(SPARES);
            r
        })
    }
}

/// The trilinear interpolation of the eight values of the cell whose corner 000 is at
/// `d` (brick layout), fractions `t`.
///
/// # Safety
/// `d + BRICK_SLICE + BRICK_ROW + 1` must be readable.
#[inline(always)]
unsafe fn trilinear(d: *const f32, [tx, ty, tz]: [f32; 3]) -> f32 {
    // SAFETY: the caller's contract covers every offset below.
    let at = |o: usize| unsafe { *d.add(o) };
    let (sy, sz) = (BRICK_ROW, BRICK_SLICE);
    let c000 = at(0);
    let c100 = at(1);
    let c010 = at(sy);
    let c110 = at(sy + 1);
    let c001 = at(sz);
    let c101 = at(sz + 1);
    let c011 = at(sz + sy);
    let c111 = at(sz + sy + 1);
    let x00 = c000 + tx * (c100 - c000);
    let x10 = c010 + tx * (c110 - c010);
    let x01 = c001 + tx * (c101 - c001);
    let x11 = c011 + tx * (c111 - c011);
    let y0 = x00 + ty * (x10 - x00);
    let y1 = x01 + ty * (x11 - x01);
    y0 + tz * (y1 - y0)
}

/// [`trilinear`] of the stored gradients, component by component, unscaled.
///
/// # Safety
/// As for [`trilinear`].
#[inline(always)]
unsafe fn trilinear_gradient(d: *const [i16; 4], [tx, ty, tz]: [f32; 3]) -> [f32; 3] {
    // SAFETY: the caller's contract covers every offset below.
    let f = |o: usize| unsafe { *d.add(o) }.map(f32::from);
    let lerp = |a: [f32; 4], b: [f32; 4], t: f32| {
        [
            a[0] + t * (b[0] - a[0]),
            a[1] + t * (b[1] - a[1]),
            a[2] + t * (b[2] - a[2]),
            0.0,
        ]
    };
    let (sy, sz) = (BRICK_ROW, BRICK_SLICE);
    let x00 = lerp(f(0), f(1), tx);
    let x10 = lerp(f(sy), f(sy + 1), tx);
    let x01 = lerp(f(sz), f(sz + 1), tx);
    let x11 = lerp(f(sz + sy), f(sz + sy + 1), tx);
    let y0 = lerp(x00, x10, ty);
    let y1 = lerp(x01, x11, ty);
    let g = lerp(y0, y1, tz);
    [g[0], g[1], g[2]]
}

/// The voxel count of a volume of `dims`, checked: at least 2 samples per axis, at
/// most [`MAX_FIELD_VOXELS`], and as many samples as the dimensions say (`samples`,
/// when known).
fn checked_count(
    dims: [usize; 3],
    samples: impl Into<Option<usize>>,
) -> Result<usize, RenderError> {
    if dims.iter().any(|&d| d < 2) {
        return Err(RenderError::Volume(format!(
            "dimensions {}x{}x{}: need at least 2 samples along each axis",
            dims[0], dims[1], dims[2]
        )));
    }
    let count = dims
        .iter()
        .try_fold(1usize, |acc, &d| acc.checked_mul(d))
        .filter(|&c| c <= MAX_FIELD_VOXELS)
        .ok_or_else(|| {
            RenderError::Volume(format!(
                "dimensions {}x{}x{} exceed the renderer's limit of {MAX_FIELD_VOXELS} voxels",
                dims[0], dims[1], dims[2]
            ))
        })?;
    match samples.into() {
        Some(n) if n != count => Err(RenderError::Volume(format!(
            "{n} samples for dimensions {}x{}x{}",
            dims[0], dims[1], dims[2]
        ))),
        _ => Ok(count),
    }
}

/// The affine's 3x3 part, origin, inverse 3x3 part and smallest spacing.
fn placement(affine: &[[f64; 4]; 4]) -> Result<(Mat3, [f64; 3], Mat3, f64), RenderError> {
    let to_world = linear_part(affine);
    let origin = [affine[0][3], affine[1][3], affine[2][3]];
    if origin.iter().any(|x| !x.is_finite()) {
        return Err(RenderError::Volume("affine has a non-finite origin".into()));
    }
    let to_index = inverse3(&to_world)
        .ok_or_else(|| RenderError::Volume("affine is singular or not finite".into()))?;
    let spacing: Vec<f64> = (0..3)
        .map(|c| (0..3).map(|r| to_world[r][c].powi(2)).sum::<f64>().sqrt())
        .collect();
    let min_spacing = spacing.iter().cloned().fold(f64::INFINITY, f64::min);
    Ok((to_world, origin, to_index, min_spacing))
}

/// The slab test of the index-space ray `o + t d` (t in mm, `d` in index units per mm)
/// against the box `lo..=hi`, from `[t0, t1]`: where the ray is inside the box along
/// every axis it moves along (entry, exit; the exit may come before the entry, a miss
/// the caller tells), or `None` when it does not move along an axis and lies outside
/// the box's extent there. The ray caster and light transport clip their rays here.
#[inline(always)]
pub(crate) fn clip_ray(
    o: Vec3,
    d: Vec3,
    (lo, hi): ([f32; 3], [f32; 3]),
    (t0, t1): (f32, f32),
) -> Option<(f32, f32)> {
    let (mut a, mut b) = (t0, t1);
    for axis in 0..3 {
        let (oa, da) = (o.get(axis), d.get(axis));
        if da.abs() < 1e-12 {
            if oa < lo[axis] || oa > hi[axis] {
                return None;
            }
            continue;
        }
        let inv = 1.0 / da;
        let (ta, tb) = ((lo[axis] - oa) * inv, (hi[axis] - oa) * inv);
        a = a.max(ta.min(tb));
        b = b.min(ta.max(tb));
    }
    Some((a, b))
}
