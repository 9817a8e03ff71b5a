//! The header: the magic line, the `field: value` lines, and the sample layout they
//! announce, validated before anything is allocated for the samples.

use std::collections::HashMap;
use std::io::{BufRead, BufReader, Read};
use std::path::Path;

use super::{invalid, truncate, MAX_HEADER_BYTES};
use crate::common::{checked_voxels, open, os_or_invalid, Endian, ScalarType};
use crate::{IoError, ReadOptions};

fn scalar_type(path: &Path, name: &str) -> Result<ScalarType, IoError> {
    let n = name.trim().to_ascii_lowercase();
    let n = n.split_whitespace().collect::<Vec<_>>().join(" ");
    Ok(match n.as_str() {
        "signed char" | "int8" | "int8_t" => ScalarType::I8,
        "uchar" | "unsigned char" | "uint8" | "uint8_t" => ScalarType::U8,
        "short" | "short int" | "signed short" | "signed short int" | "int16" | "int16_t" => {
            ScalarType::I16
        }
        "ushort" | "unsigned short" | "unsigned short int" | "uint16" | "uint16_t" => {
            ScalarType::U16
        }
        "int" | "signed int" | "int32" | "int32_t" => ScalarType::I32,
        "uint" | "unsigned int" | "uint32" | "uint32_t" => ScalarType::U32,
        "float" => ScalarType::F32,
        "double" => ScalarType::F64,
        _ => {
            return Err(IoError::Unsupported {
                path: path.into(),
                what: format!(
                    "NRRD type '{name}'; supported: int8, uint8, int16, uint16, int32, uint32, \
                     float, double"
                ),
            })
        }
    })
}

/// The `field: value` lines of a header, and where the header ended.
pub(super) struct Fields {
    /// Values by field name, names lower-cased; the last of a repeated field wins.
    pub(super) map: HashMap<String, String>,
    /// Whether a blank line ended the header (attached data may follow it).
    pub(super) ended: bool,
    /// Bytes read from the header file, the blank line included: where attached data
    /// starts.
    pub(super) len: u64,
}

impl Fields {
    pub(super) fn get(&self, key: &str) -> Option<&str> {
        self.map.get(key).map(String::as_str)
    }

    pub(super) fn required(&self, path: &Path, key: &str) -> Result<&str, IoError> {
        self.get(key)
            .ok_or_else(|| invalid(path, format!("missing required field '{key}'")))
    }
}

/// Reads the magic line and the header's fields, up to the blank line that ends it (or
/// the end of the file, for a detached header); at most [`MAX_HEADER_BYTES`].
pub(super) fn read_fields(path: &Path) -> Result<Fields, IoError> {
    let file = open(path)?;
    let mut reader = BufReader::new(file).take(MAX_HEADER_BYTES);
    let mut fields = Fields {
        map: HashMap::new(),
        ended: false,
        len: check_magic(path, &mut reader)?,
    };
    let mut line = String::new();
    loop {
        line.clear();
        let n = reader
            .read_line(&mut line)
            .map_err(|e| os_or_invalid(path, e))?;
        fields.len += n as u64;
        if n == 0 {
            break;
        }
        if !line.ends_with('\n') && fields.len >= MAX_HEADER_BYTES {
            return Err(invalid(
                path,
                format!("header longer than {MAX_HEADER_BYTES} bytes"),
            ));
        }
        let l = line.trim_end_matches(['\n', '\r']);
        if l.is_empty() {
            fields.ended = true;
            break;
        }
        if let Some((k, v)) = parse_line(path, l)? {
            fields.map.insert(k, v);
        }
    }
    Ok(fields)
}

/// Checks the first line is `NRRD0001` .. `NRRD0005`; returns its length in bytes.
fn check_magic(path: &Path, reader: &mut impl BufRead) -> Result<u64, IoError> {
    let mut first = Vec::new();
    let n = reader
        .take(64)
        .read_until(b'\n', &mut first)
        .map_err(|e| os_or_invalid(path, e))?;
    let magic = String::from_utf8_lossy(&first);
    let magic = magic.trim_end();
    if !(magic.len() == 8
        && magic.starts_with("NRRD000")
        && (b'1'..=b'5').contains(&magic.as_bytes()[7]))
    {
        return Err(IoError::BadMagic {
            path: path.into(),
            format: "NRRD",
            what: format!(
                "first line is {:?}, expected NRRD0001..NRRD0005",
                truncate(magic)
            ),
        });
    }
    Ok(n as u64)
}

/// Parses a non-blank header line: a `field: value` pair (name lower-cased, both
/// trimmed), or `None` for a comment or a `key:=value` pair.
fn parse_line(path: &Path, l: &str) -> Result<Option<(String, String)>, IoError> {
    if l.starts_with('#') || l.contains(":=") {
        return Ok(None);
    }
    // A carriage return or other control character inside a field would be quoted
    // into an error message over several lines (found by fuzzing, issue 17).
    if l.chars().any(|c| c.is_control() && c != '\t') {
        return Err(invalid(
            path,
            format!("header line {:?} contains control characters", truncate(l)),
        ));
    }
    let (k, v) = l.split_once(": ").ok_or_else(|| {
        invalid(
            path,
            format!("header line {:?} is not 'field: value'", truncate(l)),
        )
    })?;
    Ok(Some((k.trim().to_ascii_lowercase(), v.trim().to_string())))
}

