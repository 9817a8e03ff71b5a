//! The label-map options of the scene commands (`--labels` and what goes with it),
//! flattened into `SceneFlags` (scene_flags.rs).

use std::path::PathBuf;

use anyhow::bail;
use glint_render::{Input, LabelSpec, LabelsAs, Scene};

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
    /// files named *aseg*, *aparc*, *wmparc*; a DICOM SEG's own segments; else labels
    /// by number, generated colours].
    #[arg(long, value_name = "TABLE")]
    pub label_table: Option<String>,
    /// Only these labels (names or numbers, comma-separated); repeatable.
    #[arg(long, value_name = "LABELS", value_delimiter = ',')]
    pub show: Vec<String>,
    /// Not these labels (names or numbers, comma-separated); repeatable.
    #[arg(long, value_name = "LABELS", value_delimiter = ',')]
    pub hide: Vec<String>,
    /// Gaussian smoothing of the label surfaces, in voxels of the label grid's
    /// coarsest axis (0: voxel stairs) [default: 1 for isotropic grids, 2 for slices
    /// 2.5 times their pixels or more (thick slices' terraces), linear between].
    #[arg(long, value_name = "VOXELS")]
    pub label_smoothing: Option<f32>,
    /// No legend of the labels shown.
    #[arg(long)]
    pub no_legend: bool,
    /// How the labels are drawn: surfaces (smoothed, rasterised), volume (a label
    /// volume ray cast in the volume's frame: nearest-label classification, each
    /// label's colour and opacity, lit by the labels' boundary; needs a volume in a
    /// ray-cast mode) or both [default: surfaces].
    #[arg(long, value_name = "HOW", value_parser = ["surfaces", "volume", "both"])]
    pub labels_as: Option<String>,
    /// Per-label opacity of the label volume, NAME=OPACITY (name or number, opacity
    /// of one voxel's length in 0..1; comma-separated, repeatable) [default: the
    /// table's alpha, 1 without one].
    #[arg(long, value_name = "LABEL=OPACITY", value_delimiter = ',')]
    pub label_opacity: Vec<String>,
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
            || self.no_legend
            || self.labels_as.is_some()
            || !self.label_opacity.is_empty();
        let Some(spec) = &mut scene.labels else {
            if given {
                bail!("--label-table, --show, --hide, --label-smoothing, --no-legend, --labels-as and --label-opacity need --labels");
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
        if let Some(how) = &self.labels_as {
            spec.render_as = how.parse::<LabelsAs>()?;
        }
        for item in &self.label_opacity {
            let Some((name, value)) = item.rsplit_once('=') else {
                bail!("--label-opacity {item:?}: expected LABEL=OPACITY, e.g. liver=0.4");
            };
            let opacity: f32 = match value.trim().parse() {
                Ok(o) if (0.0..=1.0).contains(&o) => o,
                _ => bail!("--label-opacity {item:?}: the opacity must be a number in 0..1"),
            };
            spec.opacity.insert(name.trim().to_string(), opacity);
        }
        Ok(())
    }
}
