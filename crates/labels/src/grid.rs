//! Label grids: a volume's samples as whole-number labels, placed by its affine, with
//! per-label voxel counts, millilitres and bounding boxes.

use std::collections::BTreeMap;

use glint_io::{Samples, Volume};

use crate::LabelError;

/// A label volume: one label per voxel (0 is background), `labels[i + dims[0] * (j +
/// dims[1] * k)]` as in [`Volume`], placed in world mm (RAS+) by `affine`.
#[derive(Clone, Debug, PartialEq)]
pub struct LabelGrid {
    /// Voxels along i, j, k.
    pub dims: [usize; 3],
    /// Voxel index (i, j, k, 1) to world RAS+ mm, row-major.
    pub affine: [[f64; 4]; 4],
    /// The label of each voxel.
    pub labels: Vec<u32>,
}

/// Where one label is in a grid, and how much of it there is.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct LabelExtent {
    /// Voxels with the label.
    pub voxels: u64,
    /// The smallest (i, j, k) of those voxels.
    pub lo: [usize; 3],
    /// The largest (i, j, k) of those voxels.
    pub hi: [usize; 3],
}

impl LabelGrid {
    /// The labels of `volume`: its physical values (`slope * stored + intercept`),
    /// which must be whole numbers in `0..=u32::MAX`. Refused with the reason: a
    /// colour volume, a non-integer value (e.g. an interpolated or probability map),
    /// a negative or NaN value.
    pub fn from_volume(volume: &Volume) -> Result<LabelGrid, LabelError> {
        if volume.is_colour() {
            return Err(LabelError::NotLabels(
                "a colour volume holds colours, not labels".into(),
            ));
        }
        let (s, b) = (volume.slope, volume.intercept);
        let to_label = |i: usize, x: f64| -> Result<u32, LabelError> {
            let v = s * x + b;
            if v.is_finite() && v >= 0.0 && v <= f64::from(u32::MAX) && v.fract() == 0.0 {
                Ok(v as u32)
            } else {
                let dims = volume.dims;
                let (x, y, z) = (i % dims[0], i / dims[0] % dims[1], i / (dims[0] * dims[1]));
                Err(LabelError::NotLabels(format!(
                    "voxel ({x}, {y}, {z}) is {v}: labels are whole numbers from 0 (a probability map or resampled labels need rounding first)"
                )))
            }
        };
        let identity = s == 1.0 && b == 0.0;
        let labels = match &volume.samples {
            Samples::U8(v) if identity => v.iter().map(|&x| u32::from(x)).collect(),
            Samples::U16(v) if identity => v.iter().map(|&x| u32::from(x)).collect(),
            Samples::U32(v) if identity => v.clone(),
            other => (0..other.len())
                .map(|i| to_label(i, other.get(i)))
                .collect::<Result<Vec<u32>, _>>()?,
        };
        Ok(LabelGrid {
            dims: volume.dims,
            affine: volume.affine,
            labels,
        })
    }

    /// The volume of one voxel in millilitres (|det| of the affine's linear part, in
    /// mm^3, / 1000).
    pub fn voxel_ml(&self) -> f64 {
        let a = &self.affine;
        let det = a[0][0] * (a[1][1] * a[2][2] - a[1][2] * a[2][1])
            - a[0][1] * (a[1][0] * a[2][2] - a[1][2] * a[2][0])
            + a[0][2] * (a[1][0] * a[2][1] - a[1][1] * a[2][0]);
        det.abs() / 1000.0
    }

    /// The voxel size in mm along i, j, k (the column norms of the affine).
    pub fn spacing(&self) -> [f64; 3] {
        std::array::from_fn(|c| {
            (0..3)
                .map(|r| self.affine[r][c].powi(2))
                .sum::<f64>()
                .sqrt()
        })
    }

    /// Every label present except 0 (background), with its voxel count and bounding
    /// box, in one pass.
    pub fn summary(&self) -> BTreeMap<u32, LabelExtent> {
        let [nx, ny, _] = self.dims;
        let mut out: BTreeMap<u32, LabelExtent> = BTreeMap::new();
        // Runs of one label along i are common: look the extent up once per run.
        let mut i = 0;
        while i < self.labels.len() {
            let v = self.labels[i];
            let mut end = i + 1;
            let row_end = (i / nx + 1) * nx;
            while end < row_end && self.labels[end] == v {
                end += 1;
            }
            if v != 0 {
                let (x0, x1) = (i % nx, (end - 1) % nx);
                let (y, z) = (i / nx % ny, i / (nx * ny));
                let e = out.entry(v).or_insert(LabelExtent {
                    voxels: 0,
                    lo: [x0, y, z],
                    hi: [x1, y, z],
                });
                e.voxels += (end - i) as u64;
                e.lo = [e.lo[0].min(x0), e.lo[1].min(y), e.lo[2].min(z)];
                e.hi = [e.hi[0].max(x1), e.hi[1].max(y), e.hi[2].max(z)];
            }
            i = end;
        }
        out
    }

    /// The world (RAS+ mm) bounding box of the grid's voxel centres.
    pub fn world_bounds(&self) -> ([f64; 3], [f64; 3]) {
        world_box(self.dims, &self.affine)
    }
}

/// The world bounding box of the voxel centres of a `dims` grid placed by `affine`.
pub fn world_box(dims: [usize; 3], affine: &[[f64; 4]; 4]) -> ([f64; 3], [f64; 3]) {
    {
        let mut lo = [f64::INFINITY; 3];
        let mut hi = [f64::NEG_INFINITY; 3];
        for c in 0..8 {
            let idx = [0, 1, 2].map(|a| {
                if c >> a & 1 == 1 {
                    (dims[a] - 1) as f64
                } else {
                    0.0
                }
            });
            for r in 0..3 {
                let w = (0..3).map(|a| affine[r][a] * idx[a]).sum::<f64>() + affine[r][3];
                lo[r] = lo[r].min(w);
                hi[r] = hi[r].max(w);
            }
        }
        (lo, hi)
    }
}
