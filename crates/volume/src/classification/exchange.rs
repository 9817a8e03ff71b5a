//! Transfer functions in other programs' files: 3D Slicer's volume property files
//! (`.vp`) and ParaView's colour map JSON, read and written.
//!
//! **Slicer `.vp`**: nine lines, as `vtkMRMLVolumePropertyStorageNode::WriteDataInternal`
//! writes them (Slicer/Slicer,
//! `Modules/Loadable/VolumeRendering/MRML/vtkMRMLVolumePropertyStorageNode.cxx`, and
//! the format's description in `Docs/developer_guide/modules/volumerendering.md`):
//! interpolation type (0 nearest, 1 linear), shade (0 or 1), **diffuse**, **ambient**
//! (in that order), specular, specular power, then the scalar opacity, the gradient
//! opacity and the colour transfer functions, each `count x1 y1 x2 y2 ...` with
//! `count` the number of values that follow (two per opacity point, four per colour
//! point: value, r, g, b). No crate reads the format; it is nine lines of numbers.
//!
//! **ParaView colour maps** (the JSON that ParaView's "Choose Preset" dialog imports and
//! exports, e.g. its `ColorMaps.json`): an array of objects (or one object) with
//! `"Name"`, `"ColorSpace"`, `"RGBPoints"` (`x r g b ...`) and optionally `"Points"`
//! (`x opacity midpoint sharpness ...`); other keys are ignored. Read with serde_json.

use std::path::Path;

use serde::{Deserialize, Serialize};

use glint_core::lighting::MaterialOverrides;
use glint_core::RenderError;

use super::tf::{TransferFunction, TransferFunctionFile};

/// The largest transfer-function file read (they are a few hundred bytes).
const MAX_TF_BYTES: u64 = 1 << 20;

/// A transfer-function file format, told by the file's extension (and, for `.json`,
/// its contents).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum TfFormat {
    /// glint's own JSON (`{"opacity": ..., "color": ...}`).
    Glint,
    /// 3D Slicer's volume property file (`.vp`).
    SlicerVp,
    /// ParaView's colour map JSON.
    ParaView,
}

impl TfFormat {
    /// The format a file of this name is written in: `.vp` Slicer's, `.json`
    /// ParaView's (glint's own form is the scene's `transfer_function` field).
    pub fn for_output(path: &Path) -> Result<TfFormat, RenderError> {
        match extension(path).as_deref() {
            Some("vp") => Ok(TfFormat::SlicerVp),
            Some("json") => Ok(TfFormat::ParaView),
            _ => Err(RenderError::TransferFunctionFile {
                path: path.to_path_buf(),
                what: "unknown extension: expected .vp (3D Slicer) or .json (ParaView)".into(),
            }),
        }
    }
}

fn extension(path: &Path) -> Option<String> {
    path.extension()
        .and_then(|e| e.to_str())
        .map(str::to_ascii_lowercase)
}

impl TransferFunctionFile {
    /// Reads a transfer-function file, its format told by its extension: `.vp`
    /// Slicer's volume property file; `.json` glint's own form (an object with
    /// `opacity` and `color`) or a ParaView colour map (an array, or an object with
    /// `RGBPoints`). Errors name the file and say what is wrong in one line.
    pub fn read(path: &Path) -> Result<TransferFunctionFile, RenderError> {
        let file_err = |what: String| RenderError::TransferFunctionFile {
            path: path.to_path_buf(),
            what,
        };
        let ext = extension(path);
        if !matches!(ext.as_deref(), Some("vp" | "json")) {
            return Err(file_err(
                "unknown extension: expected .json (glint or ParaView) or .vp (3D Slicer)".into(),
            ));
        }
        let meta = std::fs::metadata(path).map_err(|e| file_err(e.to_string()))?;
        if meta.len() > MAX_TF_BYTES {
            return Err(file_err(format!(
                "{} bytes is too large for a transfer function (limit 1 MiB)",
                meta.len()
            )));
        }
        let text = std::fs::read_to_string(path).map_err(|e| file_err(e.to_string()))?;
        let parsed = match ext.as_deref() {
            Some("vp") => Self::from_vp_str(&text),
            _ if is_paraview(&text) => Self::from_paraview_str(&text),
            _ => TransferFunction::from_json_str(&text),
        };
        parsed.map_err(|e| match e {
            RenderError::TransferFunction(what) => file_err(what),
            other => file_err(other.to_string()),
        })
    }

