//! The samples: the data file (attached or detached) and its `raw`, `gzip` or `text`
//! encoding.

use std::fs::File;
use std::io::{BufRead, BufReader, Read, Seek, SeekFrom};
use std::path::{Path, PathBuf};

use flate2::read::MultiGzDecoder;

use super::header::{ByteSkip, Codec, Fields, Layout};
use super::{invalid, MAX_HEADER_BYTES};
use crate::clock::Clock;
use crate::common::{open, os_or_invalid, read_decoded, ScalarType};
use crate::{IoError, Samples};

/// Opens the file holding the samples (the header's own file after its blank line, or
/// the detached `data file`) and skips its first `line_skip` lines.
pub(super) fn open_data(
    path: &Path,
    fields: &Fields,
    line_skip: u64,
) -> Result<(PathBuf, BufReader<File>), IoError> {
    let (dpath, start) = data_location(path, fields)?;
    let mut data = BufReader::new(open(&dpath)?);
    data.seek(SeekFrom::Start(start))
        .map_err(|e| os_or_invalid(&dpath, e))?;
    for _ in 0..line_skip {
        let mut skip = Vec::new();
        // Each skipped line is bounded like a header line.
        let n = (&mut data)
            .take(MAX_HEADER_BYTES)
            .read_until(b'\n', &mut skip)
            .map_err(|e| os_or_invalid(&dpath, e))?;
        if n == 0 {
            return Err(IoError::Truncated {
                path: dpath,
                what: "the file ends within 'line skip'".into(),
            });
        }
    }
    Ok((dpath, data))
}

/// The file holding the samples and the offset where they start: a detached `data file`
/// (relative to the header's directory) from its start, or the header's own file after
/// the header. Multi-file data (`LIST`, `%d` patterns) is not read.
fn data_location(path: &Path, fields: &Fields) -> Result<(PathBuf, u64), IoError> {
    match fields.get("data file").or(fields.get("datafile")) {
        Some(name) => {
            if name.starts_with("LIST") || name.contains('%') {
                return Err(IoError::Unsupported {
                    path: path.into(),
                    what: "multi-file NRRD data (LIST or %d patterns)".into(),
                });
            }
            let p = Path::new(name);
            let p = if p.is_absolute() {
                p.to_path_buf()
            } else {
                path.parent().unwrap_or(Path::new(".")).join(p)
            };
            Ok((p, 0))
        }
        None if fields.ended => Ok((path.to_path_buf(), fields.len)),
        None => Err(IoError::Truncated {
            path: path.into(),
            what: "the header has no blank line ending it and names no data file".into(),
        }),
    }
}

/// Decodes the samples from `data` (the data file `dpath` after its skipped lines); an
/// unsupported encoding is reported against the header `path`. Time spent inflating
/// gzip data goes to `clock`.
pub(super) fn decode(
    path: &Path,
    dpath: &Path,
    data: BufReader<File>,
    layout: &Layout,
    clock: &Clock,
) -> Result<Samples, IoError> {
    match &layout.codec {
        Codec::Raw => decode_raw(dpath, data, layout),
        Codec::Gzip => decode_gzip(path, dpath, data, layout, clock),
        Codec::Text => decode_text(dpath, data, layout),
        Codec::Other(e) => Err(IoError::Unsupported {
            path: path.into(),
            what: format!("NRRD encoding '{e}'; supported: raw, gzip, text"),
        }),
    }
}

