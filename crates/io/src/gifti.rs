//! GIFTI surfaces (`.gii`, `.gii.gz`): the geometry format of FreeSurfer, Connectome
//! Workbench and nilearn.
//!
//! No maintained Rust crate reads GIFTI, so this module walks the XML with quick-xml
//! and decodes the data arrays with base64 and flate2, following the GIFTI 1.0 spec
//! (<https://www.nitrc.org/projects/gifti/>, "GIFTI Surface Data Format Version 1.0").
//! Encodings: ASCII, Base64Binary, GZipBase64Binary (zlib-compressed, then base64);
//! external-file arrays are refused.

use std::io::{Read, Write};
use std::path::Path;

use base64::Engine;
use quick_xml::events::Event;

use crate::common::{is_gzip, open, os_or_invalid, write_atomic};
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

#[derive(Default, Debug)]
struct DataArray {
    intent: String,
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

fn invalid(path: &Path, what: impl Into<String>) -> IoError {
    IoError::Invalid {
        path: path.into(),
        what: what.into(),
    }
}

/// Reads a GIFTI surface: the POINTSET array gives the positions, the TRIANGLE array
/// the faces; a VECTOR array with one row per vertex becomes the normals and the first
/// one-value-per-vertex array the scalars.
pub fn read(path: &Path) -> Result<MeshFile, IoError> {
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
    let arrays = parse_xml(path, &text)?;

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

fn parse_xml(path: &Path, text: &str) -> Result<Vec<DataArray>, IoError> {
    let mut reader = quick_xml::Reader::from_str(text);
    let mut arrays = Vec::new();
    let mut current: Option<DataArray> = None;
    // The innermost open element, for attaching text.
    let mut stack: Vec<String> = Vec::new();
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
                let empty = matches!(event, Event::Empty(_));
                let mut a = DataArray::default();
                let mut dims = [None; 6];
                let mut dimensionality = None;
                for attr in e.attributes() {
                    let attr = attr.map_err(|e| invalid(path, format!("XML attribute: {e}")))?;
                    let value = attr
                        .normalized_value(quick_xml::XmlVersion::Implicit1_0)
                        .map_err(|e| invalid(path, format!("XML attribute: {e}")))?
                        .trim()
                        .to_string();
                    match attr.key.local_name().as_ref() {
                        "Intent" => a.intent = value,
                        "DataType" => a.data_type = value,
                        "ArrayIndexingOrder" => a.column_major = value == "ColumnMajorOrder",
                        "Encoding" => a.encoding = value,
                        "Endian" => a.big_endian = value == "BigEndian",
                        "Dimensionality" => dimensionality = Some(parse_usize(path, &value)?),
                        k if k.len() == 4
                            && k.starts_with("Dim")
                            && k.as_bytes()[3].is_ascii_digit() =>
                        {
                            let i = (k.as_bytes()[3] - b'0') as usize;
                            if i < 6 {
                                dims[i] = Some(parse_usize(path, &value)?);
                            }
                        }
                        _ => {}
                    }
                }
                let nd = dimensionality
                    .ok_or_else(|| invalid(path, "a DataArray lacks Dimensionality"))?;
                if !(1..=6).contains(&nd) {
                    return Err(invalid(path, format!("Dimensionality {nd} is not 1..6")));
                }
                a.dims = (0..nd)
                    .map(|i| {
                        dims[i].ok_or_else(|| invalid(path, format!("a DataArray lacks Dim{i}")))
                    })
                    .collect::<Result<_, _>>()?;
                if empty {
                    arrays.push(a);
                } else {
                    current = Some(a);
                    stack.push("DataArray".into());
                }
            }
            Event::Start(e) => {
                let name = e.local_name().as_ref().to_string();
                if name == "GIFTI" {
                    saw_root = true;
                }
                stack.push(name);
            }
            Event::End(e) => {
                if e.local_name().as_ref() == "DataArray" {
                    if let Some(a) = current.take() {
                        arrays.push(a);
                    }
                }
                stack.pop();
            }
            Event::Text(t) => {
                let s = t.xml10_content();
                add_text(&mut current, &stack, &s);
            }
            Event::CData(t) => {
                let s = t.xml10_content();
                add_text(&mut current, &stack, &s);
            }
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
    Ok(arrays)
}

fn add_text(current: &mut Option<DataArray>, stack: &[String], s: &str) {
    let Some(a) = current.as_mut() else { return };
    match stack.last().map(String::as_str) {
        Some("Data") => {
            if a.data.len().saturating_add(s.len()) > a.data_cap() {
                a.overflow = true;
            } else {
                a.data.push_str(s);
            }
        }
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
                what: format!("GIFTI data type '{t}'"),
            })
        }
    };
    let bytes = match a.encoding.as_str() {
        "ASCII" => {
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
        "Base64Binary" | "GZipBase64Binary" => {
            let compact: Vec<u8> = a
                .data
                .bytes()
                .filter(|b| !b.is_ascii_whitespace())
                .collect();
            let raw = base64::engine::general_purpose::STANDARD
                .decode(&compact)
                .map_err(|e| invalid(path, format!("{} array: bad base64: {e}", a.intent)))?;
            if a.encoding == "GZipBase64Binary" {
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
        "ExternalFileBinary" => {
            return Err(IoError::Unsupported {
                path: path.into(),
                what: "GIFTI arrays in external files".into(),
            })
        }
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
