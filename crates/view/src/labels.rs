//! The label map of a viewer's scene (issue 33, "toggle labels by name"): the labels
//! present, with their names, colours and voxel counts (sent in the `hello` for the
//! page's legend), and which of them a scene shows.
//!
//! The page toggles labels with the scene's own `labels.hide` list (a partial
//! `labels` update, [`LABEL_FIELDS`]); the label file and its table stay the server's.

use std::collections::BTreeSet;
use std::path::Path;

use glint_io::read_volume;
use glint_render::label_maps::{LabelError, LabelGrid, LabelTable};
use glint_render::{label_read_options, LabelSpec, LabelsAs, RenderError, Scene};
use serde::Serialize;
use serde_json::{Map, Value};

use crate::ViewError;

/// The fields of the scene's `labels` a client may change (merged field by field into
/// the server's label map): which labels, the image's legend and per-label opacity.
/// The file (`path`), its `table`, smoothing and `render_as` stay the server's.
pub const LABEL_FIELDS: [&str; 4] = ["show", "hide", "legend", "opacity"];

/// One label present in the map, as the `hello` lists it.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct LabelInfo {
    /// The label's value in the map.
    pub value: u32,
    /// Its name in the colour table (`label N` when the table has none).
    pub name: String,
    /// Its colour, sRGB `#rrggbb` (the table's, or a generated one).
    pub color: String,
    /// Voxels of the map with this value.
    pub voxels: u64,
    /// Whether the starting scene shows it.
    pub shown: bool,
}

/// The labels present in a scene's label map and the table that names them.
#[derive(Clone, Debug)]
pub struct LabelList {
    entries: Vec<LabelInfo>,
    table: LabelTable,
}

impl LabelList {
    /// Reads the label map of `spec` (resolved: its table named) and lists the labels
    /// present (0, background, left out), in value order. `image` is the scene's volume
    /// file (an RT structure set is rasterised onto its grid, as the renderer does).
    pub fn read(spec: &LabelSpec, image: Option<&Path>) -> Result<LabelList, RenderError> {
        let error = |e: Box<dyn std::error::Error + Send + Sync>| RenderError::Labels {
            path: spec.path.clone(),
            source: e,
        };
        let volume = read_volume(&spec.path, &label_read_options(image))?;
        let grid = LabelGrid::from_volume(&volume).map_err(|e| error(Box::new(e)))?;
        drop(volume);
        // The renderer's rule, so the legend names and colours what the image shows
        // (a DICOM SEG's own segment table included).
        let table = LabelTable::for_map(&spec.path, spec.table.as_deref())
            .map_err(|e| error(Box::new(e)))?;
        let entries = grid
            .summary()
            .into_iter()
            .map(|(value, extent)| {
                let [r, g, b] = table.color_of(value);
                LabelInfo {
                    value,
                    name: table.name_of(value),
                    color: format!("#{r:02x}{g:02x}{b:02x}"),
                    voxels: extent.voxels,
                    shown: true,
                }
            })
            .collect();
        let mut list = LabelList { entries, table };
        let shown = list.shown(spec)?;
        for e in &mut list.entries {
            e.shown = shown.contains(&e.value);
        }
        Ok(list)
    }

    /// The labels present, in value order.
    pub fn entries(&self) -> &[LabelInfo] {
        &self.entries
    }

    /// The values of the labels present that `spec` shows (its `show` list, or every
    /// label, less its `hide` list); a name not in the table is refused.
    pub fn shown(&self, spec: &LabelSpec) -> Result<BTreeSet<u32>, RenderError> {
        let lookup = |names: &[String]| -> Result<BTreeSet<u32>, RenderError> {
            names
                .iter()
                .map(|n| {
                    self.table.lookup(n).map_err(|e| RenderError::Labels {
                        path: spec.path.clone(),
                        source: Box::new(e),
                    })
                })
                .collect()
        };
        let (show, hide) = (lookup(&spec.show)?, lookup(&spec.hide)?);
        Ok(self
            .entries
            .iter()
            .map(|e| e.value)
            .filter(|v| show.is_empty() || show.contains(v))
            .filter(|v| !hide.contains(v))
            .collect())
    }

    /// Refuses a label map the renderer would refuse, without building it: names not
    /// in the table, a `show` list naming labels the map lacks, opacities outside
    /// 0..=1 or given for surfaces (which are opaque).
    pub fn check(&self, spec: &LabelSpec) -> Result<(), ViewError> {
        self.shown(spec)?;
        let present: BTreeSet<u32> = self.entries.iter().map(|e| e.value).collect();
        for name in &spec.show {
            let v = self.table.lookup(name).map_err(|e| self.error(spec, e))?;
            if !present.contains(&v) {
                return Err(ViewError::Message(format!(
                    "label {v} ({}) is not in the map",
                    self.table.name_of(v)
                )));
            }
        }
        for (name, &opacity) in &spec.opacity {
            self.table.lookup(name).map_err(|e| self.error(spec, e))?;
            if !(0.0..=1.0).contains(&opacity) {
                return Err(ViewError::Message(format!(
                    "label {name}: opacity {opacity} is not in 0..=1"
                )));
            }
        }
        if !spec.opacity.is_empty() && spec.render_as == LabelsAs::Surfaces {
            return Err(ViewError::Message(
                "per-label opacity applies to a label volume (glint view --labels-as volume or both); surfaces are opaque".into(),
            ));
        }
        Ok(())
    }

    fn error(&self, spec: &LabelSpec, e: LabelError) -> ViewError {
        ViewError::Render(RenderError::Labels {
            path: spec.path.clone(),
            source: Box::new(e),
        })
    }

    /// `scene` as it is rendered: without its label layer when it hides every label
    /// (the page's "none"; the renderer refuses a label map with nothing to show).
    pub fn visible(&self, scene: &Scene) -> Scene {
        let mut s = scene.clone();
        let none = s
            .labels
            .as_ref()
            .is_some_and(|spec| self.shown(spec).is_ok_and(|v| v.is_empty()));
        if none {
            s.labels = None;
        }
        s
    }
}

/// `current` (the scene's label map) with the fields of a client's `labels` patch
/// merged in ([`LABEL_FIELDS`] only; `null` gives a field its default).
pub(crate) fn merge_labels(current: Option<&LabelSpec>, patch: &Value) -> Result<Value, ViewError> {
    let Some(current) = current else {
        return Err(ViewError::Message(
            "this viewer has no label map: 'labels' cannot be changed".into(),
        ));
    };
    let Value::Object(changes) = patch else {
        return Err(ViewError::Message(format!(
            "'labels' takes an object of {}",
            LABEL_FIELDS.join(", ")
        )));
    };
    let mut doc: Map<String, Value> = match serde_json::to_value(current) {
        Ok(Value::Object(m)) => m,
        _ => {
            return Err(ViewError::Message(
                "a label map serialises to an object".into(),
            ))
        }
    };
    for (key, value) in changes {
        if !LABEL_FIELDS.contains(&key.as_str()) {
            return Err(ViewError::Message(format!(
                "the viewer does not change 'labels.{key}': only {}",
                LABEL_FIELDS.join(", ")
            )));
        }
        if value.is_null() {
            doc.remove(key);
        } else {
            doc.insert(key.clone(), value.clone());
        }
    }
    Ok(Value::Object(doc))
}
