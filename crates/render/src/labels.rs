//! Label maps as a scene layer ([`LabelSpec`]): a segmentation's labels, named and
//! coloured by a colour table, drawn as one smoothed surface per label through the
//! rasterizer (alone, or in a ray-cast volume's frame like other meshes), or ray cast
//! as a label volume in a volume's frame ([`LabelsAs`]), with a legend of the labels
//! shown.

use std::collections::BTreeMap;
use std::path::{Path, PathBuf};
use std::sync::Arc;

use glint_core::{srgb_to_linear, Legend, RenderError};
use glint_io::affine::{inverse3, linear_part, mul3};
use glint_io::{read_volume, Mesh, ReadOptions};
use glint_labels::{default_label_smoothing, label_surfaces_keeping_thin, LabelGrid, LabelTable};
use glint_volume::{LabelLook, LabelVolume};

use serde::{Deserialize, Serialize};

/// A label map of a scene: which file, which colour table, which labels.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct LabelSpec {
    /// The label volume (any volume glint reads whose values are whole numbers; 0 is
    /// background). It is placed by its own affine: its grid may differ from the
    /// volume's.
    pub path: PathBuf,
    /// The colour table: `freesurfer`, `totalsegmentator` (built in) or a table file
    /// (FreeSurfer LUT text, 3D Slicer `.ctbl`/`.txt`, `.json`, `.csv`). Default:
    /// `freesurfer` for files named like FreeSurfer's (`aseg`, `aparc`, `wmparc`),
    /// a DICOM Segmentation's own segments, else none (labels named by number,
    /// generated colours).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub table: Option<String>,
    /// Only these labels (names or numbers); empty: every label present.
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub show: Vec<String>,
    /// Not these labels (names or numbers).
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub hide: Vec<String>,
    /// Gaussian smoothing of the surfaces, in voxels of the label grid's coarsest axis
    /// (default from the grid's spacing, [`glint_labels::default_label_smoothing`]: 1
    /// for isotropic grids, 2 for thick slices; 0: voxel stairs). A label it would
    /// thin below [`glint_labels::MIN_KEPT`] of its voxels gets one voxel's at most
    /// ([`glint_labels::label_surfaces_keeping_thin`]).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub smoothing: Option<f32>,
    /// Whether the image lists the labels shown (default: yes).
    #[serde(default = "yes", skip_serializing_if = "is_true")]
    pub legend: bool,
    /// How the labels are drawn (default: surfaces).
    #[serde(default, skip_serializing_if = "LabelsAs::is_surfaces")]
    pub render_as: LabelsAs,
    /// Per-label opacity of the label volume (label name or number to 0..=1, the
    /// opacity of one voxel's length); labels not named take the table's alpha
    /// (opaque when it has none). Surfaces are always opaque.
    #[serde(default, skip_serializing_if = "BTreeMap::is_empty")]
    pub opacity: BTreeMap<String, f32>,
}

/// How a label map is drawn.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum LabelsAs {
    /// One smoothed surface per label, rasterised.
    #[default]
    Surfaces,
    /// A label volume ray cast in the intensity volume's frame: each sample takes its
    /// nearest voxel's label (no blending across labels), coloured and made opaque by
    /// the label, lit by the labels' smoothed boundary.
    Volume,
    /// Both: the surfaces, and the label volume in front of them.
    Both,
}

impl LabelsAs {
    /// Every value, as named in scene files and on the command line.
    pub const ALL: [LabelsAs; 3] = [LabelsAs::Surfaces, LabelsAs::Volume, LabelsAs::Both];

    /// The name in scene files and on the command line.
    pub fn name(self) -> &'static str {
        match self {
            LabelsAs::Surfaces => "surfaces",
            LabelsAs::Volume => "volume",
            LabelsAs::Both => "both",
        }
    }

    fn is_surfaces(&self) -> bool {
        *self == LabelsAs::Surfaces
    }

    fn surfaces(self) -> bool {
        self != LabelsAs::Volume
    }

    fn volume(self) -> bool {
        self != LabelsAs::Surfaces
    }
}

impl std::str::FromStr for LabelsAs {
    type Err = RenderError;

