//! GIFTI surfaces (`.gii`, `.gii.gz`): the geometry format of FreeSurfer, Connectome
//! Workbench and nilearn.
//!
//! No maintained Rust crate reads GIFTI, so this module walks the XML with quick-xml
//! and decodes the data arrays with base64 and flate2, following the GIFTI 1.0 spec
//! (<https://www.nitrc.org/projects/gifti/>, "GIFTI Surface Data Format Version 1.0").
//! Encodings: ASCII, Base64Binary, GZipBase64Binary (zlib-compressed, then base64), the
//! legacy `GIFTI_ENCODING_*` spellings of these (nibabel's `gifti_encoding_codes`), and
//! ExternalFileBinary when the external file sits in the GIFTI's own directory.
//!
//! Besides surfaces ([`read`]), the per-vertex arrays users overlay on a surface
//! (curvature, sulcal depth, thickness, parcellations, time series) are read by
//! [`read_surface_data`].

use std::io::{Read, Seek, Write};
use std::path::Path;

use base64::Engine;
use quick_xml::events::Event;

use crate::common::{is_gzip, open, os_or_invalid, read_exact_growing, write_atomic};
use crate::mesh::check_indices;
use crate::{Format, IoError, Mesh, MeshFile};

/// Largest XML document accepted (after gzip): far above a 1M-vertex surface in ASCII.
const MAX_XML_BYTES: u64 = 4 << 30;

/// Largest inflation accepted for a gzipped document (decompressed / compressed size).
const MAX_GZIP_RATIO: u64 = 64;

/// A gzipped document may always inflate to this many bytes, whatever its ratio.
const MIN_XML_CAP: u64 = 64 << 20;

/// Characters of `<Data>` text accepted per announced value (ASCII numbers with
/// separators, or base64 with line breaks, take far fewer), plus a fixed slack.
const DATA_CHARS_PER_VALUE: usize = 32;
const DATA_SLACK: usize = 1 << 16;

/// Characters of file text quoted in an error message at most.
const MAX_QUOTED_CHARS: usize = 200;

/// GIFTI data encodings.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Encoding {
    /// Whitespace-separated decimal numbers.
    Ascii,
    /// Little-endian binary, base64-encoded.
    Base64,
    /// Little-endian binary, zlib-compressed, base64-encoded.
    GzipBase64,
}

/// One per-vertex array of a GIFTI file (see [`read_surface_data`]).
#[derive(Clone, Debug, PartialEq)]
pub struct VertexData {
    /// The array's `Name` metadata, else its intent and position (`NIFTI_INTENT_SHAPE #0`);
    /// a column of a 2-D array gets ` [t]` appended.
    pub name: String,
    /// The array's intent, e.g. `NIFTI_INTENT_SHAPE`, `NIFTI_INTENT_LABEL`,
    /// `NIFTI_INTENT_TIME_SERIES`.
    pub intent: String,
    /// One value per vertex.
    pub values: VertexValues,
}

/// The values of a [`VertexData`].
#[derive(Clone, Debug, PartialEq)]
pub enum VertexValues {
    /// Measurements (shape, statistics, time points), as f32.
    Scalars(Vec<f32>),
    /// Label keys (a parcellation), with the file's label table.
    Labels {
        /// The key of each vertex.
        keys: Vec<i32>,
        /// The file's `LabelTable`.
        table: Vec<Label>,
    },
}

/// An entry of a GIFTI `LabelTable`.
#[derive(Clone, Debug, PartialEq)]
pub struct Label {
    /// The key vertices carry.
    pub key: i32,
    /// The label's name.
    pub name: String,
    /// Red, green, blue, alpha in 0..1 (0 where the file gives none).
    pub rgba: [f32; 4],
}

#[derive(Default, Debug)]
struct DataArray {
    intent: String,
    /// `ExternalFileName` and `ExternalFileOffset` (for ExternalFileBinary).
    external: (String, String),
    /// `<MetaData>` name/value pairs.
    meta: Vec<(String, String)>,
    data_type: String,
    column_major: bool,
    dims: Vec<usize>,
    encoding: String,
    big_endian: bool,
    data_space: Option<String>,
    transformed_space: Option<String>,
    matrix: Option<String>,
    data: String,
    /// The `<Data>` text ran past what the dimensions allow; the rest was dropped.
    overflow: bool,
}

