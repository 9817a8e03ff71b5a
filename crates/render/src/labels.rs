//! Label maps as a scene layer ([`LabelSpec`]): a segmentation's labels, named and
//! coloured by a colour table, drawn as one smoothed surface per label through the
//! rasterizer (alone, or in a ray-cast volume's frame like other meshes), with a
//! legend of the labels shown.

use std::path::{Path, PathBuf};

use glint_core::{srgb_to_linear, Legend, RenderError};
use glint_io::{read_volume, Mesh, ReadOptions};
use glint_labels::{label_surfaces, LabelGrid, LabelTable};
use serde::{Deserialize, Serialize};

/// Smoothing of label surfaces when the scene gives none: a Gaussian of one voxel
/// (of the label grid's coarsest axis) removes the voxel stairs and keeps structures
/// a few voxels thin (ribs, vessels) whole. glint's choice.
pub const DEFAULT_LABEL_SMOOTHING: f32 = 1.0;

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
    /// else none (labels named by number, generated colours).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub table: Option<String>,
    /// Only these labels (names or numbers); empty: every label present.
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub show: Vec<String>,
    /// Not these labels (names or numbers).
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub hide: Vec<String>,
    /// Gaussian smoothing of the surfaces, in voxels of the label grid's coarsest axis
    /// (default [`DEFAULT_LABEL_SMOOTHING`]; 0: voxel stairs).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub smoothing: Option<f32>,
    /// Whether the image lists the labels shown (default: yes).
    #[serde(default = "yes", skip_serializing_if = "is_true")]
    pub legend: bool,
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
        }
    }

    /// The table a file of this name defaults to.
    pub fn default_table(path: &Path) -> Option<String> {
        let name = path.file_name()?.to_string_lossy().to_ascii_lowercase();
        ["aseg", "aparc", "wmparc"]
            .iter()
            .any(|k| name.contains(k))
            .then(|| "freesurfer".to_string())
    }

    /// Writes the defaults (table, smoothing) into the spec.
    pub(crate) fn resolve(&mut self) {
        if self.table.is_none() {
            self.table = LabelSpec::default_table(&self.path);
        }
        self.smoothing.get_or_insert(DEFAULT_LABEL_SMOOTHING);
    }

    fn error(&self, e: impl std::error::Error + Send + Sync + 'static) -> RenderError {
        RenderError::Labels {
            path: self.path.clone(),
            source: Box::new(e),
        }
    }
}

/// A label map's surfaces, read and extracted for a scene.
#[derive(Clone, Debug)]
pub(crate) struct LabelMeshes {
    /// One mesh per label shown (labels whose surface vanished are left out).
    pub(crate) meshes: Vec<Mesh>,
    /// Their colours, linear RGB.
    pub(crate) colors: Vec<[f32; 3]>,
    /// The labels shown, in value order, when the scene asks for a legend.
    pub(crate) legend: Option<Legend>,
    /// The label grid's world box, voxel centres (min, max), mm.
    pub(crate) bounds: ([f64; 3], [f64; 3]),
}

impl LabelMeshes {
    /// Reads `spec`'s label volume and table (`spec` resolved: [`LabelSpec::resolve`])
    /// and extracts the surfaces of the labels it shows.
    pub(crate) fn build(spec: &LabelSpec) -> Result<LabelMeshes, RenderError> {
        let volume = read_volume(&spec.path, &ReadOptions::default())?;
        let grid = LabelGrid::from_volume(&volume).map_err(|e| spec.error(e))?;
        drop(volume);
        let table = match &spec.table {
            Some(t) => LabelTable::open(t).map_err(|e| spec.error(e))?,
            None => LabelTable::new("generated"),
        };
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
        let smoothing = spec.smoothing.unwrap_or(DEFAULT_LABEL_SMOOTHING);
        let surfaces = label_surfaces(&grid, &values, smoothing).map_err(|e| spec.error(e))?;
        let linear = |v: u32| {
            table
                .color_of(v)
                .map(|c| srgb_to_linear(f64::from(c) / 255.0) as f32)
        };
        let legend = spec.legend.then(|| Legend {
            entries: values
                .iter()
                .map(|&v| (table.name_of(v), linear(v)))
                .collect(),
        });
        let (meshes, colors) = surfaces
            .into_iter()
            .filter(|(_, m)| !m.triangles.is_empty())
            .map(|(v, m)| (m, linear(v)))
            .unzip();
        Ok(LabelMeshes {
            meshes,
            colors,
            legend,
            bounds: grid.world_bounds(),
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