    fn from_str(s: &str) -> Result<LabelsAs, RenderError> {
        LabelsAs::ALL
            .into_iter()
            .find(|v| v.name() == s)
            .ok_or_else(|| {
                RenderError::Parameter(format!(
                    "labels as {s:?}: expected surfaces, volume or both"
                ))
            })
    }
}

fn yes() -> bool {
    true
}

fn is_true(b: &bool) -> bool {
    *b
}

impl LabelSpec {
    /// Every label of `path`, default table and smoothing, with a legend.
    pub fn new(path: impl Into<PathBuf>) -> LabelSpec {
        LabelSpec {
            path: path.into(),
            table: None,
            show: Vec::new(),
            hide: Vec::new(),
            smoothing: None,
            legend: true,
            render_as: LabelsAs::Surfaces,
            opacity: BTreeMap::new(),
        }
    }

    /// The table a file of this name defaults to.
    pub fn default_table(path: &Path) -> Option<String> {
        LabelTable::default_for(path).map(str::to_string)
    }

    /// Writes the defaults into the spec: the table, and the smoothing
    /// (`default_smoothing`, the label grid's: [`LabelLookup::default_smoothing`]).
    pub(crate) fn resolve(&mut self, default_smoothing: f32) {
        self.resolve_table();
        self.smoothing.get_or_insert(default_smoothing);
    }

    /// Writes the default table into the spec (the smoothing's default needs the
    /// label grid: [`LabelSpec::resolve`]).
    pub(crate) fn resolve_table(&mut self) {
        if self.table.is_none() {
            self.table = LabelSpec::default_table(&self.path);
        }
    }

    fn error(&self, e: impl std::error::Error + Send + Sync + 'static) -> RenderError {
        RenderError::Labels {
            path: self.path.clone(),
            source: Box::new(e),
        }
    }
}

/// How a scene's label map is read: an RT structure set onto the grid of `image`, the
/// scene's volume file (see [`glint_io::dicom::read_structure_set`]).
pub fn label_read_options(image: Option<&Path>) -> ReadOptions {
    ReadOptions {
        reference: image.map(Path::to_path_buf),
        ..ReadOptions::default()
    }
}

/// A label map's surfaces, read and extracted for a scene.
#[derive(Clone, Debug)]
pub(crate) struct LabelMeshes {
    /// One mesh per label shown (labels whose surface vanished are left out).
    pub(crate) meshes: Vec<Mesh>,
    /// Their colours, linear RGB.
    pub(crate) colors: Vec<[f32; 3]>,
    /// Their label values.
    pub(crate) values: Vec<u32>,
    /// The labels shown, in value order, when the scene asks for a legend.
    pub(crate) legend: Option<Legend>,
    /// The label grid's world box, voxel centres (min, max), mm.
    pub(crate) bounds: ([f64; 3], [f64; 3]),
    /// The labels shown as a label volume, when the spec asks for one.
    pub(crate) volume: Option<Arc<LabelVolume>>,
    /// The label of every voxel and their names, for picks.
    pub(crate) lookup: Arc<LabelLookup>,
}

