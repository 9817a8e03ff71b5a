//! NRRD volumes (`.nrrd` attached, `.nhdr` detached header), 3D Slicer's native format.
//!
//! The header is parsed here: the crates.io `nrrd` crates are unmaintained stubs or
//! lack detached headers, gzip and space directions, and the header is a short list of
//! `key: value` lines. Follows the NRRD0005 spec at
//! <https://teem.sourceforge.net/nrrd/format.html>. Supported: dimension 2 or 3, the
//! eight sample types, `raw`, `gzip` and `text` encodings, `byte skip` (including -1 for
//! raw data), `line skip`, `space` (RAS/LPS/LAS, converted to RAS), `space directions`,
//! `space origin`, or `spacings` without a space.

use std::collections::HashMap;
use std::io::{BufRead, BufReader, Read, Seek, SeekFrom, Write};
use std::path::{Path, PathBuf};

use crate::common::{
    check_affine, check_spacing, checked_voxels, decode_samples, diagonal_affine, encode_samples,
    open, os_or_invalid, read_exact_growing, write_atomic, Endian, ScalarType,
};
use crate::{Format, IoError, ReadOptions, Samples, Volume, VolumeFile};

/// Longest header accepted: real headers are a few hundred bytes.
const MAX_HEADER_BYTES: u64 = 1 << 20;

/// NRRD data encodings for [`write()`] and [`write_detached`].
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Encoding {
    /// Samples as bytes.
    Raw,
    /// Samples as bytes, gzip-compressed.
    Gzip,
}

fn invalid(path: &Path, what: impl Into<String>) -> IoError {
    IoError::Invalid {
        path: path.into(),
        what: what.into(),
    }
}

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

/// Parses "(x,y,z)" into three numbers; "none" gives `None`.
fn vector(path: &Path, s: &str) -> Result<Option<[f64; 3]>, IoError> {
    let s = s.trim();
    if s == "none" {
        return Ok(None);
    }
    let inner = s
        .strip_prefix('(')
        .and_then(|s| s.strip_suffix(')'))
        .ok_or_else(|| invalid(path, format!("'{s}' is not a vector like (1,0,0)")))?;
    let v: Vec<f64> = inner
        .split(',')
        .map(|x| x.trim().parse::<f64>())
        .collect::<Result<_, _>>()
        .map_err(|_| invalid(path, format!("'{s}' is not a vector of numbers")))?;
    <[f64; 3]>::try_from(v)
        .map(Some)
        .map_err(|_| invalid(path, format!("'{s}' is not a 3-vector")))
}

/// Splits "(1,0,0) (0,1,0) none" into its items.
fn vectors(s: &str) -> Vec<&str> {
    let mut out = Vec::new();
    let mut rest = s.trim();
    while !rest.is_empty() {
        let end = if rest.starts_with('(') {
            rest.find(')').map_or(rest.len(), |i| i + 1)
        } else {
            rest.find(char::is_whitespace).unwrap_or(rest.len())
        };
        out.push(&rest[..end]);
        rest = rest[end..].trim_start();
    }
    out
}