impl DataArray {
    /// Most `<Data>` characters the announced dimensions can explain.
    fn data_cap(&self) -> usize {
        self.dims
            .iter()
            .fold(1usize, |acc, &d| acc.saturating_mul(d))
            .saturating_mul(DATA_CHARS_PER_VALUE)
            .saturating_add(DATA_SLACK)
    }
}

/// An Invalid error, kept to one line whatever text it quotes (issue 17: XML errors
/// quoted the broken text verbatim, newlines included).
fn invalid(path: &Path, what: impl Into<String>) -> IoError {
    IoError::Invalid {
        path: path.into(),
        what: one_line(&what.into()),
    }
}

/// `s` with control characters (newlines, tabs, ...) escaped, at most 200 characters.
fn one_line(s: &str) -> String {
    let mut out = String::new();
    for (i, c) in s.chars().enumerate() {
        if i == MAX_QUOTED_CHARS {
            out.push_str("...");
            break;
        }
        if c.is_control() {
            out.extend(c.escape_debug());
        } else {
            out.push(c);
        }
    }
    out
}

/// Reads a GIFTI surface: the POINTSET array gives the positions, the TRIANGLE array
/// the faces; a VECTOR array with one row per vertex becomes the normals and the first
/// one-value-per-vertex array the scalars.
pub fn read(path: &Path) -> Result<MeshFile, IoError> {
    let (arrays, _) = load(path)?;
    surface(path, &arrays)
}

/// Reads the per-vertex arrays of a GIFTI file: every array other than POINTSET,
/// TRIANGLE and N x 3 VECTOR whose first dimension is the vertex count (the POINTSET's
/// rows, or when the file has no surface, the first such array's). A 1-D array (or
/// N x 1) is one [`VertexData`]; an N x T array (a time series) gives T of them, one a
/// column. LABEL arrays come with the file's label table.
///
/// ```no_run
/// # use glint_io::gifti::{read_surface_data, VertexValues};
/// for d in read_surface_data("lh.sulc.gii".as_ref()).unwrap() {
///     if let VertexValues::Scalars(v) = &d.values {
///         println!("{} ({}): {} values", d.name, d.intent, v.len());
///     }
/// }
/// ```
pub fn read_surface_data(path: &Path) -> Result<Vec<VertexData>, IoError> {
    let (arrays, table) = load(path)?;
    let geometry = |a: &DataArray| {
        matches!(
            a.intent.as_str(),
            "NIFTI_INTENT_POINTSET" | "NIFTI_INTENT_TRIANGLE"
        ) || a.intent == "NIFTI_INTENT_VECTOR" && a.dims.len() == 2 && a.dims[1] == 3
    };
    let n = arrays
        .iter()
        .find(|a| a.intent == "NIFTI_INTENT_POINTSET")
        .or_else(|| arrays.iter().find(|a| !geometry(a)))
        .map(|a| a.dims[0]);
    let mut out = Vec::new();
    for (i, a) in arrays.iter().enumerate() {
        if geometry(a) || Some(a.dims[0]) != n || a.dims.len() > 2 {
            continue;
        }
        let name = a
            .meta
            .iter()
            .find(|(k, _)| k == "Name")
            .map(|(_, v)| v.clone())
            .filter(|v| !v.is_empty())
            .unwrap_or_else(|| format!("{} #{i}", a.intent));
        let v = values(path, a)?;
        let (rows, cols) = (a.dims[0], a.dims.get(1).copied().unwrap_or(1));
        for c in 0..cols {
            let column = (0..rows).map(|r| {
                if a.column_major {
                    v[c * rows + r]
                } else {
                    v[r * cols + c]
                }
            });
            let values = if a.intent == "NIFTI_INTENT_LABEL" {
                VertexValues::Labels {
                    keys: column.map(|x| x as i32).collect(),
                    table: table.clone(),
                }
            } else {
                VertexValues::Scalars(column.map(|x| x as f32).collect())
            };
            out.push(VertexData {
                name: if cols > 1 {
                    format!("{name} [{c}]")
                } else {
                    name.clone()
                },
                intent: a.intent.clone(),
                values,
            });
        }
    }
    Ok(out)
}