    /// Parses a Slicer volume property file (the module's description above).
    /// Interpolation "nearest" and a gradient opacity other than the constant 1 are
    /// not rendered by glint: they are kept as [`notes`](Self::notes).
    pub fn from_vp_str(text: &str) -> Result<TransferFunctionFile, RenderError> {
        let bad = |what: String| RenderError::TransferFunction(what);
        let lines: Vec<&str> = text.lines().map(str::trim).collect();
        let real = lines
            .iter()
            .rposition(|l| !l.is_empty())
            .map_or(0, |i| i + 1);
        if real != VP_LINES.len() {
            return Err(bad(format!(
                "a Slicer volume property file has {} lines ({}); this one has {real}",
                VP_LINES.len(),
                VP_LINES.join(", ")
            )));
        }
        let scalar = |i: usize| -> Result<f64, RenderError> {
            let mut words = lines[i].split_whitespace();
            match (words.next().map(str::parse::<f64>), words.next()) {
                (Some(Ok(x)), None) if x.is_finite() => Ok(x),
                _ => Err(bad(format!(
                    "line {} ({}): expected one number, found '{}'",
                    i + 1,
                    VP_LINES[i],
                    lines[i]
                ))),
            }
        };
        let flag = |i: usize| -> Result<bool, RenderError> {
            match scalar(i)? {
                0.0 => Ok(false),
                1.0 => Ok(true),
                x => Err(bad(format!(
                    "line {} ({}): {x}, expected 0 or 1",
                    i + 1,
                    VP_LINES[i]
                ))),
            }
        };
        let linear = flag(0)?;
        let shade = flag(1)?;
        let [diffuse, ambient, specular] = [2, 3, 4].map(scalar);
        let power = scalar(5)?;
        let opacity = counted(lines[6], 7, 2)?;
        let gradient = counted(lines[7], 8, 2)?;
        let color = counted(lines[8], 9, 4)?;
        let tf = TransferFunction::from_flat(&opacity, &color)?;
        let mut notes = Vec::new();
        if !linear {
            notes.push("interpolation 'nearest' ignored: glint reconstructs trilinearly".into());
        }
        if gradient.chunks(2).any(|p| p[1] != 1.0) {
            notes.push(
                "gradient opacity ignored: glint has none (Slicer's presets keep it at 1)".into(),
            );
        }
        Ok(TransferFunctionFile {
            tf,
            material: MaterialOverrides {
                ambient: Some(ambient? as f32),
                diffuse: Some(diffuse? as f32),
                specular: Some(specular? as f32),
                shade: Some(shade),
            },
            power: Some(power),
            notes,
        })
    }

    /// The Slicer volume property file of this function and material (linear
    /// interpolation, the constant gradient opacity of Slicer's presets; material
    /// fields not set take VTK's defaults: ambient 0.1, diffuse 0.7, specular 0.2,
    /// power 10, shade off).
    pub fn to_vp(&self) -> String {
        let m = &self.material;
        let num = |x: f64| format!("{x}");
        let list = |values: Vec<f64>| {
            let mut out = values.len().to_string();
            for v in values {
                out.push(' ');
                out.push_str(&num(v));
            }
            out
        };
        let opacity = self.tf.opacity.iter().flat_map(|&(x, a)| [x, a]).collect();
        let color = self
            .tf
            .color
            .iter()
            .flat_map(|&(x, c)| [x, c[0], c[1], c[2]])
            .collect();
        [
            "1".to_string(),
            u8::from(m.shade.unwrap_or(false)).to_string(),
            m.diffuse.unwrap_or(0.7).to_string(),
            m.ambient.unwrap_or(0.1).to_string(),
            m.specular.unwrap_or(0.2).to_string(),
            num(self.power.unwrap_or(10.0)),
            list(opacity),
            "4 0 1 255 1".to_string(),
            list(color),
        ]
        .join("\n")
            + "\n"
    }