/// Reads a NRRD volume (attached or detached header).
pub fn read(path: &Path, options: &ReadOptions) -> Result<VolumeFile, IoError> {
    let file = open(path)?;
    let mut reader = BufReader::new(file).take(MAX_HEADER_BYTES);
    let mut first = Vec::new();
    let n = (&mut reader)
        .take(64)
        .read_until(b'\n', &mut first)
        .map_err(|e| os_or_invalid(path, e))?;
    let mut consumed = n as u64;
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
    let mut line = String::new();
    let mut fields: HashMap<String, String> = HashMap::new();
    let mut ended = false;
    loop {
        line.clear();
        let n = reader
            .read_line(&mut line)
            .map_err(|e| os_or_invalid(path, e))?;
        consumed += n as u64;
        if n == 0 {
            break;
        }
        if !line.ends_with('\n') && consumed >= MAX_HEADER_BYTES {
            return Err(invalid(
                path,
                format!("header longer than {MAX_HEADER_BYTES} bytes"),
            ));
        }
        let l = line.trim_end_matches(['\n', '\r']);
        if l.is_empty() {
            ended = true;
            break;
        }
        if l.starts_with('#') || l.contains(":=") {
            continue; // comment or key/value pair
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
        fields.insert(k.trim().to_ascii_lowercase(), v.trim().to_string());
    }
    let field = |k: &str| fields.get(k).map(String::as_str);
    let required =
        |k: &str| field(k).ok_or_else(|| invalid(path, format!("missing required field '{k}'")));

    let ty = scalar_type(path, required("type")?)?;
    let dimension: usize = required("dimension")?
        .parse()
        .map_err(|_| invalid(path, "'dimension' is not a number"))?;
    if !(2..=3).contains(&dimension) {
        return Err(IoError::Unsupported {
            path: path.into(),
            what: format!("dimension {dimension}; only 2D and 3D scalar volumes are read"),
        });
    }
    let sizes: Vec<usize> = required("sizes")?
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
    let dims = [sizes[0], sizes[1], sizes.get(2).copied().unwrap_or(1)];
    let count = checked_voxels(path, dims, ty.size(), options.max_voxels)?;
    let nbytes = count * ty.size();

    let encoding = required("encoding")?.to_ascii_lowercase();
    let endian = match field("endian") {
        Some("little") => Endian::Little,
        Some("big") => Endian::Big,
        None if ty.size() == 1 || matches!(encoding.as_str(), "txt" | "text" | "ascii") => {
            Endian::Little
        }
        None => return Err(invalid(path, "missing 'endian' for multi-byte samples")),
        Some(e) => {
            return Err(invalid(
                path,
                format!("endian '{e}' is neither little nor big"),
            ))
        }
    };
    let parse_i64 = |k: &str| -> Result<i64, IoError> {
        field(k).map_or(Ok(0), |v| {
            v.parse()
                .map_err(|_| invalid(path, format!("'{k}' is not an integer")))
        })
    };
    let line_skip = parse_i64("line skip")?;
    let byte_skip = parse_i64("byte skip")?;
    if line_skip < 0 || byte_skip < -1 {
        return Err(invalid(
            path,
            "negative 'line skip' or 'byte skip' (other than -1)",
        ));
    }

    // Where the data is.
    let data_file = field("data file").or(field("datafile"));
    let (data_path, start): (PathBuf, u64) = match data_file {
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
            (p, 0)
        }
        None if ended => (path.to_path_buf(), consumed),
        None => {
            return Err(IoError::Truncated {
                path: path.into(),
                what: "the header has no blank line ending it and names no data file".into(),
            })
        }
    };
    let dpath = data_path.as_path();
    let mut data = BufReader::new(open(dpath)?);
    data.seek(SeekFrom::Start(start))
        .map_err(|e| os_or_invalid(dpath, e))?;
    for _ in 0..line_skip {
        let mut skip = Vec::new();
        let n = (&mut data)
            .take(MAX_HEADER_BYTES)
            .read_until(b'\n', &mut skip)
            .map_err(|e| os_or_invalid(dpath, e))?;
        if n == 0 {
            return Err(IoError::Truncated {
                path: dpath.into(),
                what: "the file ends within 'line skip'".into(),
            });
        }
    }

    let samples = match encoding.as_str() {
        "raw" => {
            let pos = data
                .stream_position()
                .map_err(|e| os_or_invalid(dpath, e))?;
            let len = data
                .get_ref()
                .metadata()
                .map_err(|e| os_or_invalid(dpath, e))?
                .len();
            let available = len.saturating_sub(pos);
            let skip = if byte_skip == -1 {
                available.checked_sub(nbytes as u64).ok_or_else(|| IoError::SizeMismatch {
                    path: dpath.into(),
                    what: format!("'byte skip: -1' but the file holds {available} bytes of the {nbytes} announced"),
                })?
            } else {
                byte_skip as u64
            };
            if available < skip + nbytes as u64 {
                return Err(IoError::SizeMismatch {
                    path: dpath.into(),
                    what: format!(
                        "the header announces {nbytes} bytes of {ty} data ({}x{}x{}) after {skip} skipped, \
                         but {available} bytes follow the header",
                        dims[0], dims[1], dims[2]
                    ),
                });
            }
            data.seek(SeekFrom::Current(skip as i64))
                .map_err(|e| os_or_invalid(dpath, e))?;
            let bytes = read_exact_growing(dpath, &mut data, nbytes, "voxel data")?;
            decode_samples(&bytes, ty, endian)
        }
        "gzip" | "gz" => {
            if byte_skip == -1 {
                return Err(invalid(
                    path,
                    "'byte skip: -1' is only allowed with raw encoding",
                ));
            }
            let mut gz = BufReader::new(flate2::read::MultiGzDecoder::new(data));
            let skipped =
                std::io::copy(&mut (&mut gz).take(byte_skip as u64), &mut std::io::sink())
                    .map_err(|e| os_or_invalid(dpath, e))?;
            if skipped < byte_skip as u64 {
                return Err(IoError::Truncated {
                    path: dpath.into(),
                    what: "data ends within 'byte skip'".into(),
                });
            }
            let bytes = read_exact_growing(dpath, &mut gz, nbytes, "gzip-compressed voxel data")?;
            decode_samples(&bytes, ty, endian)
        }
        "txt" | "text" | "ascii" => {
            let mut text = String::new();
            // At most ~32 characters per number.
            data.take(32 * count as u64 + 1024)
                .read_to_string(&mut text)
                .map_err(|e| os_or_invalid(dpath, e))?;
            parse_text(dpath, &text, ty, count)?
        }
        e => {
            return Err(IoError::Unsupported {
                path: path.into(),
                what: format!("NRRD encoding '{e}'; supported: raw, gzip, text"),
            })
        }
    };

    // Geometry. Every axis must be spatial: a color or vector axis (kinds RGB-color,
    // vector, list, ...) is not a voxel dimension.
    if let Some(kinds) = field("kinds") {
        for (i, k) in kinds.split_whitespace().take(dimension).enumerate() {
            if !matches!(
                k.to_ascii_lowercase().as_str(),
                "domain" | "space" | "none" | "???"
            ) {
                return Err(IoError::Unsupported {
                    path: path.into(),
                    what: format!(
                        "axis {i} is a non-spatial axis (kind '{k}'); only scalar volumes \
                         with spatial axes are read"
                    ),
                });
            }
        }
    }
    let mut notes = Vec::new();
    let space = field("space").map(str::to_ascii_lowercase);
    let flip = match space.as_deref() {
        Some("right-anterior-superior" | "ras") | None => [1.0, 1.0, 1.0],
        Some("left-posterior-superior" | "lps") => [-1.0, -1.0, 1.0],
        Some("left-anterior-superior" | "las") => [-1.0, 1.0, 1.0],
        Some(s) => {
            notes.push(format!("space '{s}' taken as RAS"));
            [1.0, 1.0, 1.0]
        }
    };
    let affine = if let Some(dirs) = field("space directions") {
        let items = vectors(dirs);
        if items.len() != dimension {
            return Err(invalid(
                path,
                format!("{} space directions for dimension {dimension}", items.len()),
            ));
        }
        let mut cols = Vec::new();
        for item in items {
            cols.push(vector(path, item)?.ok_or_else(|| IoError::Unsupported {
                path: path.into(),
                what: "a non-spatial axis ('none' direction)".into(),
            })?);
        }
        if dimension == 2 {
            // The third axis of a single slice: unit length along the plane's normal.
            let (a, b) = (cols[0], cols[1]);
            let n = [
                a[1] * b[2] - a[2] * b[1],
                a[2] * b[0] - a[0] * b[2],
                a[0] * b[1] - a[1] * b[0],
            ];
            let l = (n[0] * n[0] + n[1] * n[1] + n[2] * n[2]).sqrt();
            cols.push(if l > 0.0 { n.map(|x| x / l) } else { n });
        }
        let origin = match field("space origin") {
            Some(o) => vector(path, o)?.unwrap_or([0.0; 3]),
            None => [0.0; 3],
        };
        let mut a = [[0.0; 4]; 4];
        for r in 0..3 {
            for c in 0..3 {
                a[r][c] = flip[r] * cols[c][r];
            }
            a[r][3] = flip[r] * origin[r];
        }
        a[3][3] = 1.0;
        notes.push(format!(
            "space {}",
            space.as_deref().unwrap_or("unspecified (taken as RAS)")
        ));
        a
    } else {
        let mut spacing = [1.0; 3];
        match field("spacings") {
            Some(s) => {
                for (i, t) in s.split_whitespace().take(3).enumerate() {
                    spacing[i] = t.parse::<f64>().unwrap_or(f64::NAN);
                }
                check_spacing(path, spacing)?;
            }
            None => notes.push("no spacings or space directions: 1 mm voxels".into()),
        }
        // A space origin is a world position even without space directions.
        let origin = match field("space origin") {
            Some(o) => vector(path, o)?.unwrap_or([0.0; 3]),
            None => [0.0; 3],
        };
        diagonal_affine(spacing, std::array::from_fn(|r| flip[r] * origin[r]))
    };
    let spacing = check_affine(path, &affine)?;
    Ok(VolumeFile {
        volume: Volume {
            dims,
            spacing,
            affine,
            samples,
            slope: 1.0,
            intercept: 0.0,
            units: None,
        },
        format: Format::Nrrd,
        notes,
        inflate: None,
    })
}