/// The data arrays and the label table of a GIFTI file, not yet decoded.
fn load(path: &Path) -> Result<(Vec<DataArray>, Vec<Label>), IoError> {
    let gz = is_gzip(path)?;
    let file = open(path)?;
    let file_len = file.metadata().map_err(|e| os_or_invalid(path, e))?.len();
    // A gzip bomb (a megabyte inflating to gigabytes of whitespace) is stopped at a
    // ratio no real surface reaches: base64 or ASCII numbers compress a few times, not
    // a hundred.
    let max_xml = if gz {
        file_len
            .saturating_mul(MAX_GZIP_RATIO)
            .clamp(MIN_XML_CAP, MAX_XML_BYTES)
    } else {
        MAX_XML_BYTES
    };
    let mut text = Vec::new();
    let reader: Box<dyn Read> = if gz {
        Box::new(flate2::read::MultiGzDecoder::new(std::io::BufReader::new(
            file,
        )))
    } else {
        Box::new(file)
    };
    reader
        .take(max_xml + 1)
        .read_to_end(&mut text)
        .map_err(|e| os_or_invalid(path, e))?;
    if text.len() as u64 > max_xml {
        return Err(IoError::TooLarge {
            path: path.into(),
            what: if gz {
                format!(
                    "the {file_len}-byte gzip file inflates past {max_xml} bytes of XML \
                     (more than {MAX_GZIP_RATIO}x: a decompression bomb?)"
                )
            } else {
                format!("XML larger than {MAX_XML_BYTES} bytes")
            },
        });
    }
    let text = String::from_utf8(text).map_err(|_| invalid(path, "the XML is not UTF-8"))?;
    parse_xml(path, &text)
}

/// The surface of the arrays: POINTSET, TRIANGLE, normals and the first scalars.
fn surface(path: &Path, arrays: &[DataArray]) -> Result<MeshFile, IoError> {
    let mut mesh = Mesh::default();
    let mut coordinate_system = None;
    let mut notes = Vec::new();
    let pointset = arrays
        .iter()
        .find(|a| a.intent == "NIFTI_INTENT_POINTSET")
        .ok_or_else(|| {
            invalid(
                path,
                format!(
                    "no NIFTI_INTENT_POINTSET array: not a surface (arrays: {})",
                    arrays
                        .iter()
                        .map(|a| a.intent.as_str())
                        .collect::<Vec<_>>()
                        .join(", ")
                ),
            )
        })?;
    mesh.positions = rows3(path, pointset, "POINTSET", |v| v as f32)?;
    let n = mesh.positions.len();
    if let Some(tri) = arrays.iter().find(|a| a.intent == "NIFTI_INTENT_TRIANGLE") {
        let rows = rows3(path, tri, "TRIANGLE", |v| v)?;
        mesh.triangles = rows
            .iter()
            .map(|r| {
                let mut t = [0u32; 3];
                for (o, &x) in t.iter_mut().zip(r) {
                    if x < 0.0 || x.fract() != 0.0 || x > u32::MAX as f64 {
                        return Err(IoError::BadIndex {
                            path: path.into(),
                            what: format!(
                                "triangle {r:?} has an index that is not a vertex number"
                            ),
                        });
                    }
                    *o = x as u32;
                }
                Ok(t)
            })
            .collect::<Result<_, _>>()?;
    } else {
        notes.push("no TRIANGLE array: a point set".into());
    }
    if let Some(a) = arrays
        .iter()
        .find(|a| a.intent == "NIFTI_INTENT_VECTOR" && a.dims == [n, 3])
    {
        mesh.normals = Some(rows3(path, a, "VECTOR", |v| v as f32)?);
    }
    if let Some(a) = arrays.iter().find(|a| {
        !matches!(
            a.intent.as_str(),
            "NIFTI_INTENT_POINTSET" | "NIFTI_INTENT_TRIANGLE" | "NIFTI_INTENT_VECTOR"
        ) && (a.dims == [n] || a.dims == [n, 1])
    }) {
        mesh.scalars = Some(values(path, a)?.into_iter().map(|v| v as f32).collect());
        notes.push(format!("scalars from a {} array", a.intent));
    }
    if let (Some(ds), Some(ts)) = (&pointset.data_space, &pointset.transformed_space) {
        let identity = pointset.matrix.as_deref().is_some_and(|m| {
            let v: Vec<f64> = m
                .split_whitespace()
                .filter_map(|x| x.parse().ok())
                .collect();
            v.len() == 16
                && v.iter()
                    .enumerate()
                    .all(|(i, &x)| x == if i % 5 == 0 { 1.0 } else { 0.0 })
        });
        coordinate_system = Some(if identity {
            format!("{ds} -> {ts} (identity)")
        } else {
            format!("{ds} -> {ts} (matrix not applied)")
        });
    }
    check_indices(path, &mesh)?;
    Ok(MeshFile {
        mesh,
        format: Format::Gifti,
        coordinate_system,
        notes,
    })
}

