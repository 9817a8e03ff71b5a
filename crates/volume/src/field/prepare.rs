//! The one pass over the whole volume a field needs before its first frame: the value
//! range, the macro cells' value ranges, the largest gradient component (the gradients'
//! quantisation step) and the robust range's subsample. It streams slabs of slices,
//! keeping no copy of the volume; the values and gradients themselves are built later,
//! per brick, where rays go.

use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::{Mutex, PoisonError};

use rayon::prelude::*;

use glint_core::RenderError;

use super::brick::{Recipe, Scratch};
use super::filter::{row_gradients, span, Neighbours};
use super::MACRO_CELL;

/// What [`prepare`] found.
pub(super) struct Prepared {
    /// Finite physical range before the prefilter.
    pub(super) range: (f32, f32),
    /// The robust range of the reconstruction values.
    pub(super) robust: (f32, f32),
    pub(super) cell_dims: [usize; 3],
    /// Per macro cell, the (min, max) of the reconstruction values it covers.
    pub(super) cells: Vec<(f32, f32)>,
    /// The largest world gradient component over all voxels.
    pub(super) largest: f32,
    /// Whether every value read was finite. When the pass measured the range and met
    /// a NaN or an infinity, nothing else it found holds: the caller measures the
    /// finite range ([`finite_range`]) and runs the pass again with the fill set.
    pub(super) finite: bool,
}

/// One slab's share of [`Prepared`] (its cells are written in place).
struct Slab {
    range: (f32, f32),
    finite: bool,
    largest: f32,
    robust: Vec<f32>,
}

impl Slab {
    /// The share of a slab that met a non-finite value, or of one skipped after
    /// another did.
    fn void() -> Slab {
        Slab {
            range: (f32::NAN, f32::NAN),
            finite: false,
            largest: 0.0,
            robust: Vec::new(),
        }
    }
}

/// Buffers that slabs hand on to the next slab a thread takes: at most one set per
/// thread at a time, so the pass pages in a few slabs' worth of memory however many
/// slabs the volume has, and frees it at its end. (Fresh buffers per slab made the
/// kernel's zeroing of new pages the largest cost of a first image: 36% of an end-to-end
/// run's samples on the MNI152 bench scene, `perf record --call-graph dwarf`.)
struct Spares<T, F>(Mutex<Vec<T>>, F);

impl<T, F: Fn() -> T> Spares<T, F> {
    /// A pool whose new sets of buffers `make` makes (with room for the largest slab).
    fn new(make: F) -> Self {
        Spares::with_kept(Vec::new(), make)
    }

    /// A pool that hands out the sets `kept` first.
    fn with_kept(kept: Vec<T>, make: F) -> Self {
        Spares(Mutex::new(kept), make)
    }

    /// The sets of buffers the pool holds.
    fn into_sets(self) -> Vec<T> {
        self.0.into_inner().unwrap_or_else(PoisonError::into_inner)
    }

    /// `f` with a spare set of buffers (or a new one), which then goes back.
    fn with<R>(&self, f: impl FnOnce(&mut T) -> R) -> R {
        let spare = self.0.lock().unwrap_or_else(PoisonError::into_inner).pop();
        let mut b = spare.unwrap_or_else(&self.1);
        let r = f(&mut b);
        self.0
            .lock()
            .unwrap_or_else(PoisonError::into_inner)
            .push(b);
        r
    }
}

/// Macro-cell layers per slab: about 16 MiB of f32 slices per slab (more layers for
/// small slices, at least one), so a slab's halo of filtered slices stays a small
/// share of its work and its buffers stay small beside the volume.
fn layers_per_slab(dims: [usize; 3]) -> usize {
    let slice = (dims[0] * dims[1] * 4).max(1);
    ((16 << 20) / (slice * MACRO_CELL)).clamp(1, 8)
}

