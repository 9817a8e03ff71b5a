//! The macro cells a classification can show a sample in, and the distances and boxes
//! derived from them for empty-space skipping.

use glint_core::{RenderMode, Vec3};

use super::lut::Lut;
use super::settings::ClassifySettings;
use crate::field::{Field, MACRO_CELL};

/// Edge, in macro cells, of the blocks whose projections bound where rays start (2:
/// 8 voxels; on the MNI152 scene 1 and 4 were 2% and 10% slower single-threaded,
/// from more splats to project and looser bounds respectively).
pub(crate) const START_BLOCK: usize = 2;

/// Per macro cell: can a sample there show? (composite: some value in the cell's range
/// has opacity; iso: the cell reaches the threshold; MIP: the cell holds more than the
/// volume's minimum).
pub(super) fn visible_cells(field: &Field, lut: &Lut, settings: &ClassifySettings) -> Vec<bool> {
    let floor = field.range().0;
    field
        .cells
        .iter()
        .map(|&(cmin, cmax)| match settings.mode {
            RenderMode::Iso => cmax >= settings.iso,
            RenderMode::Mip => cmax > floor,
            // Surface scenes are refused by `ClassifySettings::validate`.
            RenderMode::Composite | RenderMode::Surface => lut.any_opaque(cmin, cmax),
        })
        .collect()
}

/// The `[i, j, k]` of linear index `idx` in a grid of `dims` (i fastest).
pub(super) fn grid_coords(idx: usize, dims: [usize; 3]) -> [usize; 3] {
    [
        idx % dims[0],
        (idx / dims[0]) % dims[1],
        idx / (dims[0] * dims[1]),
    ]
}

/// World corners of every block of `START_BLOCK`^3 macro cells holding an `active`
/// one. A block's box covers its cells' boxes (cell `c` spans voxels `4c ..= 4c + 4`),
/// so every sample that can show lies inside some block's box.
pub(super) fn visible_blocks(field: &Field, active: &[bool]) -> Vec<[Vec3; 8]> {
    let cd = field.cell_dims;
    let bd = cd.map(|c| c.div_ceil(START_BLOCK));
    let mut hit = vec![false; bd[0] * bd[1] * bd[2]];
    for (idx, _) in active.iter().enumerate().filter(|(_, v)| **v) {
        let b = grid_coords(idx, cd).map(|x| x / START_BLOCK);
        hit[b[0] + bd[0] * (b[1] + bd[1] * b[2])] = true;
    }
    let span = (START_BLOCK * MACRO_CELL) as f64;
    let mut out = Vec::new();
    for (idx, _) in hit.iter().enumerate().filter(|(_, v)| **v) {
        let b = grid_coords(idx, bd);
        let lo = b.map(|x| x as f64 * span);
        let hi = [0, 1, 2].map(|a| (lo[a] + span).min((field.dims[a] - 1) as f64));
        out.push(std::array::from_fn(|n| {
            let p = [0, 1, 2].map(|a| if n & (1 << a) != 0 { hi[a] } else { lo[a] });
            let w = field.index_to_world(p);
            Vec3::new(w[0] as f32, w[1] as f32, w[2] as f32)
        }));
    }
    out
}

/// The index-space box (voxel-centre coordinates) covering the `active` macro cells,
/// `None` when none is.
pub(super) fn active_bounds(field: &Field, active: &[bool]) -> Option<([f64; 3], [f64; 3])> {
    let cd = field.cell_dims;
    let mut lo = [usize::MAX; 3];
    let mut hi = [0usize; 3];
    for (idx, _) in active.iter().enumerate().filter(|(_, v)| **v) {
        let c = grid_coords(idx, cd);
        for a in 0..3 {
            lo[a] = lo[a].min(c[a] * MACRO_CELL);
            hi[a] = hi[a].max(((c[a] + 1) * MACRO_CELL).min(field.dims[a] - 1));
        }
    }
    (lo[0] != usize::MAX).then(|| (lo.map(|x| x as f64), hi.map(|x| x as f64)))
}