    /// Parses a ParaView colour map (the first of an array, or a single object):
    /// `RGBPoints` the colours; `Points` the opacity (its midpoint and sharpness
    /// must be ParaView's defaults, 0.5 and 0: linear segments), else ParaView's
    /// default ramp from 0 at the first colour point to 1 at the last. Colours are
    /// interpolated in RGB whatever the `ColorSpace`.
    pub fn from_paraview_str(text: &str) -> Result<TransferFunctionFile, RenderError> {
        let bad = |what: String| RenderError::TransferFunction(what);
        let doc: ParaViewDoc = serde_json::from_str(text)
            .map_err(|e| bad(format!("not a ParaView colour map: {e}")))?;
        let map = match doc {
            ParaViewDoc::One(m) => m,
            ParaViewDoc::Many(maps) => maps
                .into_iter()
                .next()
                .ok_or_else(|| bad("an empty list of colour maps".into()))?,
        };
        let name = map.name.as_deref().unwrap_or("unnamed");
        if map.rgb_points.is_empty() || !map.rgb_points.len().is_multiple_of(4) {
            return Err(bad(format!(
                "colour map '{name}': RGBPoints has {} numbers, expected a multiple of 4 (x r g b), at least 4",
                map.rgb_points.len()
            )));
        }
        let opacity = match &map.points {
            Some(p) if p.is_empty() || !p.len().is_multiple_of(4) => {
                return Err(bad(format!(
                    "colour map '{name}': Points has {} numbers, expected a multiple of 4 (x opacity midpoint sharpness)",
                    p.len()
                )))
            }
            Some(p) => {
                if let Some(q) = p.chunks(4).find(|q| q[2] != 0.5 || q[3] != 0.0) {
                    return Err(bad(format!(
                        "colour map '{name}': opacity point at {} has midpoint {} and sharpness {}: glint's segments are linear (0.5, 0)",
                        q[0], q[2], q[3]
                    )));
                }
                p.chunks(4).flat_map(|q| [q[0], q[1]]).collect()
            }
            None => {
                let first = map.rgb_points[0];
                let last = map.rgb_points[map.rgb_points.len() - 4];
                if last > first {
                    vec![first, 0.0, last, 1.0]
                } else {
                    vec![first, 1.0]
                }
            }
        };
        let tf = TransferFunction::from_flat(&opacity, &map.rgb_points)
            .map_err(|e| bad(format!("colour map '{name}': {}", strip(&e))))?;
        Ok(TransferFunctionFile {
            tf,
            material: MaterialOverrides::default(),
            power: None,
            notes: Vec::new(),
        })
    }

    /// The ParaView colour map (an array of one map named `name`, colour space RGB,
    /// the opacity as `Points` with linear segments). ParaView's maps hold no
    /// material: it is not written.
    pub fn to_paraview(&self, name: &str) -> String {
        let map = ParaViewMap {
            name: Some(name.to_string()),
            color_space: Some("RGB".into()),
            rgb_points: self
                .tf
                .color
                .iter()
                .flat_map(|&(x, c)| [x, c[0], c[1], c[2]])
                .collect(),
            points: Some(
                self.tf
                    .opacity
                    .iter()
                    .flat_map(|&(x, a)| [x, a, 0.5, 0.0])
                    .collect(),
            ),
        };
        serde_json::to_string_pretty(&[map]).expect("colour maps serialise") + "\n"
    }
}