/// Bytes the pass's buffers take at most, on `threads` threads: per thread the read
/// slices of a slab with the prefilter's halo, the filter's four slices of scratch and
/// the filtered slices (the pass over NaN-free sources; the finite-range pass before it,
/// when there is one, takes less).
pub(super) fn pass_bytes(dims: [usize; 3], threads: usize) -> u64 {
    let slices = (layers_per_slab(dims) * MACRO_CELL + 2) as u64;
    let slice = (dims[0] * dims[1] * std::mem::size_of::<f32>()) as u64;
    threads as u64 * slice * ((slices + 2) + 4 + slices)
}

/// The finite range of the physical values, in a pass of its own, for sources whose
/// values may be NaN or infinite (those are then replaced by the minimum before
/// filtering, so the minimum must be known first).
pub(super) fn finite_range(recipe: &Recipe) -> Result<(f32, f32), RenderError> {
    let [nx, ny, nz] = recipe.dims;
    let step = (layers_per_slab(recipe.dims) * MACRO_CELL).max(1);
    let spares = Spares::new(|| Vec::with_capacity(nx * ny * step));
    let (lo, hi) = (0..nz.div_ceil(step))
        .into_par_iter()
        .map(|s| {
            let (z0, z1) = (s * step, ((s + 1) * step).min(nz));
            spares.with(|raw| {
                raw.resize(nx * ny * (z1 - z0), 0.0);
                recipe
                    .source
                    .read([0, 0, z0 as isize], [nx, ny, z1 - z0], raw);
                finite_min_max(raw)
            })
        })
        .reduce(
            || (f32::INFINITY, f32::NEG_INFINITY),
            |a, b| (a.0.min(b.0), a.1.max(b.1)),
        );
    if !lo.is_finite() {
        return Err(RenderError::Volume(
            "no finite sample (all NaN or infinite)".into(),
        ));
    }
    Ok((lo, hi))
}

fn finite_min_max(v: &[f32]) -> (f32, f32) {
    let mut lo = f32::INFINITY;
    let mut hi = f32::NEG_INFINITY;
    for &x in v.iter().filter(|x| x.is_finite()) {
        lo = lo.min(x);
        hi = hi.max(x);
    }
    (lo, hi)
}

/// The pass. `range` is [`finite_range`]'s result with `recipe.fill` set from it, or
/// `None` to measure the range here: then, should the source hold a non-finite value,
/// the pass says so ([`Prepared::finite`]) and its other results are not to be used.
/// Most float volumes hold none, and measuring the range here spares them a pass of
/// its own. `progress` is called with the slices done after each slab.
pub(super) fn prepare(
    recipe: &Recipe,
    range: Option<(f32, f32)>,
    progress: &(dyn Fn(u64) + Sync),
) -> Result<Prepared, RenderError> {
    let dims = recipe.dims;
    let [nx, ny, nz] = dims;
    let cell_dims = dims.map(|d| (d - 1).div_ceil(MACRO_CELL));
    let layers = layers_per_slab(dims);
    let slabs = cell_dims[2].div_ceil(layers);
    let count = nx * ny * nz;
    let stride = count.div_ceil(glint_io::ROBUST_SAMPLES).max(1);
    // A slab filters at most its cell layers' slices and one more on each side, and
    // reads one more on each side again for the prefilter.
    let slices = layers * MACRO_CELL + 2;
    let spares = Spares::with_kept(take_kept(dims, slices), || slab_buffers(dims, slices));
    // Each slab writes its layers' cells in place: collected per slab and joined, the
    // cells were held twice at the end of the pass (512 MiB more at the peak of a
    // 2048x2048x1024 level).
    let mut cells = vec![(0.0f32, 0.0f32); cell_dims.iter().product()];
    let non_finite = AtomicBool::new(false);
    let parts: Vec<Slab> = cells
        .par_chunks_mut(layers * cell_dims[0] * cell_dims[1])
        .enumerate()
        .map(|(s, cells)| {
            let cz = (s * layers, ((s + 1) * layers).min(cell_dims[2]));
            // Once a slab met a non-finite value the pass's results are void: the
            // slabs left are skipped.
            if non_finite.load(Ordering::Relaxed) {
                return Slab::void();
            }
            let slab = spares.with(|b| slab(recipe, cz, stride, range.is_none(), b, cells));
            if !slab.finite {
                non_finite.store(true, Ordering::Relaxed);
            }
            progress((slab_slices(dims, cz, cell_dims[2]).1 - cz.0 * MACRO_CELL) as u64);
            slab
        })
        .collect();
    keep(spares.into_sets());
    debug_assert_eq!(parts.len(), slabs);
    let mut out = Prepared {
        range: range.unwrap_or((f32::INFINITY, f32::NEG_INFINITY)),
        robust: (0.0, 0.0),
        cell_dims,
        cells,
        largest: 0.0,
        finite: parts.iter().all(|p| p.finite),
    };
    if !out.finite {
        return Ok(out);
    }
    let mut sub = Vec::with_capacity(count.div_ceil(stride));
    for p in parts {
        if range.is_none() {
            out.range = (out.range.0.min(p.range.0), out.range.1.max(p.range.1));
        }
        out.largest = out.largest.max(p.largest);
        sub.extend_from_slice(&p.robust);
    }
    if !out.range.0.is_finite() {
        return Err(RenderError::Volume(
            "no finite sample (all NaN or infinite)".into(),
        ));
    }
    debug_assert_eq!(sub.len(), count.div_ceil(stride));
    out.robust = robust_in_place(&mut sub).unwrap_or(out.range);
    Ok(out)
}

