//! Meshes as occluders of the volume's light: the scene's triangles voxelised
//! conservatively onto the light volumes' grid (a grid point is occupied when a
//! triangle touches its cell, the box of one grid step around it), in the field's
//! index space after the meshes' placement in world space. The `shadows` sweep makes
//! occupied grid points opaque (transmittance 0 there and beyond, towards the
//! shadow); the path tracer ends shadow rays and scattered paths at the first
//! occupied cell they enter. Meshes neither reflect nor scatter light here.
//!
//! The triangle-box test is the separating-axis test of Akenine-Möller ("Fast 3D
//! triangle-box overlap testing", Journal of Graphics Tools 6(1), 2001): 13 axes.
//! Written here: the crates that have it (parry3d and the like) bring a whole
//! geometry library for one predicate.

use rayon::prelude::*;

use glint_core::Vec3;

use super::tracking::{CellWalk, IndexRay};
use super::{grid_len, LIGHT_CELL};
use crate::field::{Field, MACRO_CELL};

/// Added to the half edge of a grid cell in the overlap test, so triangles lying on a
/// cell face (a plane at a half-integer grid position) mark both cells: the
/// voxelisation errs towards occupied.
const CONSERVATIVE_SLACK: f64 = 1e-6;

/// Triangles per parallel task of the voxelisation.
const CHUNK: usize = 4096;

/// The grid points of a field's light-volume grid that meshes occupy. The same for
/// the same triangles in any order and on any thread count.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct Occluders {
    /// Grid points along each index axis (the light volumes' grid).
    dims: [usize; 3],
    /// Per grid point, `i + dims[0] * (j + dims[1] * k)`: whether a triangle
    /// touches its cell.
    occupied: Vec<bool>,
    /// How many grid points are occupied.
    count: usize,
}

impl Occluders {
    /// The cells of `field`'s light-volume grid touched by `triangles` (corners in
    /// world mm, the frame of the field's affine). Triangles wholly outside the grid
    /// occupy nothing; non-finite corners are skipped.
    pub fn new(field: &Field, triangles: impl IntoIterator<Item = [Vec3; 3]>) -> Occluders {
        let dims = field.dims().map(grid_len);
        let h = LIGHT_CELL as f64;
        let to_grid = |v: Vec3| {
            let p = field.world_to_index([f64::from(v.x), f64::from(v.y), f64::from(v.z)]);
            p.map(|x| x / h)
        };
        let tris: Vec<[[f64; 3]; 3]> = triangles.into_iter().map(|t| t.map(to_grid)).collect();
        let hits: Vec<Vec<usize>> = tris
            .par_chunks(CHUNK)
            .map(|chunk| {
                let mut out = Vec::new();
                for t in chunk {
                    touched_points(t, dims, &mut out);
                }
                out
            })
            .collect();
        let mut occupied = vec![false; dims.iter().product()];
        for i in hits.into_iter().flatten() {
            occupied[i] = true;
        }
        let count = occupied.iter().filter(|&&o| o).count();
        Occluders {
            dims,
            occupied,
            count,
        }
    }

    /// Grid points along each index axis.
    pub fn dims(&self) -> [usize; 3] {
        self.dims
    }

    /// How many grid points are occupied.
    pub fn count(&self) -> usize {
        self.count
    }

    /// Whether grid point `[i, j, k]` is occupied.
    #[inline(always)]
    pub fn occupied(&self, [i, j, k]: [usize; 3]) -> bool {
        self.occupied[i + self.dims[0] * (j + self.dims[1] * k)]
    }