/// What the XML walk has collected so far.
#[derive(Default)]
struct Collect {
    arrays: Vec<DataArray>,
    labels: Vec<Label>,
    current: Option<DataArray>,
    /// The innermost open elements, for attaching text.
    stack: Vec<String>,
    /// The `<Name>` and `<Value>` of the `<MD>` being read.
    md: (String, String),
}

fn parse_xml(path: &Path, text: &str) -> Result<(Vec<DataArray>, Vec<Label>), IoError> {
    let mut reader = quick_xml::Reader::from_str(text);
    let mut c = Collect::default();
    let mut saw_root = false;
    loop {
        let event = reader.read_event().map_err(|e| {
            invalid(
                path,
                format!("XML error at byte {}: {e}", reader.buffer_position()),
            )
        })?;
        match event {
            Event::Start(ref e) | Event::Empty(ref e) if e.local_name().as_ref() == "DataArray" => {
                let a = data_array(path, e)?;
                if matches!(event, Event::Empty(_)) {
                    c.arrays.push(a);
                } else {
                    c.current = Some(a);
                    c.stack.push("DataArray".into());
                }
            }
            Event::Start(ref e) | Event::Empty(ref e) if e.local_name().as_ref() == "Label" => {
                c.labels.push(label(path, e)?);
                if matches!(event, Event::Start(_)) {
                    c.stack.push("Label".into());
                }
            }
            Event::Start(e) => {
                let name = e.local_name().as_ref().to_string();
                if name == "GIFTI" {
                    saw_root = true;
                }
                if name == "MD" {
                    c.md = Default::default();
                }
                c.stack.push(name);
            }
            Event::End(e) => {
                match e.local_name().as_ref() {
                    "DataArray" => c.arrays.extend(c.current.take()),
                    "MD" => {
                        if let Some(a) = c.current.as_mut() {
                            a.meta.push(std::mem::take(&mut c.md));
                        }
                    }
                    _ => {}
                }
                c.stack.pop();
            }
            Event::Text(t) => add_text(&mut c, &t.xml10_content()),
            Event::CData(t) => add_text(&mut c, &t.xml10_content()),
            Event::Eof => break,
            _ => {}
        }
    }
    if !saw_root {
        return Err(IoError::BadMagic {
            path: path.into(),
            format: "GIFTI",
            what: "no <GIFTI> root element".into(),
        });
    }
    Ok((c.arrays, c.labels))
}

/// The attributes of an element as (local name, trimmed normalised value).
fn attributes(
    path: &Path,
    e: &quick_xml::events::BytesStart,
) -> Result<Vec<(String, String)>, IoError> {
    e.attributes()
        .map(|attr| {
            let attr = attr.map_err(|e| invalid(path, format!("XML attribute: {e}")))?;
            let value = attr
                .normalized_value(quick_xml::XmlVersion::Implicit1_0)
                .map_err(|e| invalid(path, format!("XML attribute: {e}")))?
                .trim()
                .to_string();
            let key = attr.key.local_name().as_ref().to_string();
            Ok((key, value))
        })
        .collect()
}

