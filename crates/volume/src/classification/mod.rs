//! Classification: a field classified by a transfer function ([`Classification`]),
//! with what the classification is built from and keeps: the transfer function and
//! its presets, its tables (point-sampled and pre-integrated), the empty-space map,
//! the colour volume, and, built on first use by light transport, the medium, its
//! extinction on the light volumes' grid and the ambient occlusion. Below both the ray
//! caster (`raycast`) and the light transport (`transport`), which read it.

use std::sync::{Arc, OnceLock};

use glint_core::{RenderError, RenderMode, Vec3};

use crate::field::Field;

mod cells;
mod colour;
mod density;
mod exchange;
mod lut;
mod medium;
pub(crate) mod preint;
pub mod presets;
mod settings;
mod tf;

#[cfg(test)]
pub(crate) use cells::START_BLOCK;
use cells::{active_bounds, chessboard_distance, visible_blocks, visible_cells};
pub use colour::ColourVolume;
pub use density::LIGHT_CELL;
pub(crate) use density::{grid_len, occlusion_grid, DensityGrid};
pub use exchange::TfFormat;
pub use lut::{Lut, LUT_SIZE};
pub(crate) use medium::Medium;
pub(crate) use preint::Last;
pub use preint::{PreIntegratedTables, Sampling};
pub use settings::ClassifySettings;
pub use tf::{TransferFunction, TransferFunctionFile, WindowLevel};

/// The transfer function tabulated for `settings` (MIP shows the function's own
/// opacity, not a per-step one).
fn lut_for(field: &Field, tf: &TransferFunction, settings: &ClassifySettings) -> Lut {
    let (lo, hi) = table_range(field, tf);
    // The opacity correction's exponent: the step in units of the opacity's length.
    let lut_step = match (settings.mode, settings.opacity_unit) {
        (RenderMode::Mip, _) => 1.0,
        (_, None) => settings.step,
        (_, Some(unit)) => settings.step * field.min_spacing() / unit,
    };
    Lut::new(tf, lo, hi, lut_step)
}

/// How many times wider than the robust range the value range may be before the
/// table covers the transfer function's domain instead (issue 33: a float volume
/// with a few voxels at 1e29 put every other value into the table's first entry, and
/// rendered black). Ordinary scans stay far below it (CT: full range over robust
/// range about 1.5), so their tables, and images, are unchanged.
const OUTLIER_SPAN: f64 = 1000.0;

/// The values the table covers: the volume's range, or, when a few outliers stretch
/// it past [`OUTLIER_SPAN`] times the robust range, the part of it the transfer
/// function's domain covers (lookups beyond the table take its end entries, the
/// function's values beyond its domain).
fn table_range(field: &Field, tf: &TransferFunction) -> (f32, f32) {
    let (lo, hi) = field.range();
    let (rlo, rhi) = field.robust_range();
    let span = f64::from(hi) - f64::from(lo);
    let robust = (f64::from(rhi) - f64::from(rlo)).max(f64::MIN_POSITIVE);
    if span <= OUTLIER_SPAN * robust {
        return (lo, hi);
    }
    let (tlo, thi) = tf.domain();
    let a = (tlo as f32).clamp(lo, hi);
    let b = (thi as f32).clamp(lo, hi);
    if b > a {
        (a, b)
    } else {
        (lo, hi)
    }
}

/// Whether the affine's axes are far from orthogonal (the cosine of some pair's angle
/// above 0.1, about 84 degrees): scanners' grids, oblique or not, are orthogonal
/// (a CT gantry tilt above about 6 degrees counts too, and is framed the same way).
fn sheared(affine: &[[f64; 4]; 4]) -> bool {
    let col = |c: usize| [affine[0][c], affine[1][c], affine[2][c]];
    let dot = |a: [f64; 3], b: [f64; 3]| a[0] * b[0] + a[1] * b[1] + a[2] * b[2];
    [(0, 1), (0, 2), (1, 2)].iter().any(|&(i, j)| {
        let (a, b) = (col(i), col(j));
        dot(a, b).abs() > 0.1 * (dot(a, a) * dot(b, b)).sqrt()
    })
}

/// The world box of the voxels whose value the table gives opacity (`None`: none).
fn opaque_world_box(field: &Field, lut: &Lut) -> Option<([f64; 3], [f64; 3])> {
    let [nx, ny, _] = field.dims;
    let mut lo = [f64::INFINITY; 3];
    let mut hi = [f64::NEG_INFINITY; 3];
    for (i, &v) in field.values().iter().enumerate() {
        if lut.opaque[lut.index(v)] == 0 {
            continue;
        }
        let p = [
            (i % nx) as f64,
            (i / nx % ny) as f64,
            (i / (nx * ny)) as f64,
        ];
        let w = field.index_to_world(p);
        for a in 0..3 {
            lo[a] = lo[a].min(w[a]);
            hi[a] = hi[a].max(w[a]);
        }
    }
    (lo[0] <= hi[0]).then_some((lo, hi))
}

