//! One input's line of `results.jsonl`: what was made of it, or why nothing was.

use serde::{Deserialize, Serialize};

use crate::Item;

/// Whether an input's outputs were made.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum Status {
    /// Every output was written.
    Ok,
    /// Nothing was written; [`Row::error`] says why.
    Failed,
}

/// One input's result. Serialised (`row.json`, a line of `results.jsonl`) with its
/// fields in this order; a failed row has no outputs, volume or times, so the same
/// failure gives the same row.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Row {
    /// The input's id ([`Item::id`]), the name of its output folder.
    pub id: String,
    /// The input's path (lossily as text, were it not UTF-8).
    pub input: String,
    /// BIDS subject label.
    pub subject: Option<String>,
    /// BIDS session label.
    pub session: Option<String>,
    /// Made or failed.
    pub status: Status,
    /// The input's [checksum](crate::checksum) (`None` when it could not be read).
    pub checksum: Option<String>,
    /// The [spec's key](crate::Spec::key) the outputs were made with.
    pub spec: String,
    /// The views of the mosaic, left to right.
    pub views: Vec<String>,
    /// The files written, relative to the output directory.
    pub outputs: Option<Outputs>,
    /// What the volume was.
    pub volume: Option<VolumeInfo>,
    /// Where the time went.
    pub seconds: Option<Seconds>,
    /// What the reader said (where the affine came from, what it assumed).
    pub notes: Vec<String>,
    /// Why the input failed: the error's one line ([`glint_io::one_line`]).
    pub error: Option<String>,
}

/// The files of an input, relative to the output directory, `/`-separated.
#[derive(Clone, Debug, PartialEq, Eq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Outputs {
    /// The views side by side (PNG).
    pub mosaic: String,
    /// Sagittal, coronal and axial slices (PNG), when asked for.
    pub slices: Option<String>,
    /// The first view's resolved scene (JSON).
    pub scene: String,
}

/// The volume an input held.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct VolumeInfo {
    /// Samples along i, j, k.
    pub dims: [usize; 3],
    /// Voxel size, mm.
    pub spacing: [f64; 3],
    /// The slices' intensity window (the volume's robust range), when slices were made.
    pub window: Option<[f64; 2]>,
}

/// Seconds spent on each stage of an input.
#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Seconds {
    /// Hashing the input.
    pub checksum: f64,
    /// Reading and decoding it.
    pub read: f64,
    /// Building the field (filtering, gradients, macro cells).
    pub field: f64,
    /// Classifying (once for all views of one transfer function).
    pub classify: f64,
    /// Rendering the views' frames.
    pub frames: f64,
    /// Resampling the slices.
    pub slices: f64,
    /// Encoding and writing the files.
    pub write: f64,
    /// The whole job.
    pub total: f64,
}

impl Row {
    /// A failed row of `item`: its error line and nothing else.
    pub fn failed(
        item: &Item,
        spec: &str,
        views: &[String],
        checksum: Option<String>,
        error: String,
    ) -> Row {
        Row {
            id: item.id.clone(),
            input: item.path.to_string_lossy().into_owned(),
            subject: item.subject.clone(),
            session: item.session.clone(),
            status: Status::Failed,
            checksum,
            spec: spec.into(),
            views: views.to_vec(),
            outputs: None,
            volume: None,
            seconds: None,
            notes: Vec::new(),
            error: Some(error),
        }
    }

    /// The row as one line of JSON (no newline).
    pub fn to_line(&self) -> String {
        serde_json::to_string(self).expect("a row serialises: plain fields, string keys")
    }

    /// Every output path of the row.
    pub fn output_paths(&self) -> Vec<&str> {
        let Some(o) = &self.outputs else {
            return Vec::new();
        };
        let mut paths = vec![o.mosaic.as_str(), o.scene.as_str()];
        paths.extend(o.slices.as_deref());
        paths
    }
}
