//! Planar polygons filled on a voxel grid: the rasteriser of RT structure set contours
//! (see `rtstruct`).
//!
//! Written here rather than taken from a crate: what is needed is a few dozen lines
//! (a scanline fill of voxel centres in index space with the even-odd rule over every
//! contour of a slice at once, so that a contour inside another is a hole, PS3.3
//! C.8.8.6.3), and the 2D rasterisers on crates.io (`imageproc`'s `draw_polygon`,
//! `tiny-skia`, `raqote`) draw into images of pixels, anti-alias or use the non-zero
//! rule, and pull in image stacks glint-io does not otherwise need.
//!
//! The rule is PNPOLY's crossing test (W. R. Franklin; the even-odd rule of
//! PostScript and SVG `fill-rule: evenodd`): a voxel centre is inside when a ray from
//! it along +i crosses the slice's contours an odd number of times. An edge is crossed
//! on row `j` when its end points lie on different sides of `y = j` with the half-open
//! rule (`y > j` on one end only), so a vertex on a row is counted once.

/// Largest distance (in slices) of a contour's points from the slice it is placed on:
/// half the slice spacing. A contour is matched to the nearest slice.
pub(super) const HALF_SLICE: f64 = 0.5;

/// Slack on [`HALF_SLICE`] for rounding in the world-to-index transform.
const SLICE_EPS: f64 = 1e-6;

/// Why a contour's points are not on one slice of the grid.
#[derive(Clone, Copy, Debug, PartialEq)]
pub(super) enum OffSlice {
    /// The points are not all within half a slice of one slice plane (lowest and
    /// highest continuous slice index): the contour is not parallel to the slices.
    Spread { lo: f64, hi: f64 },
    /// The points are in one plane, more than half a slice before the first slice or
    /// after the last (their mean continuous slice index).
    Outside { at: f64 },
}

/// The slice of a contour whose points are `ks` (continuous slice indices): the nearest
/// slice to their mean, when every point is within half a slice of it and it is one of
/// the grid's `slices`.
pub(super) fn slice_of(ks: &[f64], slices: usize) -> Result<usize, OffSlice> {
    let lo = ks.iter().copied().fold(f64::INFINITY, f64::min);
    let hi = ks.iter().copied().fold(f64::NEG_INFINITY, f64::max);
    let mean = ks.iter().sum::<f64>() / ks.len() as f64;
    let nearest = mean.round();
    let distance = (hi - nearest).max(nearest - lo);
    if distance.is_nan() || distance > HALF_SLICE + SLICE_EPS {
        return Err(OffSlice::Spread { lo, hi });
    }
    if nearest < 0.0 || nearest >= slices as f64 {
        return Err(OffSlice::Outside { at: mean });
    }
    Ok(nearest as usize)
}

/// The runs of voxel centres inside `polygons` (each a closed ring of (i, j) points,
/// continuous indices; the last point joins the first) on a `cols` x `rows` slice, by
/// the even-odd rule over all of them: `(row, first column, last column)`, rows in
/// order. Points outside the slice are clipped.
pub(super) fn fill(
    polygons: &[Vec<[f64; 2]>],
    cols: usize,
    rows: usize,
) -> Vec<(usize, usize, usize)> {
    let mut runs = Vec::new();
    let (mut ylo, mut yhi) = (f64::INFINITY, f64::NEG_INFINITY);
    for p in polygons.iter().flatten() {
        ylo = ylo.min(p[1]);
        yhi = yhi.max(p[1]);
    }
    if !(ylo.is_finite() && yhi.is_finite()) || rows == 0 || cols == 0 {
        return runs;
    }
    let first = ylo.ceil().max(0.0);
    let last = yhi.floor().min(rows as f64 - 1.0);
    if first > last {
        return runs;
    }
    let mut xs = Vec::new();
    for j in first as usize..=last as usize {
        let y = j as f64;
        xs.clear();
        for poly in polygons {
            let n = poly.len();
            for e in 0..n {
                let (a, b) = (poly[e], poly[(e + 1) % n]);
                if (a[1] > y) != (b[1] > y) {
                    xs.push(a[0] + (y - a[1]) * (b[0] - a[0]) / (b[1] - a[1]));
                }
            }
        }
        xs.sort_by(f64::total_cmp);
        // Column i is inside when an odd number of crossings lie beyond it (x > i):
        // between crossings 2m and 2m+1, x[2m] <= i < x[2m+1].
        for pair in xs.chunks_exact(2) {
            let from = pair[0].ceil().max(0.0);
            let to = (pair[1].ceil() - 1.0).min(cols as f64 - 1.0);
            if from <= to {
                runs.push((j, from as usize, to as usize));
            }
        }
    }
    runs
}