fn truncate(s: &str) -> String {
    s.chars().take(40).collect()
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

fn type_name(ty: ScalarType) -> &'static str {
    match ty {
        ScalarType::U8 => "uint8",
        ScalarType::I8 => "int8",
        ScalarType::U16 => "uint16",
        ScalarType::I16 => "int16",
        ScalarType::U32 => "uint32",
        ScalarType::I32 => "int32",
        ScalarType::F32 => "float",
        ScalarType::F64 => "double",
    }
}

fn header(volume: &Volume, encoding: Encoding, endian: Endian, data_file: Option<&str>) -> String {
    let a = &volume.affine;
    let col = |c: usize| format!("({},{},{})", a[0][c], a[1][c], a[2][c]);
    let mut h =
        format!(
        "NRRD0004\n# written by glint\ntype: {}\ndimension: 3\nspace: right-anterior-superior\n\
         sizes: {} {} {}\nspace directions: {} {} {}\nkinds: domain domain domain\n\
         endian: {}\nencoding: {}\nspace origin: ({},{},{})\n",
        type_name(ScalarType::of(&volume.samples)),
        volume.dims[0],
        volume.dims[1],
        volume.dims[2],
        col(0),
        col(1),
        col(2),
        if endian == Endian::Big { "big" } else { "little" },
        if encoding == Encoding::Gzip { "gzip" } else { "raw" },
        a[0][3],
        a[1][3],
        a[2][3],
    );
    if let Some(f) = data_file {
        h += &format!("data file: {f}\n");
    }
    h
}