/// Chessboard (L-infinity) distance from every macro cell to the nearest `active` one,
/// in cells, saturating at 255: the exact two-pass chamfer transform with the 26
/// neighbours (Rosenfeld and Pfaltz 1966), O(cells). Each row takes the minimum over
/// its 12 neighbours in earlier (later) rows in one vectorisable sweep, then the one
/// along the row in a short serial sweep.
pub(super) fn chessboard_distance(active: &[bool], dims: [usize; 3]) -> Vec<u8> {
    // Padded by one cell on every side (never active) so neighbours need no checks.
    let [px, py, pz] = dims.map(|d| d + 2);
    let row = |y: usize, z: usize| px * (y + py * z);
    let mut d = vec![u8::MAX; px * py * pz];
    for z in 0..dims[2] {
        for y in 0..dims[1] {
            let src = &active[dims[0] * (y + dims[1] * z)..][..dims[0]];
            let dst = &mut d[row(y + 1, z + 1) + 1..][..dims[0]];
            for (o, &a) in dst.iter_mut().zip(src) {
                *o = if a { 0 } else { u8::MAX };
            }
        }
    }
    // Minimum of row `r` at x-1, x, x+1 into `m[x-1]` for x = 1..px-1.
    let min3 = |m: &mut [u8], r: &[u8]| {
        for (((o, &a), &b), &c) in m.iter_mut().zip(r).zip(&r[1..]).zip(&r[2..]) {
            *o = (*o).min(a.min(b).min(c));
        }
    };
    let mut m = vec![u8::MAX; px - 2];
    for z in 1..pz - 1 {
        for y in 1..py - 1 {
            let start = row(y, z);
            let (before, after) = d.split_at_mut(start);
            m.fill(u8::MAX);
            for ny in y - 1..=y + 1 {
                min3(&mut m, &before[row(ny, z - 1)..][..px]);
            }
            min3(&mut m, &before[row(y - 1, z)..][..px]);
            let cur = &mut after[..px];
            for (c, &n) in cur[1..px - 1].iter_mut().zip(&m) {
                *c = (*c).min(n.saturating_add(1));
            }
            for x in 1..px - 1 {
                cur[x] = cur[x].min(cur[x - 1].saturating_add(1));
            }
        }
    }
    for z in (1..pz - 1).rev() {
        for y in (1..py - 1).rev() {
            let start = row(y, z);
            let base = start + px;
            let (before, after) = d.split_at_mut(base);
            m.fill(u8::MAX);
            for ny in y - 1..=y + 1 {
                min3(&mut m, &after[row(ny, z + 1) - base..][..px]);
            }
            min3(&mut m, &after[row(y + 1, z) - base..][..px]);
            let cur = &mut before[start..];
            for (c, &n) in cur[1..px - 1].iter_mut().zip(&m) {
                *c = (*c).min(n.saturating_add(1));
            }
            for x in (1..px - 1).rev() {
                cur[x] = cur[x].min(cur[x + 1].saturating_add(1));
            }
        }
    }
    let mut out = Vec::with_capacity(active.len());
    for z in 0..dims[2] {
        for y in 0..dims[1] {
            out.extend_from_slice(&d[row(y + 1, z + 1) + 1..][..dims[0]]);
        }
    }
    out
}

#[cfg(test)]
mod distance_tests {
    use super::{chessboard_distance, grid_coords};

    #[test]
    fn chessboard_distance_matches_brute_force() {
        let dims = [9, 7, 6];
        let n = dims.iter().product::<usize>();
        // Scattered active cells (a fixed pattern), then none at all.
        let scattered: Vec<bool> = (0..n).map(|i| (i * 37) % 101 == 3).collect();
        assert!(scattered.iter().filter(|a| **a).count() >= 3);
        for act in [scattered, vec![false; n]] {
            let d = chessboard_distance(&act, dims);
            let coords = |i: usize| grid_coords(i, dims);
            let cells: Vec<[usize; 3]> = (0..n).filter(|&i| act[i]).map(coords).collect();
            for (i, &di) in d.iter().enumerate() {
                let c = coords(i);
                let expect = cells
                    .iter()
                    .map(|a| (0..3).map(|k| c[k].abs_diff(a[k])).max().unwrap())
                    .min();
                match expect {
                    Some(e) => assert_eq!(di as usize, e, "cell {c:?}"),
                    // Nothing active: every distance is at least the grid's extent.
                    None => assert!(di as usize >= dims[0], "cell {c:?}: {di}"),
                }
            }
        }
    }
}