#[cfg(test)]
mod tests {
    use super::*;

    fn count(runs: &[(usize, usize, usize)]) -> usize {
        runs.iter().map(|r| r.2 - r.1 + 1).sum()
    }

    fn square(lo: f64, hi: f64) -> Vec<[f64; 2]> {
        vec![[lo, lo], [hi, lo], [hi, hi], [lo, hi]]
    }

    #[test]
    fn a_square_on_voxel_edges_fills_the_voxels_inside() {
        // Voxels 2..=5 in i and j, traced along their outer edges.
        let runs = fill(&[square(1.5, 5.5)], 10, 10);
        assert_eq!(count(&runs), 16);
        assert_eq!(runs.first(), Some(&(2, 2, 5)));
        assert_eq!(runs.last(), Some(&(5, 2, 5)));
        // Either winding.
        let mut cw = square(1.5, 5.5);
        cw.reverse();
        assert_eq!(fill(&[cw], 10, 10), runs);
        // Clipped at the slice's edges.
        assert_eq!(count(&fill(&[square(-3.5, 1.5)], 10, 10)), 4);
    }

    #[test]
    fn a_contour_inside_another_is_a_hole() {
        let outer = square(0.5, 8.5); // voxels 1..=8: 64
        let inner = square(3.5, 5.5); // voxels 4..=5: 4
        let runs = fill(&[outer.clone(), inner.clone()], 10, 10);
        assert_eq!(count(&runs), 60);
        assert!(!runs.iter().any(|&(j, a, b)| j == 4 && (a..=b).contains(&4)));
        // Order does not matter; a disjoint second contour adds to the first.
        assert_eq!(fill(&[inner, outer], 10, 10), runs);
        assert_eq!(
            count(&fill(&[square(0.5, 2.5), square(5.5, 7.5)], 10, 10)),
            8
        );
    }

    #[test]
    fn a_triangle_takes_the_centres_it_covers() {
        // Right triangle (0,0), (4,0), (0,4) in voxel centres: centres with i + j < 4
        // and the edges i = 0 / j = 0 included, the hypotenuse's far side not.
        let runs = fill(&[vec![[-0.01, -0.01], [4.0, -0.01], [-0.01, 4.0]]], 8, 8);
        assert_eq!(count(&runs), 4 + 3 + 2 + 1);
    }

    #[test]
    fn contours_are_matched_to_the_slice_within_half_the_spacing() {
        assert_eq!(slice_of(&[3.0, 3.0, 3.0], 10), Ok(3));
        assert_eq!(slice_of(&[3.4, 3.45, 3.4], 10), Ok(3));
        assert_eq!(slice_of(&[2.6, 2.6], 10), Ok(3));
        // Off-slice by more than half the spacing: before the first slice or after the
        // last, or not in one plane.
        assert_eq!(
            slice_of(&[-0.7, -0.7], 10),
            Err(OffSlice::Outside { at: -0.7 })
        );
        assert_eq!(
            slice_of(&[9.6, 9.6], 10),
            Err(OffSlice::Outside { at: 9.6 })
        );
        assert!(matches!(
            slice_of(&[2.4, 3.3], 10),
            Err(OffSlice::Spread { .. })
        ));
        assert!(matches!(
            slice_of(&[2.0, 3.5, 5.0], 10),
            Err(OffSlice::Spread { .. })
        ));
        assert!(slice_of(&[f64::NAN], 10).is_err());
    }
}