/// What each line of a `.vp` file holds.
const VP_LINES: [&str; 9] = [
    "interpolation",
    "shade",
    "diffuse",
    "ambient",
    "specular",
    "specular power",
    "scalar opacity",
    "gradient opacity",
    "colour",
];

/// A `count v1 v2 ...` line (line number `n`) whose values come in groups of `group`.
fn counted(line: &str, n: usize, group: usize) -> Result<Vec<f64>, RenderError> {
    let what = VP_LINES[n - 1];
    let bad = |msg: String| RenderError::TransferFunction(format!("line {n} ({what}): {msg}"));
    let mut words = line.split_whitespace();
    let count = words
        .next()
        .ok_or_else(|| bad("empty, expected 'count x1 y1 ...'".into()))?;
    let count: usize = count
        .parse()
        .map_err(|_| bad(format!("count '{count}' is not a whole number")))?;
    let values = words
        .map(|w| match w.parse::<f64>() {
            Ok(x) if x.is_finite() => Ok(x),
            _ => Err(bad(format!("'{w}' is not a number"))),
        })
        .collect::<Result<Vec<f64>, _>>()?;
    if values.len() != count {
        return Err(bad(format!(
            "count {count} but {} values follow",
            values.len()
        )));
    }
    if count == 0 || !count.is_multiple_of(group) {
        return Err(bad(format!(
            "{count} values: expected a positive multiple of {group}"
        )));
    }
    Ok(values)
}

/// A transfer-function error's message without its "invalid transfer function: ".
fn strip(e: &RenderError) -> String {
    match e {
        RenderError::TransferFunction(what) => what.clone(),
        other => other.to_string(),
    }
}

/// Whether a `.json` file's text is a ParaView colour map rather than glint's form.
fn is_paraview(text: &str) -> bool {
    match serde_json::from_str::<serde_json::Value>(text) {
        Ok(serde_json::Value::Array(_)) => true,
        Ok(serde_json::Value::Object(o)) => o.contains_key("RGBPoints"),
        _ => false,
    }
}

#[derive(Deserialize)]
#[serde(untagged)]
enum ParaViewDoc {
    Many(Vec<ParaViewMap>),
    One(ParaViewMap),
}