/// A data `encoding` field, lower-cased.
#[derive(Debug, PartialEq)]
pub(super) enum Codec {
    Raw,
    Gzip,
    Text,
    /// Not read; refused when the samples are decoded (after the data file is opened,
    /// the order in which errors have always been reported).
    Other(String),
}

impl Codec {
    fn parse(name: &str) -> Codec {
        match name.to_ascii_lowercase().as_str() {
            "raw" => Codec::Raw,
            "gzip" | "gz" => Codec::Gzip,
            "txt" | "text" | "ascii" => Codec::Text,
            other => Codec::Other(other.to_string()),
        }
    }
}

/// A `byte skip` field.
#[derive(Clone, Copy, Debug, PartialEq)]
pub(super) enum ByteSkip {
    /// Bytes to skip before the samples.
    Bytes(u64),
    /// `-1`: the samples are the last bytes of the (raw) data file.
    ToEnd,
}

/// The samples a header announces and how they are stored, validated.
pub(super) struct Layout {
    pub(super) ty: ScalarType,
    /// 2 or 3.
    pub(super) dimension: usize,
    /// Sizes, 1 for the third of a 2D image.
    pub(super) dims: [usize; 3],
    /// Voxels, within the reader's limit.
    pub(super) count: usize,
    /// Bytes of the samples: `count` times the sample size, known not to overflow.
    pub(super) nbytes: usize,
    pub(super) codec: Codec,
    pub(super) endian: Endian,
    pub(super) line_skip: u64,
    pub(super) byte_skip: ByteSkip,
}

impl Layout {
    /// Validates the fields that say what the samples are and where they start.
    pub(super) fn parse(
        path: &Path,
        fields: &Fields,
        options: &ReadOptions,
    ) -> Result<Layout, IoError> {
        let ty = scalar_type(path, fields.required(path, "type")?)?;
        let (dimension, dims) = sizes(path, fields)?;
        let count = checked_voxels(path, dims, ty.size(), options.max_voxels)?;
        let codec = Codec::parse(fields.required(path, "encoding")?);
        let endian = endian(path, fields, ty, &codec)?;
        let (line_skip, byte_skip) = skips(path, fields)?;
        Ok(Layout {
            ty,
            dimension,
            dims,
            count,
            nbytes: count * ty.size(),
            codec,
            endian,
            line_skip,
            byte_skip,
        })
    }
}

/// The `dimension` (2 or 3) and the `sizes`, padded to three.
fn sizes(path: &Path, fields: &Fields) -> Result<(usize, [usize; 3]), IoError> {
    let dimension: usize = fields
        .required(path, "dimension")?
        .parse()
        .map_err(|_| invalid(path, "'dimension' is not a number"))?;
    if !(2..=3).contains(&dimension) {
        return Err(IoError::Unsupported {
            path: path.into(),
            what: format!("dimension {dimension}; only 2D and 3D scalar volumes are read"),
        });
    }
    let sizes: Vec<usize> = fields
        .required(path, "sizes")?
        .split_whitespace()
        .map(|s| s.parse::<usize>())
        .collect::<Result<_, _>>()
        .map_err(|_| invalid(path, "'sizes' are not non-negative integers"))?;
    if sizes.len() != dimension {
        return Err(invalid(
            path,
            format!("{} sizes for dimension {dimension}", sizes.len()),
        ));
    }
    Ok((
        dimension,
        [sizes[0], sizes[1], sizes.get(2).copied().unwrap_or(1)],
    ))
}

/// The byte order; needed only for multi-byte samples stored as bytes.
fn endian(path: &Path, fields: &Fields, ty: ScalarType, codec: &Codec) -> Result<Endian, IoError> {
    match fields.get("endian") {
        Some("little") => Ok(Endian::Little),
        Some("big") => Ok(Endian::Big),
        None if ty.size() == 1 || *codec == Codec::Text => Ok(Endian::Little),
        None => Err(invalid(path, "missing 'endian' for multi-byte samples")),
        Some(e) => Err(invalid(
            path,
            format!("endian '{e}' is neither little nor big"),
        )),
    }
}

/// `line skip` (lines) and `byte skip` (bytes, or -1), 0 when absent.
fn skips(path: &Path, fields: &Fields) -> Result<(u64, ByteSkip), IoError> {
    let parse_i64 = |k: &str| -> Result<i64, IoError> {
        fields.get(k).map_or(Ok(0), |v| {
            v.parse()
                .map_err(|_| invalid(path, format!("'{k}' is not an integer")))
        })
    };
    let line_skip = parse_i64("line skip")?;
    let byte_skip = parse_i64("byte skip")?;
    let negative = || invalid(path, "negative 'line skip' or 'byte skip' (other than -1)");
    let line_skip = u64::try_from(line_skip).map_err(|_| negative())?;
    let byte_skip = match byte_skip {
        -1 => ByteSkip::ToEnd,
        b => ByteSkip::Bytes(u64::try_from(b).map_err(|_| negative())?),
    };
    Ok((line_skip, byte_skip))
}