    /// The parameter (mm) at which `ray` enters the first occupied cell over
    /// `[t0, t1]`, the cell it starts in excluded (a sample next to a mesh is not
    /// shadowed by the mesh it lies against: the bias the light volumes' lookup has).
    /// `None` when it enters none.
    pub(crate) fn first_hit(&self, ray: &IndexRay, t0: f32, t1: f32) -> Option<f32> {
        if self.count == 0 {
            return None;
        }
        // The walk of macro cells over a ray scaled so that one of its cells is one
        // grid cell: cell `c` holds index positions `[h c - h/2, h c + h/2)`, the cell
        // of grid point `c`. Both scale factors are powers of two: exact.
        let s = (MACRO_CELL / LIGHT_CELL) as f32;
        let half = LIGHT_CELL as f32 / 2.0;
        let scaled = IndexRay {
            o: (ray.o + Vec3::new(half, half, half)) * s,
            d: ray.d * s,
        };
        let bound = self.dims.map(|d| d * MACRO_CELL + 1);
        let (a, b) = scaled.clip(bound, t0, t1)?;
        let mut walk = CellWalk::new(&scaled, a, b, self.dims);
        walk.next_cell()?;
        while let Some((cell, enter, _)) = walk.next_cell() {
            if self.occupied[cell] {
                return Some(enter);
            }
        }
        None
    }
}

/// Appends the linear indices of the grid points (grid `dims`) whose cells triangle
/// `t` (grid units) touches.
fn touched_points(t: &[[f64; 3]; 3], dims: [usize; 3], out: &mut Vec<usize>) {
    if t.iter().flatten().any(|x| !x.is_finite()) {
        return;
    }
    let half = 0.5 + CONSERVATIVE_SLACK;
    let mut lo = [0usize; 3];
    let mut hi = [0usize; 3];
    for a in 0..3 {
        let mn = t[0][a].min(t[1][a]).min(t[2][a]) - half;
        let mx = t[0][a].max(t[1][a]).max(t[2][a]) + half;
        let top = (dims[a] - 1) as f64;
        if mx < 0.0 || mn > top {
            return;
        }
        lo[a] = mn.max(0.0).ceil() as usize;
        hi[a] = mx.min(top).floor() as usize;
        if lo[a] > hi[a] {
            return;
        }
    }
    for k in lo[2]..=hi[2] {
        for j in lo[1]..=hi[1] {
            for i in lo[0]..=hi[0] {
                let c = [i as f64, j as f64, k as f64];
                let v = t.map(|p| [p[0] - c[0], p[1] - c[1], p[2] - c[2]]);
                if triangle_touches_box(&v, half) {
                    out.push(i + dims[0] * (j + dims[1] * k));
                }
            }
        }
    }
}

fn sub(a: [f64; 3], b: [f64; 3]) -> [f64; 3] {
    [a[0] - b[0], a[1] - b[1], a[2] - b[2]]
}

fn cross(a: [f64; 3], b: [f64; 3]) -> [f64; 3] {
    [
        a[1] * b[2] - a[2] * b[1],
        a[2] * b[0] - a[0] * b[2],
        a[0] * b[1] - a[1] * b[0],
    ]
}

/// Whether the triangle `v` (relative to the box's centre) and the box of half edge
/// `h` overlap: no separating axis among the box's 3 face normals, the triangle's
/// normal and the 9 cross products of the box's edges with the triangle's
/// (Akenine-Möller 2001). A zero axis (a degenerate triangle's) separates nothing.
fn triangle_touches_box(v: &[[f64; 3]; 3], h: f64) -> bool {
    let separates = |a: [f64; 3]| {
        let p = v.map(|x| a[0] * x[0] + a[1] * x[1] + a[2] * x[2]);
        let r = h * (a[0].abs() + a[1].abs() + a[2].abs());
        p[0].min(p[1]).min(p[2]) > r || p[0].max(p[1]).max(p[2]) < -r
    };
    let units = [[1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 1.0]];
    if units.iter().any(|&e| separates(e)) {
        return false;
    }
    let edges = [sub(v[1], v[0]), sub(v[2], v[1]), sub(v[0], v[2])];
    if separates(cross(edges[0], edges[1])) {
        return false;
    }
    !units
        .iter()
        .any(|&e| edges.iter().any(|&f| separates(cross(e, f))))
}