/// A `<DataArray>`'s attributes.
fn data_array(path: &Path, e: &quick_xml::events::BytesStart) -> Result<DataArray, IoError> {
    let mut a = DataArray::default();
    let mut dims = [None; 6];
    let mut dimensionality = None;
    for (key, value) in attributes(path, e)? {
        match key.as_str() {
            "Intent" => a.intent = value,
            "DataType" => a.data_type = value,
            "ArrayIndexingOrder" => a.column_major = value == "ColumnMajorOrder",
            "Encoding" => a.encoding = value,
            "Endian" => a.big_endian = value == "BigEndian",
            "ExternalFileName" => a.external.0 = value,
            "ExternalFileOffset" => a.external.1 = value,
            "Dimensionality" => dimensionality = Some(parse_usize(path, &value)?),
            k if k.len() == 4 && k.starts_with("Dim") && k.as_bytes()[3].is_ascii_digit() => {
                let i = (k.as_bytes()[3] - b'0') as usize;
                if i < 6 {
                    dims[i] = Some(parse_usize(path, &value)?);
                }
            }
            _ => {}
        }
    }
    let nd = dimensionality.ok_or_else(|| invalid(path, "a DataArray lacks Dimensionality"))?;
    if !(1..=6).contains(&nd) {
        return Err(invalid(path, format!("Dimensionality {nd} is not 1..6")));
    }
    a.dims = (0..nd)
        .map(|i| dims[i].ok_or_else(|| invalid(path, format!("a DataArray lacks Dim{i}"))))
        .collect::<Result<_, _>>()?;
    Ok(a)
}

/// A `<Label>`'s attributes (its name is the element's text, added later).
fn label(path: &Path, e: &quick_xml::events::BytesStart) -> Result<Label, IoError> {
    let mut l = Label {
        key: 0,
        name: String::new(),
        rgba: [0.0; 4],
    };
    for (key, value) in attributes(path, e)? {
        let channel = ["Red", "Green", "Blue", "Alpha"]
            .iter()
            .position(|&c| c == key);
        if key == "Key" || key == "Index" {
            l.key = value
                .parse()
                .map_err(|_| invalid(path, format!("label key '{value}' is not an integer")))?;
        } else if let Some(i) = channel {
            l.rgba[i] = value
                .parse()
                .map_err(|_| invalid(path, format!("label colour '{value}' is not a number")))?;
        }
    }
    Ok(l)
}

fn add_text(c: &mut Collect, s: &str) {
    let top = c.stack.last().map(String::as_str);
    if top == Some("Label") {
        if let Some(l) = c.labels.last_mut() {
            l.name.push_str(s.trim());
        }
        return;
    }
    let in_md = c.stack.len() >= 2 && c.stack[c.stack.len() - 2] == "MD";
    let Some(a) = c.current.as_mut() else { return };
    match top {
        Some("Data") => {
            if a.data.len().saturating_add(s.len()) > a.data_cap() {
                a.overflow = true;
            } else {
                a.data.push_str(s);
            }
        }
        Some("Name") if in_md => c.md.0.push_str(s.trim()),
        Some("Value") if in_md => c.md.1.push_str(s.trim()),
        Some("DataSpace") => a.data_space = Some(s.trim().to_string()),
        Some("TransformedSpace") => a.transformed_space = Some(s.trim().to_string()),
        Some("MatrixData") => a.matrix.get_or_insert_with(String::new).push_str(s),
        _ => {}
    }
}

fn parse_usize(path: &Path, s: &str) -> Result<usize, IoError> {
    s.parse()
        .map_err(|_| invalid(path, format!("'{s}' is not a dimension")))
}