fn payload(
    volume: &Volume,
    encoding: Encoding,
    endian: Endian,
    w: &mut dyn Write,
) -> std::io::Result<()> {
    let data = encode_samples(&volume.samples, endian);
    match encoding {
        Encoding::Raw => w.write_all(&data),
        Encoding::Gzip => {
            let mut e = flate2::write::GzEncoder::new(w, flate2::Compression::default());
            e.write_all(&data)?;
            e.finish().map(|_| ())
        }
    }
}

/// Writes an attached-header NRRD (`.nrrd`) in RAS space. Slope and intercept are not
/// part of NRRD and are dropped.
pub fn write(
    path: &Path,
    volume: &Volume,
    encoding: Encoding,
    endian: Endian,
) -> Result<(), IoError> {
    let h = header(volume, encoding, endian, None);
    write_atomic(path, |w| {
        w.write_all(h.as_bytes())?;
        w.write_all(b"\n")?;
        payload(volume, encoding, endian, w)
    })
}

/// Writes a detached header `path` (`.nhdr`) and its data file `path` with the extension
/// `.raw` or `.raw.gz`, side by side.
pub fn write_detached(
    path: &Path,
    volume: &Volume,
    encoding: Encoding,
    endian: Endian,
) -> Result<PathBuf, IoError> {
    let ext = if encoding == Encoding::Gzip {
        "raw.gz"
    } else {
        "raw"
    };
    let data_path = path.with_extension(ext);
    let name = data_path
        .file_name()
        .map(|n| n.to_string_lossy().into_owned())
        .unwrap_or_default();
    write_atomic(&data_path, |w| payload(volume, encoding, endian, w))?;
    let h = header(volume, encoding, endian, Some(&name));
    write_atomic(path, |w| w.write_all(h.as_bytes()))?;
    Ok(data_path)
}

#[cfg(test)]
mod tests {
    use super::vectors;

    #[test]
    fn splits_space_directions() {
        assert_eq!(
            vectors("(1,0,0) (0, 1,0)  none (0,0,1.5)"),
            vec!["(1,0,0)", "(0, 1,0)", "none", "(0,0,1.5)"]
        );
    }
}