/// [`glint_io::robust_range`] of the pass's subsample `sub` (the values that function
/// takes, in its order), found in place and in f32: the same ranks, and the same
/// values, since f32 to f64 is exact and keeps the order. That function's f64 copy of
/// the subsample (8 MiB of fresh pages per volume) was 5% of a `glint batch`
/// subject's CPU, most of it the kernel clearing those pages (issue 47).
fn robust_in_place(sub: &mut Vec<f32>) -> Option<(f32, f32)> {
    sub.retain(|x| x.is_finite());
    if sub.is_empty() {
        return None;
    }
    let (p_lo, p_hi) = glint_io::ROBUST_PERCENTILES;
    let rank = |p: f64| ((p / 100.0) * (sub.len() - 1) as f64).round() as usize;
    let (lo_rank, hi_rank) = (rank(p_lo), rank(p_hi));
    let lo = *sub.select_nth_unstable_by(lo_rank, f32::total_cmp).1;
    let hi = *sub.select_nth_unstable_by(hi_rank, f32::total_cmp).1;
    if hi > lo {
        return Some((lo, hi));
    }
    // The maximum as that function takes it, in f64.
    let max = sub.iter().fold(f64::from(lo), |m, &x| m.max(f64::from(x)));
    Some((lo, max as f32))
}

/// The voxel slices a slab of cell layers `cz` owns (its gradients, range and robust
/// samples): from its first cell's first slice to the next slab's, the last slab to
/// the volume's end.
fn slab_slices(dims: [usize; 3], cz: (usize, usize), layers: usize) -> (usize, usize) {
    let z0 = cz.0 * MACRO_CELL;
    let z1 = if cz.1 == layers {
        dims[2]
    } else {
        cz.1 * MACRO_CELL
    };
    (z0, z1)
}

/// A slab's buffers: the prefilter's, and the filtered values.
type Buffers = (Scratch, Vec<f32>);

/// The pass's buffers, kept from one field's pass for the next (at most one set per
/// thread, each at most [`KEPT_BYTES`]): a study of many volumes of one size (`glint
/// batch`) then pages them in once, not per volume. Fresh sets per pass made the
/// kernel's clearing of their pages 7-14% of a batch subject's CPU once the volume's
/// samples were reused (issue 47).
static KEPT: Mutex<Vec<Buffers>> = Mutex::new(Vec::new());

/// Largest set of pass buffers [`KEPT`] keeps: 64 MiB (the sets of a 197x233x189
/// volume take 14 MiB; those of 2048^2 slices, over 100 MiB, are freed).
const KEPT_BYTES: usize = 64 << 20;