/// The array's values in file order (row-major unless the array says otherwise), as f64.
fn values(path: &Path, a: &DataArray) -> Result<Vec<f64>, IoError> {
    let count = a
        .dims
        .iter()
        .try_fold(1usize, |acc, &d| acc.checked_mul(d))
        .filter(|&c| c <= 1 << 31)
        .ok_or_else(|| IoError::TooLarge {
            path: path.into(),
            what: format!("data array dimensions {:?}", a.dims),
        })?;
    if a.overflow {
        return Err(IoError::SizeMismatch {
            path: path.into(),
            what: format!(
                "{} array: more than {} characters of data for {count} values",
                a.intent,
                a.data_cap()
            ),
        });
    }
    let size = match a.data_type.as_str() {
        "NIFTI_TYPE_UINT8" => 1,
        "NIFTI_TYPE_INT32" | "NIFTI_TYPE_FLOAT32" => 4,
        "NIFTI_TYPE_FLOAT64" => 8,
        t => {
            return Err(IoError::Unsupported {
                path: path.into(),
                what: one_line(&format!("GIFTI data type '{t}'")),
            })
        }
    };
    let bytes = match a.encoding.as_str() {
        "ASCII" | "GIFTI_ENCODING_ASCII" => {
            let v: Vec<f64> = a
                .data
                .split_whitespace()
                .map(|x| {
                    x.parse::<f64>()
                        .map_err(|_| invalid(path, format!("'{x}' is not a number")))
                })
                .collect::<Result<_, _>>()?;
            if v.len() != count {
                return Err(IoError::SizeMismatch {
                    path: path.into(),
                    what: format!(
                        "{} array: {count} values announced, {} found",
                        a.intent,
                        v.len()
                    ),
                });
            }
            return Ok(v);
        }
        "Base64Binary" | "GZipBase64Binary" | "GIFTI_ENCODING_B64BIN" | "GIFTI_ENCODING_B64GZ" => {
            let compact: Vec<u8> = a
                .data
                .bytes()
                .filter(|b| !b.is_ascii_whitespace())
                .collect();
            let raw = base64::engine::general_purpose::STANDARD
                .decode(&compact)
                .map_err(|e| invalid(path, format!("{} array: bad base64: {e}", a.intent)))?;
            if matches!(
                a.encoding.as_str(),
                "GZipBase64Binary" | "GIFTI_ENCODING_B64GZ"
            ) {
                let dec = flate2::read::ZlibDecoder::new(raw.as_slice());
                let mut out = Vec::new();
                dec.take(count as u64 * size as u64 + 1)
                    .read_to_end(&mut out)
                    .map_err(|e| {
                        invalid(path, format!("{} array: bad zlib data: {e}", a.intent))
                    })?;
                out
            } else {
                raw
            }
        }
        "ExternalFileBinary" | "GIFTI_ENCODING_EXTBIN" => external(path, a, count * size)?,
        e => return Err(invalid(path, format!("unknown GIFTI encoding '{e}'"))),
    };
    if bytes.len() != count * size {
        return Err(IoError::SizeMismatch {
            path: path.into(),
            what: format!(
                "{} array: {:?} {} needs {} bytes, the data holds {}",
                a.intent,
                a.dims,
                a.data_type,
                count * size,
                bytes.len()
            ),
        });
    }
    let be = a.big_endian;
    let v = match size {
        1 => bytes.iter().map(|&b| f64::from(b)).collect(),
        4 => bytes
            .chunks_exact(4)
            .map(|c| {
                let c: [u8; 4] = c.try_into().expect("4 bytes");
                let bits = if be {
                    u32::from_be_bytes(c)
                } else {
                    u32::from_le_bytes(c)
                };
                if a.data_type == "NIFTI_TYPE_INT32" {
                    f64::from(bits as i32)
                } else {
                    f64::from(f32::from_bits(bits))
                }
            })
            .collect(),
        _ => bytes
            .chunks_exact(8)
            .map(|c| {
                let c: [u8; 8] = c.try_into().expect("8 bytes");
                if be {
                    f64::from_be_bytes(c)
                } else {
                    f64::from_le_bytes(c)
                }
            })
            .collect(),
    };
    Ok(v)
}

