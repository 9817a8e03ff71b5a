//! The label-map options of the scene commands (`--labels` and what goes with it),
//! flattened into `SceneFlags` (scene_flags.rs).

use std::path::PathBuf;

use anyhow::bail;
use glint_render::{Input, LabelSpec, Scene};

/// Label-map options.
#[derive(clap::Args, Default)]
pub struct LabelFlags {
    /// A label map (segmentation: any volume glint reads whose values are whole
    /// numbers, 0 background) drawn as one smoothed surface per label, placed by its
    /// own affine; with a volume, in the volume's frame (its transfer function
    /// decides how much of the volume covers them).
    #[arg(long, value_name = "FILE")]
    pub labels: Option<PathBuf>,
    /// The labels' colour table: freesurfer, totalsegmentator (built in), or a file
    /// (FreeSurfer LUT text, Slicer .ctbl/.txt, .json, .csv) [default: freesurfer for
    /// files named *aseg*, *aparc*, *wmparc*; else labels by number, generated
    /// colours].
    #[arg(long, value_name = "TABLE")]
    pub label_table: Option<String>,
    /// Only these labels (names or numbers, comma-separated); repeatable.
    #[arg(long, value_name = "LABELS", value_delimiter = ',')]
    pub show: Vec<String>,
    /// Not these labels (names or numbers, comma-separated); repeatable.
    #[arg(long, value_name = "LABELS", value_delimiter = ',')]
    pub hide: Vec<String>,
    /// Gaussian smoothing of the label surfaces, in voxels of the label grid's
    /// coarsest axis (0: voxel stairs) [default: 1].
    #[arg(long, value_name = "VOXELS")]
    pub label_smoothing: Option<f32>,
    /// No legend of the labels shown.
    #[arg(long)]
    pub no_legend: bool,
}

impl LabelFlags {
    /// Applies the flags to `scene`; `alone`: no volume was asked for (no input,
    /// phantom or scene file), so a label map is rendered by itself.
    pub fn apply(&self, scene: &mut Scene, alone: bool) -> anyhow::Result<()> {
        if let Some(path) = &self.labels {
            scene.labels = Some(LabelSpec::new(path));
            if alone {
                scene.input = Input::None;
            }
        }
        let given = self.label_table.is_some()
            || !self.show.is_empty()
            || !self.hide.is_empty()
            || self.label_smoothing.is_some()
            || self.no_legend;
        let Some(spec) = &mut scene.labels else {
            if given {
                bail!("--label-table, --show, --hide, --label-smoothing and --no-legend need --labels");
            }
            return Ok(());
        };
        if self.label_table.is_some() {
            spec.table = self.label_table.clone();
        }
        if !self.show.is_empty() {
            spec.show = self.show.clone();
        }
        if !self.hide.is_empty() {
            spec.hide = self.hide.clone();
        }
        if self.label_smoothing.is_some() {
            spec.smoothing = self.label_smoothing;
        }
        if self.no_legend {
            spec.legend = false;
        }
        Ok(())
    }
}