/// The kept sets that can hold a slab of `slices` filtered slices of `dims` without
/// growing (the others are freed).
fn take_kept(dims: [usize; 3], slices: usize) -> Vec<Buffers> {
    let mut kept = std::mem::take(&mut *KEPT.lock().unwrap_or_else(PoisonError::into_inner));
    kept.retain(|b| fits(b, dims, slices));
    kept
}

/// Whether `b` holds a slab of `slices` filtered slices of `dims` without growing: as
/// much room as [`slab_buffers`] makes.
fn fits((scratch, f): &Buffers, [nx, ny, _]: [usize; 3], slices: usize) -> bool {
    scratch.capacity() >= (nx + 2) * (ny + 2) * (slices + 2) && f.capacity() >= nx * ny * slices
}

/// Keeps the pass's sets of buffers for the next pass (up to one per thread, each at
/// most [`KEPT_BYTES`]).
fn keep(sets: Vec<Buffers>) {
    let bytes = |(scratch, f): &Buffers| scratch.bytes() + 4 * f.capacity();
    let mut kept = KEPT.lock().unwrap_or_else(PoisonError::into_inner);
    let room = rayon::current_num_threads().saturating_sub(kept.len());
    kept.extend(
        sets.into_iter()
            .filter(|b| bytes(b) <= KEPT_BYTES)
            .take(room),
    );
}

/// Buffers for the slabs of a volume of `dims` that filter at most `slices` slices:
/// the read box has the prefilter's halo on every side, not only along z. (Sized for
/// less, the first slab's read grew the buffer by reallocation, which copied its
/// capacity and cleared twice its pages: 3% of a `glint batch` subject's CPU, issue
/// 47.)
fn slab_buffers([nx, ny, _]: [usize; 3], slices: usize) -> Buffers {
    (
        Scratch::with_capacity((nx + 2) * (ny + 2) * (slices + 2)),
        Vec::with_capacity(nx * ny * slices),
    )
}

/// One slab of cell layers `cz.0 .. cz.1`, in the buffers `b`; its macro cells into
/// `cells_out` (the layers' cells, in order).
fn slab(
    recipe: &Recipe,
    cz: (usize, usize),
    stride: usize,
    measure_range: bool,
    (scratch, f): &mut Buffers,
    cells_out: &mut [(f32, f32)],
) -> Slab {
    let dims = recipe.dims;
    let [nx, ny, nz] = dims;
    let sxy = nx * ny;
    let cell_dims = dims.map(|d| (d - 1).div_ceil(MACRO_CELL));
    let (z0, z1) = slab_slices(dims, cz, cell_dims[2]);
    // Filtered slices fa ..= fb: the cells' and one around the owned slices.
    let fa = z0.saturating_sub(1);
    let fb = z1.max(cz.1 * MACRO_CELL).min(nz - 1);
    // With the range of the physical values read, and whether they are all finite.
    let (range, finite) =
        recipe.values_into([0, 0, fa], [nx - 1, ny - 1, fb], measure_range, scratch, f);
    if !finite {
        return Slab::void();
    }
    let f = &f[..];
    let row = |j: usize, k: usize| &f[nx * (j + ny * (k - fa))..][..nx];
    let g = &recipe.to_world_gradient;
    // The shortcut's argument needs finite index gradients; a slab whose differences
    // overflow takes the general path.
    let largest = match diagonal(g).map(|d| largest_axis_aligned(d, z0..z1, dims, row)) {
        Some(l) if l.is_finite() => l,
        _ => largest_world(g, z0..z1, dims, row),
    };
    let robust = (z0 * sxy).div_ceil(stride)..(z1 * sxy).div_ceil(stride);
    let robust = robust
        .map(|m| {
            let i = m * stride;
            f[i - fa * sxy]
        })
        .collect();
    cells(f, dims, (fa, 0), cz, cells_out);
    Slab {
        range,
        finite,
        largest,
        robust,
    }
}