/// The `nbytes` of an ExternalFileBinary array: raw samples at ExternalFileOffset in
/// ExternalFileName, which must be inside the GIFTI's directory (a relative path without
/// `..`, and no symlink leading out), so a downloaded file cannot make glint read
/// arbitrary files.
fn external(path: &Path, a: &DataArray, nbytes: usize) -> Result<Vec<u8>, IoError> {
    let (name, offset) = &a.external;
    let outside = |why: &str| IoError::Unsupported {
        path: path.into(),
        what: one_line(&format!(
            "external file '{name}' {why}: only files in the GIFTI's own directory are read"
        )),
    };
    if name.is_empty() {
        return Err(invalid(
            path,
            "an ExternalFileBinary array has no ExternalFileName",
        ));
    }
    let rel = Path::new(name);
    if rel
        .components()
        .any(|c| !matches!(c, std::path::Component::Normal(_)))
    {
        return Err(outside("is absolute or contains '..'"));
    }
    let dir = match path.parent() {
        Some(d) if !d.as_os_str().is_empty() => d,
        _ => Path::new("."),
    };
    let full = dir.join(rel);
    let os = |e| IoError::Os {
        path: full.clone(),
        source: e,
    };
    let canonical = full.canonicalize().map_err(os)?;
    if !canonical.starts_with(dir.canonicalize().map_err(os)?) {
        return Err(outside("leads out of the directory through a symlink"));
    }
    let offset: u64 = if offset.is_empty() {
        0
    } else {
        offset.parse().map_err(|_| {
            invalid(
                path,
                format!("ExternalFileOffset '{offset}' is not a byte offset"),
            )
        })?
    };
    let mut file = open(&full)?;
    let len = file.metadata().map_err(os)?.len();
    if len < offset.saturating_add(nbytes as u64) {
        return Err(IoError::SizeMismatch {
            path: path.into(),
            what: one_line(&format!(
                "{} array: {nbytes} bytes at offset {offset} of '{name}', which has {len}",
                a.intent
            )),
        });
    }
    file.seek(std::io::SeekFrom::Start(offset)).map_err(os)?;
    read_exact_growing(&full, file, nbytes, "external GIFTI array")
}

/// An N x 3 array as rows.
fn rows3<T: Copy + Default>(
    path: &Path,
    a: &DataArray,
    what: &str,
    conv: impl Fn(f64) -> T,
) -> Result<Vec<[T; 3]>, IoError> {
    if a.dims.len() != 2 || a.dims[1] != 3 {
        return Err(invalid(
            path,
            format!(
                "the {what} array has dimensions {:?}, expected N x 3",
                a.dims
            ),
        ));
    }
    let n = a.dims[0];
    let v = values(path, a)?;
    Ok((0..n)
        .map(|i| {
            std::array::from_fn(|j| {
                conv(if a.column_major {
                    v[j * n + i]
                } else {
                    v[3 * i + j]
                })
            })
        })
        .collect())
}