#[derive(Serialize, Deserialize)]
struct ParaViewMap {
    #[serde(rename = "Name", default, skip_serializing_if = "Option::is_none")]
    name: Option<String>,
    #[serde(
        rename = "ColorSpace",
        default,
        skip_serializing_if = "Option::is_none"
    )]
    color_space: Option<String>,
    #[serde(rename = "RGBPoints")]
    rgb_points: Vec<f64>,
    #[serde(rename = "Points", default, skip_serializing_if = "Option::is_none")]
    points: Option<Vec<f64>>,
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Written by hand from Slicer's description of the format (the module's doc):
    /// diffuse before ambient, counts of values, a gradient opacity line.
    const HAND_VP: &str = "1\n1\n0.9\n0.1\n0.2\n10\n\
        8 -1000 0 100 0 300 0.8 2000 0.8\n\
        4 0 1 255 1\n\
        12 -1000 0 0 0 300 1 0.5 0.25 2000 1 1 1\n";

    #[test]
    fn a_hand_written_vp_file_reads_and_round_trips() {
        let f = TransferFunctionFile::from_vp_str(HAND_VP).unwrap();
        assert_eq!(
            f.tf.opacity,
            vec![(-1000.0, 0.0), (100.0, 0.0), (300.0, 0.8), (2000.0, 0.8)]
        );
        assert_eq!(f.tf.color[1], (300.0, [1.0, 0.5, 0.25]));
        // Line 3 is diffuse, line 4 ambient.
        assert_eq!(f.material.diffuse, Some(0.9));
        assert_eq!(f.material.ambient, Some(0.1));
        assert_eq!(f.material.specular, Some(0.2));
        assert_eq!((f.material.shade, f.power), (Some(true), Some(10.0)));
        assert!(f.notes.is_empty(), "{:?}", f.notes);
        // Written back, the same lines.
        assert_eq!(f.to_vp(), HAND_VP);
        assert_eq!(TransferFunctionFile::from_vp_str(&f.to_vp()).unwrap(), f);
    }

    #[test]
    fn bad_vp_files_say_which_line() {
        let with = |line: usize, text: &str| {
            let mut lines: Vec<&str> = HAND_VP.lines().collect();
            lines[line - 1] = text;
            lines.join("\n")
        };
        for (text, needle) in [
            (
                with(7, "6 -1000 0 100 0 300 0.8 2000 0.8"),
                "count 6 but 8 values follow",
            ),
            (
                with(9, "12 -1000 0 0 0 300 1 0.5 x 2000 1 1 1"),
                "'x' is not a number",
            ),
            (with(3, "shiny"), "line 3 (diffuse)"),
            (with(1, "2"), "line 1 (interpolation)"),
            (with(8, "3 0 1 255"), "multiple of 2"),
            (with(7, "4 300 0 100 1"), "strictly increasing"),
            ("1\n1\n0.9\n".to_string(), "has 3"),
        ] {
            let err = TransferFunctionFile::from_vp_str(&text)
                .unwrap_err()
                .to_string();
            assert!(err.contains(needle), "{needle}: {err}");
            assert_eq!(err.lines().count(), 1, "{err}");
        }
        let nearest = with(1, "0").replace("4 0 1 255 1", "4 0 0 255 1");
        let f = TransferFunctionFile::from_vp_str(&nearest).unwrap();
        assert_eq!(f.notes.len(), 2, "{:?}", f.notes);
    }

    #[test]
    fn a_hand_written_paraview_map_reads() {
        let text = r#"[{"Name": "Hand", "ColorSpace": "Diverging", "NanColor": [1, 1, 0],
            "RGBPoints": [-1, 0, 0, 1, 0, 1, 1, 1, 1, 1, 0, 0],
            "Points": [-1, 0, 0.5, 0, 1, 0.5, 0.5, 0]}]"#;
        let f = TransferFunctionFile::from_paraview_str(text).unwrap();
        assert_eq!(f.tf.opacity, vec![(-1.0, 0.0), (1.0, 0.5)]);
        assert_eq!(f.tf.color_at(-0.5), [0.5, 0.5, 1.0]);
        assert_eq!(f.tf.opacity_at(0.0), 0.25);
        // No Points: ParaView's ramp from 0 to 1 over the colour points.
        let ramp = TransferFunctionFile::from_paraview_str(
            r#"{"Name": "r", "RGBPoints": [0, 0, 0, 0, 10, 1, 1, 1]}"#,
        )
        .unwrap();
        assert_eq!(ramp.tf.opacity, vec![(0.0, 0.0), (10.0, 1.0)]);
        // Round trip through the writer.
        let back = TransferFunctionFile::from_paraview_str(&f.to_paraview("Hand")).unwrap();
        assert_eq!(back.tf, f.tf);
        for (bad, needle) in [
            (r#"[{"RGBPoints": [0, 0, 0]}]"#, "multiple of 4"),
            (
                r#"[{"RGBPoints": [0, 0, 0, "red"]}]"#,
                "not a ParaView colour map",
            ),
            (
                r#"[{"Name": "x", "RGBPoints": [0, 0, 0, 0], "Points": [0, 1]}]"#,
                "Points has 2",
            ),
            (
                r#"[{"RGBPoints": [0, 0, 0, 0], "Points": [0, 1, 0.3, 0]}]"#,
                "midpoint 0.3",
            ),
            (r#"[{"RGBPoints": [0, 0, 0, 2]}]"#, "outside [0, 1]"),
            ("[]", "empty list"),
        ] {
            let err = TransferFunctionFile::from_paraview_str(bad)
                .unwrap_err()
                .to_string();
            assert!(err.contains(needle), "{needle}: {err}");
        }
    }
}