#[cfg(test)]
mod tests {
    use super::*;
    use glint_io::{Samples, Volume};

    #[test]
    fn rays_meet_the_first_occupied_cell_after_their_own() {
        let vol = Volume::new([16; 3], [1.0; 3], Samples::F32(vec![0.0; 16 * 16 * 16])).unwrap();
        let field = Field::new(&vol).unwrap();
        // A small triangle near (8, 8, 8): grid point (4, 4, 4) alone, whose cell
        // holds index positions 7..9 along each axis.
        let tri = [
            Vec3::new(8.0, 7.9, 8.0),
            Vec3::new(8.2, 7.9, 8.1),
            Vec3::new(8.1, 8.1, 8.2),
        ];
        let occ = Occluders::new(&field, [tri]);
        assert_eq!(occ.dims(), [9; 3]);
        assert_eq!(occ.count(), 1);
        assert!(occ.occupied([4, 4, 4]));
        let ray = |o: [f32; 3], d: [f32; 3]| IndexRay {
            o: Vec3::new(o[0], o[1], o[2]),
            d: Vec3::new(d[0], d[1], d[2]),
        };
        let inf = f32::INFINITY;
        let hit = occ.first_hit(&ray([2.0, 8.0, 8.0], [1.0, 0.0, 0.0]), 0.0, inf);
        assert_eq!(hit, Some(5.0));
        // Towards -x at 2 index units per mm: the cell's face x = 9 at 2.5 mm.
        let hit = occ.first_hit(&ray([14.0, 8.0, 8.0], [-2.0, 0.0, 0.0]), 0.0, inf);
        assert_eq!(hit, Some(2.5));
        // Not within [0, 2] mm; a ray beside the cell; a ray leaving it (its own
        // cell is skipped: the bias).
        assert_eq!(
            occ.first_hit(&ray([14.0, 8.0, 8.0], [-2.0, 0.0, 0.0]), 0.0, 2.0),
            None
        );
        assert_eq!(
            occ.first_hit(&ray([2.0, 10.5, 8.0], [1.0, 0.0, 0.0]), 0.0, inf),
            None
        );
        assert_eq!(
            occ.first_hit(&ray([8.0, 8.0, 8.0], [0.0, 0.0, 1.0]), 0.0, inf),
            None
        );
        // Empty occupancy: nothing, whatever the ray.
        let none = Occluders::new(&field, []);
        assert_eq!(none.count(), 0);
        assert_eq!(
            none.first_hit(&ray([2.0, 8.0, 8.0], [1.0, 0.0, 0.0]), 0.0, inf),
            None
        );
    }

    #[test]
    fn the_box_test_finds_overlaps_and_gaps() {
        let h = 0.5;
        // A triangle through the centre.
        assert!(triangle_touches_box(
            &[[-2.0, -2.0, 0.0], [2.0, -2.0, 0.0], [0.0, 2.0, 0.0]],
            h
        ));
        // A big triangle whose plane misses the box (z = 0.6).
        assert!(!triangle_touches_box(
            &[[-5.0, -5.0, 0.6], [5.0, -5.0, 0.6], [0.0, 5.0, 0.6]],
            h
        ));
        // Its bounding box holds the box's corner region but an edge axis separates:
        // the hypotenuse x + y = 1.2 passes outside the corner (0.5, 0.5).
        assert!(!triangle_touches_box(
            &[[1.2, 0.0, 0.0], [0.0, 1.2, 0.0], [3.0, 3.0, 0.0]],
            h
        ));
        // The same at x + y = 0.9 crosses it.
        assert!(triangle_touches_box(
            &[[0.9, 0.0, 0.0], [0.0, 0.9, 0.0], [3.0, 3.0, 0.0]],
            h
        ));
        // A degenerate triangle (a point) inside the box touches it; outside not.
        assert!(triangle_touches_box(&[[0.1, 0.2, 0.3]; 3], h));
        assert!(!triangle_touches_box(&[[0.1, 0.2, 0.7]; 3], h));
    }
}
