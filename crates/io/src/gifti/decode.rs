//! Decoding a data array's `<Data>`: ASCII numbers, Base64 (optionally zlib-compressed)
//! binary, or an external binary file, to f64 values in file order.

use std::io::{Read, Seek};
use std::path::Path;

use base64::Engine;

use super::xml::DataArray;
use super::{invalid, one_line};
use crate::common::{open, read_exact_growing};
use crate::IoError;

/// The array's values in file order (row-major unless the array says otherwise), as f64.
///
/// The steps: the announced count (bounded) and sample size, then the text decoded by
/// the array's encoding (ASCII numbers are the values themselves; the binary encodings
/// give bytes), then the bytes' size checked and converted.
pub(super) fn values(path: &Path, a: &DataArray) -> Result<Vec<f64>, IoError> {
    let count = value_count(path, a)?;
    let size = sample_size(path, a)?;
    let bytes = match a.encoding.as_str() {
        "ASCII" | "GIFTI_ENCODING_ASCII" => return ascii_values(path, a, count),
        "Base64Binary" | "GIFTI_ENCODING_B64BIN" => base64_bytes(path, a)?,
        "GZipBase64Binary" | "GIFTI_ENCODING_B64GZ" => {
            inflate(path, a, &base64_bytes(path, a)?, count * size)?
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
    Ok(binary_values(a, size, &bytes))
}

/// The number of values the dimensions announce (at most 2^31), and that the `<Data>`
/// text was not cut for running past what they allow.
fn value_count(path: &Path, a: &DataArray) -> Result<usize, IoError> {
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
    Ok(count)
}

/// Bytes per value of the array's data type.
fn sample_size(path: &Path, a: &DataArray) -> Result<usize, IoError> {
    Ok(match a.data_type.as_str() {
        "NIFTI_TYPE_UINT8" => 1,
        "NIFTI_TYPE_INT32" | "NIFTI_TYPE_FLOAT32" => 4,
        "NIFTI_TYPE_FLOAT64" => 8,
        t => {
            return Err(IoError::Unsupported {
                path: path.into(),
                what: one_line(&format!("GIFTI data type '{t}'")),
            })
        }
    })
}

/// ASCII data: exactly `count` whitespace-separated numbers.
fn ascii_values(path: &Path, a: &DataArray, count: usize) -> Result<Vec<f64>, IoError> {
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
    Ok(v)
}

/// The base64 text of `<Data>` (line breaks and spaces ignored) as bytes.
fn base64_bytes(path: &Path, a: &DataArray) -> Result<Vec<u8>, IoError> {
    let compact: Vec<u8> = a
        .data
        .bytes()
        .filter(|b| !b.is_ascii_whitespace())
        .collect();
    base64::engine::general_purpose::STANDARD
        .decode(&compact)
        .map_err(|e| invalid(path, format!("{} array: bad base64: {e}", a.intent)))
}

/// Inflates zlib data, stopping one byte past the `nbytes` expected (so a bomb costs no
/// more than that, and a longer stream is still seen to be too long).
fn inflate(path: &Path, a: &DataArray, raw: &[u8], nbytes: usize) -> Result<Vec<u8>, IoError> {
    let dec = flate2::read::ZlibDecoder::new(raw);
    let mut out = Vec::new();
    dec.take(nbytes as u64 + 1)
        .read_to_end(&mut out)
        .map_err(|e| invalid(path, format!("{} array: bad zlib data: {e}", a.intent)))?;
    Ok(out)
}

/// Binary values (`size` bytes each, the array's byte order) as f64.
fn binary_values(a: &DataArray, size: usize, bytes: &[u8]) -> Vec<f64> {
    let be = a.big_endian;
    match size {
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
    }
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
pub(super) fn rows3<T: Copy + Default>(
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
