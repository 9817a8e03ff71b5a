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

//!
//! The module is split by concern: `xml` reads the document into undecoded data
//! arrays, `decode` turns an array's text into numbers, `write` writes surfaces; this
//! file holds the public types and puts arrays together into surfaces and per-vertex
//! data.

mod decode;
mod write;
mod xml;

use std::path::Path;

use crate::mesh::check_indices;
use crate::{Format, IoError, Mesh, MeshFile};

use decode::{rows3, values};
use xml::{load, DataArray};

pub use write::write;

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
#[derive(Clone, Debug, PartialEq, serde::Serialize)]
pub struct Label {
    /// The key vertices carry.
    pub key: i32,
    /// The label's name.
    pub name: String,
    /// Red, green, blue, alpha in 0..1 (0 where the file gives none).
    pub rgba: [f32; 4],
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
    vertex_data(path, &arrays, &table)
}

/// A GIFTI file's surface and its per-vertex data ([`read`] and
/// [`read_surface_data`]) from one read of the file. The surface is `None` for a file of
/// per-vertex data alone (a sulcal depth map, a parcellation: arrays but no POINTSET);
/// a file with neither is an error, as [`read`] gives it.
pub fn read_with_data(path: &Path) -> Result<(Option<MeshFile>, Vec<VertexData>), IoError> {
    let (arrays, table) = load(path)?;
    let data = vertex_data(path, &arrays, &table)?;
    let has_surface = arrays.iter().any(|a| a.intent == "NIFTI_INTENT_POINTSET");
    if !has_surface && !data.is_empty() {
        return Ok((None, data));
    }
    Ok((Some(surface(path, &arrays)?), data))
}

/// The per-vertex arrays of [`read_surface_data`], from the file's arrays and label
/// table.
fn vertex_data(
    path: &Path,
    arrays: &[DataArray],
    table: &[Label],
) -> Result<Vec<VertexData>, IoError> {
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
                    table: table.to_vec(),
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