/// Writes a GIFTI surface (POINTSET in NIFTI_XFORM_UNKNOWN space, TRIANGLE, and
/// normals and scalars when present) with the given encoding; gzip-compresses the whole
/// file when the name ends in `.gz`.
pub fn write(path: &Path, mesh: &Mesh, encoding: Encoding) -> Result<(), IoError> {
    let mut xml = String::from(
        "<?xml version=\"1.0\" encoding=\"UTF-8\"?>\n\
         <!DOCTYPE GIFTI SYSTEM \"http://gifti.projects.nitrc.org/gifti.dtd\">\n",
    );
    let count = 2 + usize::from(mesh.normals.is_some()) + usize::from(mesh.scalars.is_some());
    xml += &format!("<GIFTI Version=\"1.0\" NumberOfDataArrays=\"{count}\">\n");
    let flat = |rows: &[[f32; 3]]| {
        rows.iter()
            .flatten()
            .map(|&x| f64::from(x))
            .collect::<Vec<_>>()
    };
    array(
        &mut xml,
        "NIFTI_INTENT_POINTSET",
        "NIFTI_TYPE_FLOAT32",
        &[mesh.positions.len(), 3],
        &flat(&mesh.positions),
        encoding,
        true,
    );
    let tris: Vec<f64> = mesh
        .triangles
        .iter()
        .flatten()
        .map(|&i| f64::from(i))
        .collect();
    array(
        &mut xml,
        "NIFTI_INTENT_TRIANGLE",
        "NIFTI_TYPE_INT32",
        &[mesh.triangles.len(), 3],
        &tris,
        encoding,
        false,
    );
    if let Some(n) = &mesh.normals {
        array(
            &mut xml,
            "NIFTI_INTENT_VECTOR",
            "NIFTI_TYPE_FLOAT32",
            &[n.len(), 3],
            &flat(n),
            encoding,
            false,
        );
    }
    if let Some(s) = &mesh.scalars {
        let v: Vec<f64> = s.iter().map(|&x| f64::from(x)).collect();
        array(
            &mut xml,
            "NIFTI_INTENT_SHAPE",
            "NIFTI_TYPE_FLOAT32",
            &[s.len()],
            &v,
            encoding,
            false,
        );
    }
    xml += "</GIFTI>\n";
    let gz = path.to_string_lossy().to_ascii_lowercase().ends_with(".gz");
    write_atomic(path, |w| {
        if gz {
            let mut e = flate2::write::GzEncoder::new(w, flate2::Compression::default());
            e.write_all(xml.as_bytes())?;
            e.finish()?;
            Ok(())
        } else {
            w.write_all(xml.as_bytes())
        }
    })
}

fn array(
    xml: &mut String,
    intent: &str,
    data_type: &str,
    dims: &[usize],
    v: &[f64],
    encoding: Encoding,
    coordinates: bool,
) {
    let enc = match encoding {
        Encoding::Ascii => "ASCII",
        Encoding::Base64 => "Base64Binary",
        Encoding::GzipBase64 => "GZipBase64Binary",
    };
    xml.push_str(&format!(
        "  <DataArray Intent=\"{intent}\" DataType=\"{data_type}\" \
         ArrayIndexingOrder=\"RowMajorOrder\" Dimensionality=\"{}\"",
        dims.len()
    ));
    for (i, d) in dims.iter().enumerate() {
        xml.push_str(&format!(" Dim{i}=\"{d}\""));
    }
    xml.push_str(&format!(
        " Encoding=\"{enc}\" Endian=\"LittleEndian\" ExternalFileName=\"\" ExternalFileOffset=\"\">\n"
    ));
    if coordinates {
        xml.push_str(
            "    <CoordinateSystemTransformMatrix>\n\
             <DataSpace><![CDATA[NIFTI_XFORM_UNKNOWN]]></DataSpace>\n\
             <TransformedSpace><![CDATA[NIFTI_XFORM_UNKNOWN]]></TransformedSpace>\n\
             <MatrixData>1 0 0 0 0 1 0 0 0 0 1 0 0 0 0 1</MatrixData>\n\
             </CoordinateSystemTransformMatrix>\n",
        );
    }
    let int = data_type == "NIFTI_TYPE_INT32";
    let data = match encoding {
        Encoding::Ascii => v
            .iter()
            .map(|x| {
                if int {
                    format!("{}", *x as i64)
                } else {
                    format!("{}", *x as f32)
                }
            })
            .collect::<Vec<_>>()
            .join(" "),
        _ => {
            let bytes: Vec<u8> = v
                .iter()
                .flat_map(|&x| {
                    if int {
                        (x as i32).to_le_bytes()
                    } else {
                        (x as f32).to_le_bytes()
                    }
                })
                .collect();
            let bytes = if encoding == Encoding::GzipBase64 {
                let mut e =
                    flate2::write::ZlibEncoder::new(Vec::new(), flate2::Compression::default());
                e.write_all(&bytes).expect("writing to a Vec cannot fail");
                e.finish().expect("writing to a Vec cannot fail")
            } else {
                bytes
            };
            base64::engine::general_purpose::STANDARD.encode(bytes)
        }
    };
    xml.push_str("    <Data>");
    xml.push_str(&data);
    xml.push_str("</Data>\n  </DataArray>\n");
}