impl LabelMeshes {
    /// Reads `spec`'s label volume and table (`spec`'s table resolved:
    /// [`LabelSpec::resolve_table`]; no smoothing: the grid's default)
    /// and extracts the surfaces of the labels it shows. `image` is the scene's volume
    /// file, the grid an RT structure set's contours are rasterised onto.
    pub(crate) fn build(
        spec: &LabelSpec,
        image: Option<&Path>,
    ) -> Result<LabelMeshes, RenderError> {
        let volume = read_volume(&spec.path, &label_read_options(image))?;
        let grid = LabelGrid::from_volume(&volume).map_err(|e| spec.error(e))?;
        drop(volume);
        let table =
            LabelTable::for_map(&spec.path, spec.table.as_deref()).map_err(|e| spec.error(e))?;
        let summary = grid.summary();
        let lookup = |names: &[String]| -> Result<Vec<u32>, RenderError> {
            names
                .iter()
                .map(|n| table.lookup(n).map_err(|e| spec.error(e)))
                .collect()
        };
        let show = lookup(&spec.show)?;
        let hide = lookup(&spec.hide)?;
        if let Some(v) = show.iter().find(|v| !summary.contains_key(v)) {
            return Err(RenderError::Parameter(format!(
                "label map {}: label {} ({}) is not in the map",
                spec.path.display(),
                v,
                table.name_of(*v)
            )));
        }
        let values: Vec<u32> = summary
            .keys()
            .copied()
            .filter(|v| show.is_empty() || show.contains(v))
            .filter(|v| !hide.contains(v))
            .collect();
        if values.is_empty() {
            return Err(RenderError::Parameter(format!(
                "label map {}: no label to show ({} labels present, all hidden or none)",
                spec.path.display(),
                summary.len()
            )));
        }
        let linear = |v: u32| {
            table
                .color_of(v)
                .map(|c| srgb_to_linear(f64::from(c) / 255.0) as f32)
        };
        let volume = spec
            .render_as
            .volume()
            .then(|| label_volume(spec, &grid, &values, &table, &linear))
            .transpose()?;
        let (meshes, colors) = if spec.render_as.surfaces() {
            if spec.render_as == LabelsAs::Surfaces && !spec.opacity.is_empty() {
                return Err(RenderError::Parameter(
                    "per-label opacity applies to a label volume (labels as volume or both); surfaces are opaque".into(),
                ));
            }
            let smoothing =
                (spec.smoothing).unwrap_or_else(|| default_label_smoothing(grid.spacing()));
            // Labels thinner than the smoothing keeps whole take one voxel's at most.
            let surfaces =
                label_surfaces_keeping_thin(&grid, &values, smoothing, smoothing.min(1.0))
                    .map_err(|e| spec.error(e))?;
            surfaces
                .into_iter()
                .filter(|(_, m, _)| !m.triangles.is_empty())
                .map(|(v, m, _)| (m, (linear(v), v)))
                .unzip()
        } else {
            (Vec::new(), Vec::new())
        };
        let (colors, surface_values) = colors.into_iter().unzip();
        let legend = spec.legend.then(|| Legend {
            entries: values
                .iter()
                .map(|&v| (table.name_of(v), linear(v)))
                .collect(),
        });
        let bounds = grid.world_bounds();
        Ok(LabelMeshes {
            meshes,
            colors,
            values: surface_values,
            legend,
            bounds,
            volume,
            lookup: Arc::new(LabelLookup::new(grid, table)),
        })
    }

    /// Refuses a label grid whose world box does not meet the volume's.
    pub(crate) fn check_overlap(
        &self,
        spec: &LabelSpec,
        volume: ([f64; 3], [f64; 3]),
    ) -> Result<(), RenderError> {
        let (a, b) = (self.bounds, volume);
        let apart = (0..3).any(|k| a.1[k] < b.0[k] || b.1[k] < a.0[k]);
        if apart {
            let fmt = |p: [f64; 3]| format!("({:.1}, {:.1}, {:.1})", p[0], p[1], p[2]);
            return Err(RenderError::Parameter(format!(
                "label map {} does not overlap the volume: its grid spans {} to {} mm, the volume {} to {} mm (RAS); are they of the same subject and space?",
                spec.path.display(),
                fmt(a.0),
                fmt(a.1),
                fmt(b.0),
                fmt(b.1)
            )));
        }
        Ok(())
    }
}

/// The label volume of the labels `values` of `grid`: each in its table colour
/// (`linear`) and with its table alpha as opacity, unless `spec.opacity` names it (by
/// name or number, looked up in `table`).
fn label_volume(
    spec: &LabelSpec,
    grid: &LabelGrid,
    values: &[u32],
    table: &LabelTable,
    linear: &dyn Fn(u32) -> [f32; 3],
) -> Result<Arc<LabelVolume>, RenderError> {
    let mut looks: BTreeMap<u32, LabelLook> = values
        .iter()
        .map(|&v| {
            let look = LabelLook {
                color: linear(v),
                opacity: f32::from(table.alpha_of(v)) / 255.0,
            };
            (v, look)
        })
        .collect();
    for (name, &opacity) in &spec.opacity {
        if !(0.0..=1.0).contains(&opacity) {
            return Err(RenderError::Parameter(format!(
                "label {name}: opacity {opacity} is not in 0..=1"
            )));
        }
        let v = table.lookup(name).map_err(|e| spec.error(e))?;
        // A hidden label, or one not in the map, stays undrawn.
        if let Some(l) = looks.get_mut(&v) {
            l.opacity = opacity;
        }
    }
    Ok(Arc::new(LabelVolume::new(
        grid.dims,
        grid.affine,
        &grid.labels,
        &looks,
    )?))
}