/// The largest world gradient component of the voxels of slices `ks`: each gradient
/// as the bricks compute it ([`row_gradients`]), then its largest component.
fn largest_world<'a>(
    g: &[[f32; 3]; 3],
    ks: std::ops::Range<usize>,
    [nx, ny, nz]: [usize; 3],
    row: impl Fn(usize, usize) -> &'a [f32],
) -> f32 {
    let mut largest = 0.0f32;
    let mut out = vec![[0.0f32; 3]; nx];
    for k in ks {
        let (km, kp, sk) = span(k, nz);
        for j in 0..ny {
            let (jm, jp, sj) = span(j, ny);
            let n = Neighbours {
                jm: row(jm, k),
                jp: row(jp, k),
                span_j: sj,
                km: row(j, km),
                kp: row(j, kp),
                span_k: sk,
            };
            row_gradients(row(j, k), &n, (0, nx), (true, true), g, &mut out);
            largest = largest.max(largest_abs(out.as_flattened()));
        }
    }
    largest
}

/// The diagonal of `g` when every other entry is zero and the diagonal's are finite
/// and non-zero (the affine is a scaling, perhaps with flips, as for most scans).
pub(super) fn diagonal(g: &[[f32; 3]; 3]) -> Option<[f32; 3]> {
    let off = (0..3).all(|a| (0..3).all(|b| a == b || g[a][b] == 0.0));
    let d = [g[0][0], g[1][1], g[2][2]];
    (off && d.iter().all(|x| x.is_finite() && *x != 0.0)).then_some(d)
}

/// [`largest_world`] for a diagonal `g` (`d`), with the same result bit for bit and
/// without the matrix: world component a of a voxel is `d[a] * g_a + 0 * g_b + 0 *
/// g_c`, which is `d[a] * g_a` (the index gradients are finite, so the zero products
/// are zeros and adding them changes nothing but the sign of a zero); rounding is
/// monotonic and symmetric, so the largest `|d[a] * g_a|` over voxels is `|d[a]|`
/// times the largest `|g_a|`, rounded. Each `g_a` is the difference [`row_gradients`]
/// takes, divided by the same span.
fn largest_axis_aligned<'a>(
    d: [f32; 3],
    ks: std::ops::Range<usize>,
    [nx, ny, nz]: [usize; 3],
    row: impl Fn(usize, usize) -> &'a [f32],
) -> f32 {
    let mut m = [0.0f32; 3];
    for k in ks {
        let (km, kp, sk) = span(k, nz);
        for j in 0..ny {
            let (jm, jp, sj) = span(j, ny);
            let c = row(j, k);
            // Along i: one-sided at both ends, central between (row_gradients's faces).
            let ends = ((c[1] - c[0]) / 1.0)
                .abs()
                .max(((c[nx - 1] - c[nx - 2]) / 1.0).abs());
            m[0] = m[0]
                .max(ends)
                .max(largest_abs_diff(&c[2..], &c[..nx - 2], 2.0));
            m[1] = m[1].max(largest_abs_diff(row(jp, k), row(jm, k), sj));
            m[2] = m[2].max(largest_abs_diff(row(j, kp), row(j, km), sk));
        }
    }
    (0..3).fold(0.0f32, |l, a| l.max(d[a].abs() * m[a]))
}

/// The largest `|(a[i] - b[i]) / span|` (0 for none), in eight running maxima as
/// [`largest_abs`].
fn largest_abs_diff(a: &[f32], b: &[f32], span: f32) -> f32 {
    let mut lanes = [0.0f32; 8];
    let (mut ca, mut cb) = (a.chunks_exact(8), b.chunks_exact(8));
    for (x, y) in (&mut ca).zip(&mut cb) {
        for ((m, &x), &y) in lanes.iter_mut().zip(x).zip(y) {
            *m = m.max(((x - y) / span).abs());
        }
    }
    let rest = ca
        .remainder()
        .iter()
        .zip(cb.remainder())
        .fold(0.0f32, |m, (&x, &y)| m.max(((x - y) / span).abs()));
    lanes.iter().fold(rest, |m, &x| m.max(x))
}