/// Raw samples: the announced size is checked against the file's length before it is
/// read.
fn decode_raw(
    dpath: &Path,
    mut data: BufReader<File>,
    layout: &Layout,
) -> Result<Samples, IoError> {
    let nbytes = layout.nbytes;
    let pos = data
        .stream_position()
        .map_err(|e| os_or_invalid(dpath, e))?;
    let len = data
        .get_ref()
        .metadata()
        .map_err(|e| os_or_invalid(dpath, e))?
        .len();
    let available = len.saturating_sub(pos);
    let skip = match layout.byte_skip {
        ByteSkip::ToEnd => {
            available
                .checked_sub(nbytes as u64)
                .ok_or_else(|| IoError::SizeMismatch {
                    path: dpath.into(),
                    what: format!(
                        "'byte skip: -1' but the file holds {available} bytes of the {nbytes} \
                     announced"
                    ),
                })?
        }
        ByteSkip::Bytes(b) => b,
    };
    if available < skip.saturating_add(nbytes as u64) {
        let [x, y, z] = layout.dims;
        return Err(IoError::SizeMismatch {
            path: dpath.into(),
            what: format!(
                "the header announces {nbytes} bytes of {} data ({x}x{y}x{z}) after {skip} \
                 skipped, but {available} bytes follow the header",
                layout.ty
            ),
        });
    }
    // skip <= available <= the file's length, which fits an i64.
    data.seek(SeekFrom::Current(skip as i64))
        .map_err(|e| os_or_invalid(dpath, e))?;
    read_decoded(
        dpath,
        data,
        layout.count,
        layout.ty,
        layout.endian,
        "voxel data",
        true,
    )
}

/// Gzip-compressed samples (concatenated members allowed); `byte skip` counts bytes
/// after decompression. The inflater is timed by `clock`.
fn decode_gzip(
    path: &Path,
    dpath: &Path,
    data: BufReader<File>,
    layout: &Layout,
    clock: &Clock,
) -> Result<Samples, IoError> {
    let ByteSkip::Bytes(byte_skip) = layout.byte_skip else {
        return Err(invalid(
            path,
            "'byte skip: -1' is only allowed with raw encoding",
        ));
    };
    let mut gz = BufReader::new(clock.timed(MultiGzDecoder::new(data)));
    let skipped = std::io::copy(&mut (&mut gz).take(byte_skip), &mut std::io::sink())
        .map_err(|e| os_or_invalid(dpath, e))?;
    if skipped < byte_skip {
        return Err(IoError::Truncated {
            path: dpath.into(),
            what: "data ends within 'byte skip'".into(),
        });
    }
    let what = "gzip-compressed voxel data";
    read_decoded(
        dpath,
        gz,
        layout.count,
        layout.ty,
        layout.endian,
        what,
        false,
    )
}

/// Samples as text numbers separated by white space or commas.
fn decode_text(dpath: &Path, data: BufReader<File>, layout: &Layout) -> Result<Samples, IoError> {
    let mut text = String::new();
    // At most ~32 characters per number.
    data.take(32 * layout.count as u64 + 1024)
        .read_to_string(&mut text)
        .map_err(|e| os_or_invalid(dpath, e))?;
    parse_text(dpath, &text, layout.ty, layout.count)
}

fn parse_text(path: &Path, text: &str, ty: ScalarType, count: usize) -> Result<Samples, IoError> {
    let tokens: Vec<&str> = text
        .split(|c: char| c.is_whitespace() || c == ',')
        .filter(|t| !t.is_empty())
        .take(count + 1)
        .collect();
    if tokens.len() != count {
        return Err(IoError::SizeMismatch {
            path: path.into(),
            what: format!(
                "the header announces {count} values, the text holds {}",
                if tokens.len() > count {
                    "more".to_string()
                } else {
                    tokens.len().to_string()
                }
            ),
        });
    }
    macro_rules! parse {
        ($t:ty, $v:ident) => {
            Samples::$v(
                tokens
                    .iter()
                    .map(|t| {
                        t.parse::<$t>()
                            .map_err(|_| invalid(path, format!("'{t}' is not a {}", ty)))
                    })
                    .collect::<Result<_, _>>()?,
            )
        };
    }
    Ok(match ty {
        ScalarType::U8 => parse!(u8, U8),
        ScalarType::I8 => parse!(i8, I8),
        ScalarType::U16 => parse!(u16, U16),
        ScalarType::I16 => parse!(i16, I16),
        ScalarType::U32 => parse!(u32, U32),
        ScalarType::I32 => parse!(i32, I32),
        ScalarType::F32 => parse!(f32, F32),
        ScalarType::F64 => parse!(f64, F64),
    })
}