/// A label at a picked point.
#[derive(Clone, Debug, PartialEq, Eq, Serialize, Deserialize)]
pub struct PickLabel {
    /// The label's value in the label map.
    pub id: u32,
    /// Its name in the scene's colour table (`label N` when the table has none).
    pub name: String,
}

/// The label of every voxel of a scene's label map and the names of its table: what
/// a pick reads its label from.
#[derive(Clone, Debug)]
pub(crate) struct LabelLookup {
    dims: [usize; 3],
    /// World mm to voxel index: the inverse of the grid's affine, linear part and
    /// translation.
    to_index: ([[f64; 3]; 3], [f64; 3]),
    voxels: LabelVoxels,
    table: LabelTable,
    /// The grid's default surface smoothing ([`default_label_smoothing`]).
    default_smoothing: f32,
}

/// A label grid's values, two bytes a voxel when every value fits (nearly every
/// segmentation), four otherwise.
#[derive(Clone, Debug)]
enum LabelVoxels {
    U16(Vec<u16>),
    U32(Vec<u32>),
}

impl LabelLookup {
    /// The lookup of `grid` named by `table`.
    pub(crate) fn new(grid: LabelGrid, table: LabelTable) -> LabelLookup {
        let linear = linear_part(&grid.affine);
        // The grid was placed in the world (its surfaces extracted) with this affine,
        // which glint-io checked to be invertible; a singular one finds no label.
        let inverse = inverse3(&linear).unwrap_or([[f64::NAN; 3]; 3]);
        let shift = [0, 1, 2].map(|r| grid.affine[r][3]);
        let default_smoothing = default_label_smoothing(grid.spacing());
        let voxels = match grid.labels.iter().all(|&v| v <= u32::from(u16::MAX)) {
            true => LabelVoxels::U16(grid.labels.iter().map(|&v| v as u16).collect()),
            false => LabelVoxels::U32(grid.labels),
        };
        LabelLookup {
            dims: grid.dims,
            to_index: (inverse, shift),
            voxels,
            table,
            default_smoothing,
        }
    }

    /// The smoothing of the grid's surfaces when the scene gives none
    /// ([`default_label_smoothing`] of its spacing).
    pub(crate) fn default_smoothing(&self) -> f32 {
        self.default_smoothing
    }

    /// The name of label `id` in the table.
    pub(crate) fn name_of(&self, id: u32) -> String {
        self.table.name_of(id)
    }

    /// The label of the voxel nearest world point `p`; `None` off the grid or in the
    /// background (0).
    pub(crate) fn at(&self, p: [f64; 3]) -> Option<PickLabel> {
        let (inverse, shift) = &self.to_index;
        let index = mul3(inverse, [0, 1, 2].map(|a| p[a] - shift[a]));
        let [i, j, k] = nearest(index, self.dims)?;
        let n = i + self.dims[0] * (j + self.dims[1] * k);
        let id = match &self.voxels {
            LabelVoxels::U16(v) => u32::from(v[n]),
            LabelVoxels::U32(v) => v[n],
        };
        (id != 0).then(|| PickLabel {
            id,
            name: self.table.name_of(id),
        })
    }
}

/// The voxel nearest index-space point `p` of a grid of `dims`; `None` off the grid
/// (more than half a voxel past its outer voxel centres) or not finite.
pub(crate) fn nearest(p: [f64; 3], dims: [usize; 3]) -> Option<[usize; 3]> {
    let mut out = [0usize; 3];
    for a in 0..3 {
        let r = p[a].round();
        if !(r >= 0.0 && r < dims[a] as f64) {
            return None;
        }
        out[a] = r as usize;
    }
    Some(out)
}