/// The largest absolute value of `v` (0 for none), in eight running maxima that the
/// compiler keeps in one vector register: a single running maximum would chain every
/// comparison on the one before. The maximum of a set does not depend on the order.
fn largest_abs(v: &[f32]) -> f32 {
    let mut lanes = [0.0f32; 8];
    let mut chunks = v.chunks_exact(8);
    for chunk in &mut chunks {
        for (m, x) in lanes.iter_mut().zip(chunk) {
            *m = m.max(x.abs());
        }
    }
    let rest = chunks
        .remainder()
        .iter()
        .fold(0.0f32, |m, x| m.max(x.abs()));
    lanes.iter().fold(rest, |m, &x| m.max(x))
}

/// The macro cells' (min, max) of the voxels `reach` beyond each cell's own on every
/// side (clipped to the volume): for the tricubic filter, whose samples in a cell read
/// one voxel beyond it (`reach` 1), a pass over the volume like [`prepare`]'s (the
/// source read again, slab by slab), which bounds its samples far tighter than the
/// trilinear cells widened to their neighbours' (6 voxels more per axis instead of 2).
pub(super) fn cell_ranges(recipe: &Recipe, reach: usize) -> Vec<(f32, f32)> {
    let dims = recipe.dims;
    let [nx, ny, nz] = dims;
    let cell_dims = dims.map(|d| (d - 1).div_ceil(MACRO_CELL));
    let layers = layers_per_slab(dims);
    let mut ranges = vec![(0.0f32, 0.0f32); cell_dims.iter().product()];
    ranges
        .par_chunks_mut(layers * cell_dims[0] * cell_dims[1])
        .enumerate()
        .for_each_init(
            || (Scratch::default(), Vec::new()),
            |(scratch, f), (s, out)| {
                let cz = (s * layers, ((s + 1) * layers).min(cell_dims[2]));
                let fa = (cz.0 * MACRO_CELL).saturating_sub(reach);
                let fb = (cz.1 * MACRO_CELL + reach).min(nz - 1);
                recipe.values_into([0, 0, fa], [nx - 1, ny - 1, fb], false, scratch, f);
                cells(f, dims, (fa, reach), cz, out);
            },
        );
    ranges
}