/// A field classified by a transfer function for one mode and sample step: the
/// tabulated transfer function, the empty-space map (per macro cell, the chessboard
/// distance to the nearest cell that can show a sample) and the boxes rays are clipped
/// to and cameras framed on.
///
/// Building it reads every macro cell; rendering only reads it. An interactive viewer
/// builds it once per transfer function and renders every frame that changes only the
/// camera, lights, lobe or image size from it (VTK's ray-cast mapper likewise keeps its
/// min-max volume until the transfer function changes).
pub struct Classification {
    pub(crate) field: Arc<Field>,
    pub(crate) lut: Lut,
    pub(crate) settings: ClassifySettings,
    /// Per macro cell: 0 where a sample can contribute, else the chessboard distance in
    /// cells to the nearest such cell (capped at 255); every cell closer than that is
    /// empty. All 0 when skipping is off.
    pub(crate) distance: Vec<u8>,
    /// Index-space box of the cells that can show a sample (`None`: no such cell).
    pub(crate) visible_box: Option<([f64; 3], [f64; 3])>,
    /// Index-space box rays are clipped to.
    pub(crate) clip_box: ([f64; 3], [f64; 3]),
    /// For a sheared grid in composite mode: the world box of the voxels the transfer
    /// function gives opacity, which cameras frame ([`sheared`]).
    pub(crate) opaque_world: Option<([f64; 3], [f64; 3])>,
    /// World corners of the blocks of `START_BLOCK`^3 macro cells that hold a cell
    /// that can show a sample, for the rays' start bounds (empty when skipping is off
    /// or in MIP, whose leaps depend on the ray's maximum so far).
    pub(crate) blocks: Vec<[Vec3; 8]>,
    /// The transfer function, for light transport's medium.
    pub(crate) tf: TransferFunction,
    /// Built on first use by light transport: the medium (extinction and colour per
    /// value, majorants per macro cell), the extinction on the light volumes' grid,
    /// and its local ambient occlusion.
    pub(crate) medium: OnceLock<Medium>,
    pub(crate) density: OnceLock<DensityGrid>,
    pub(crate) occlusion: OnceLock<Arc<Vec<f32>>>,
    /// [`Classification::with_colour`].
    pub(crate) colour: Option<Arc<ColourVolume>>,
}

impl Classification {
    /// Classifies `field` by `tf` for the mode, step and empty-space skipping of
    /// `settings`. The classification keeps the field, so frames can be rendered from
    /// it alone (a viewer or a Python object holds it across frames).
    pub fn new(
        field: Arc<Field>,
        tf: &TransferFunction,
        settings: &ClassifySettings,
    ) -> Result<Classification, RenderError> {
        settings.validate()?;
        tf.validate()?;
        let lut = lut_for(&field, tf, settings);
        let visible = visible_cells(&field, &lut, settings);
        let visible_box = active_bounds(&field, &visible);
        let full_box = ([0.0; 3], field.dims.map(|d| (d - 1) as f64));
        let (distance, clip_box) = if settings.skip_empty {
            let clip_box = if settings.mode == RenderMode::Mip {
                full_box
            } else {
                visible_box.unwrap_or(([0.0; 3], [-1.0; 3]))
            };
            (chessboard_distance(&visible, field.cell_dims), clip_box)
        } else {
            (vec![0; visible.len()], full_box)
        };
        let opaque_world = match settings.mode {
            RenderMode::Composite if sheared(&field.affine()) => opaque_world_box(&field, &lut),
            _ => None,
        };
        let blocks = if settings.skip_empty && settings.mode != RenderMode::Mip {
            visible_blocks(&field, &visible)
        } else {
            Vec::new()
        };
        Ok(Classification {
            field,
            lut,
            blocks,
            settings: *settings,
            distance,
            visible_box,
            clip_box,
            tf: tf.clone(),
            medium: OnceLock::new(),
            density: OnceLock::new(),
            occlusion: OnceLock::new(),
            opaque_world,
            colour: None,
        })
    }

    /// The classification with each composite or iso sample's colour taken from
    /// `colour` (a colour volume's data, trilinear) instead of the transfer function:
    /// the transfer function of the field's grey values still gives the opacity, and
    /// the field's gradient the normal. MIP keeps the transfer function's colour, and
    /// the `path` model's medium the transfer function's albedo. Frames with colour
    /// run the reference compositing loop (the SIMD loop reads no colour). Refused when
    /// `colour`'s grid is not the field's.
    pub fn with_colour(mut self, colour: Arc<ColourVolume>) -> Result<Classification, RenderError> {
        if colour.dims() != self.field.dims {
            return Err(RenderError::Parameter(format!(
                "colour volume of {:?} voxels for a field of {:?}",
                colour.dims(),
                self.field.dims
            )));
        }
        self.colour = Some(colour);
        Ok(self)
    }

    /// The colours samples take ([`Classification::with_colour`]); `None`: the
    /// transfer function's.
    pub fn colour(&self) -> Option<&Arc<ColourVolume>> {
        self.colour.as_ref()
    }

    /// The classified field as a participating medium (built on first use).
    pub(crate) fn medium(&self) -> &Medium {
        self.medium.get_or_init(|| {
            let unit = self
                .settings
                .opacity_unit
                .unwrap_or_else(|| self.field.min_spacing());
            Medium::new(&self.field, &self.tf, unit)
        })
    }

    /// The extinction on the light volumes' grid (built on first use).
    pub(crate) fn density(&self) -> &DensityGrid {
        self.density
            .get_or_init(|| DensityGrid::new(&self.field, self.medium()))
    }

    /// The local ambient occlusion on the light volumes' grid (built on first use).
    pub(crate) fn occlusion(&self) -> Arc<Vec<f32>> {
        self.occlusion
            .get_or_init(|| Arc::new(occlusion_grid(self.density(), |_| true)))
            .clone()
    }

    /// The field it classifies.
    pub fn field(&self) -> &Arc<Field> {
        &self.field
    }

    /// The settings it was built for.
    pub fn settings(&self) -> &ClassifySettings {
        &self.settings
    }
}