/// Per macro cell of layers `cz`, the (min, max) of the filtered values `f` (slices
/// from `fa`) it covers: cell c covers voxels c*B ..= c*B + B (one voxel of overlap, so
/// every trilinear sample inside the cell's box reads only voxels it covers), and
/// `reach` voxels more on every side (clipped to the volume).
///
/// Per row of cells, first the minimum and maximum of each voxel column over the
/// cells' voxel rows (element-wise over whole rows, which vectorises), then of each
/// cell's columns: the same sets of values, so the same extremes as a loop per cell.
fn cells(
    f: &[f32],
    dims: [usize; 3],
    (fa, reach): (usize, usize),
    cz: (usize, usize),
    out: &mut [(f32, f32)],
) {
    let [nx, ny, nz] = dims;
    let [cx, cy, _] = dims.map(|d| (d - 1).div_ceil(MACRO_CELL));
    debug_assert_eq!(out.len(), cx * cy * (cz.1 - cz.0));
    let mut out = out.iter_mut();
    let mut lo = vec![0.0f32; nx];
    let mut hi = vec![0.0f32; nx];
    for ck in cz.0..cz.1 {
        for cj in 0..cy {
            lo.fill(f32::INFINITY);
            hi.fill(f32::NEG_INFINITY);
            let span = |c: usize, n: usize| {
                (c * MACRO_CELL).saturating_sub(reach)..=((c + 1) * MACRO_CELL + reach).min(n - 1)
            };
            for k in span(ck, nz) {
                for j in span(cj, ny) {
                    let row = &f[nx * (j + ny * (k - fa))..][..nx];
                    for ((l, h), &v) in lo.iter_mut().zip(hi.iter_mut()).zip(row) {
                        *l = l.min(v);
                        *h = h.max(v);
                    }
                }
            }
            for ci in 0..cx {
                let columns = span(ci, nx);
                let lo_c = lo[columns.clone()]
                    .iter()
                    .fold(f32::INFINITY, |m, &v| m.min(v));
                let hi_c = hi[columns].iter().fold(f32::NEG_INFINITY, |m, &v| m.max(v));
                if let Some(o) = out.next() {
                    *o = (lo_c, hi_c);
                }
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::field::{Field, Prefilter};
    use glint_io::{Samples, Volume};

    /// The in-place f32 robust range is glint_io's, bit for bit: spread values with
    /// outliers, negative and positive zeros, a sparse set whose percentiles coincide
    /// (the maximum then), a constant, one value, none finite.
    #[test]
    fn robust_in_place_is_glint_io_robust_range() {
        let spread: Vec<f32> = (0..20_011)
            .map(|i| ((i * 7919 % 10_007) as f32 - 5000.0) * 0.37)
            .chain([-1.5e37, 1e30, -0.0, 0.0, f32::NAN])
            .collect();
        let mut sparse = vec![0.0f32; 5000];
        sparse[17] = 200.0;
        sparse[4000] = -0.0;
        for v in [spread, sparse, vec![3.5; 99], vec![-2.0], vec![f32::NAN; 3]] {
            let want = glint_io::robust_range(v.len(), |i| f64::from(v[i]))
                .map(|(a, b)| (a as f32, b as f32));
            let got = robust_in_place(&mut v.clone());
            let bits = |r: Option<(f32, f32)>| r.map(|(a, b)| (a.to_bits(), b.to_bits()));
            assert_eq!(bits(got), bits(want), "{} values", v.len());
        }
    }

    /// A kept set of pass buffers serves a later volume only when it holds that
    /// volume's slabs without growing: made for the same or larger slices, not smaller.
    #[test]
    fn kept_buffers_serve_volumes_whose_slabs_they_hold() {
        let made = slab_buffers([40, 30, 9], 10);
        assert!(fits(&made, [40, 30, 9], 10));
        assert!(fits(&made, [40, 30, 500], 10));
        assert!(fits(&made, [30, 40, 9], 10));
        assert!(fits(&made, [20, 30, 9], 6));
        assert!(!fits(&made, [41, 30, 9], 10));
        assert!(!fits(&made, [40, 30, 9], 11));
        assert!(!fits(&(Scratch::default(), Vec::new()), [2, 2, 2], 1));
    }

    /// Every slab of the pass reads and filters within the buffers made for it, so
    /// the pass never grows (reallocates and copies) them: thin, flat and cubic
    /// volumes, with and without the prefilter's halo.
    #[test]
    fn slabs_fit_their_buffers() {
        for dims in [[5, 4, 9], [3, 17, 70], [40, 33, 6], [2, 2, 2]] {
            let n = dims.iter().product::<usize>();
            let v = (0..n).map(|i| (i * 37 % 101) as f32).collect();
            let vol = Volume::new(dims, [1.0; 3], Samples::F32(v)).unwrap();
            for prefilter in [Prefilter::Binomial, Prefilter::None] {
                let field = Field::with_prefilter(&vol, prefilter).unwrap();
                let recipe = &field.recipe;
                let cell_dims = dims.map(|d| (d - 1).div_ceil(MACRO_CELL));
                let layers = layers_per_slab(dims);
                let mut b = slab_buffers(dims, layers * MACRO_CELL + 2);
                let before = (b.0.capacity(), b.1.capacity());
                let mut cells = vec![(0.0, 0.0); cell_dims.iter().product()];
                for (s, out) in cells
                    .chunks_mut(layers * cell_dims[0] * cell_dims[1])
                    .enumerate()
                {
                    let cz = (s * layers, ((s + 1) * layers).min(cell_dims[2]));
                    slab(recipe, cz, 1, true, &mut b, out);
                    assert_eq!(
                        (b.0.capacity(), b.1.capacity()),
                        before,
                        "{dims:?} slab {s}"
                    );
                }
            }
        }
    }
}
