//! NRRD volumes (`.nrrd` attached, `.nhdr` detached header), 3D Slicer's native format.
//!
//! The header is parsed here: the crates.io `nrrd` crates are unmaintained stubs or
//! lack detached headers, gzip and space directions, and the header is a short list of
//! `key: value` lines. Follows the NRRD0005 spec at
//! <https://teem.sourceforge.net/nrrd/format.html>. Supported: dimension 2 or 3, the
//! eight sample types, `raw`, `gzip` and `text` encodings, `byte skip` (including -1 for
//! raw data), `line skip`, `space` (RAS/LPS/LAS, converted to RAS), `space directions`,
//! `space origin`, or `spacings` without a space. The time spent inflating gzip data is
//! reported as [`VolumeFile::inflate`](crate::VolumeFile::inflate).

use std::collections::HashMap;
use std::fs::File;
use std::io::{BufRead, BufReader, Read, Seek, SeekFrom, Write};
use std::path::{Path, PathBuf};

use flate2::read::MultiGzDecoder;

use crate::clock::Clock;

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
///
/// The steps, in the order their errors are reported: the header's fields, the sample
/// layout they announce (checked against `options.max_voxels` before anything is
/// allocated), the data file, the samples, then the geometry.
pub fn read(path: &Path, options: &ReadOptions) -> Result<VolumeFile, IoError> {
    let fields = read_fields(path)?;
    let layout = Layout::parse(path, &fields, options)?;
    let (dpath, data) = open_data(path, &fields, layout.line_skip)?;
    let clock = Clock::default();
    let samples = decode(path, &dpath, data, &layout, &clock)?;
    let (affine, notes) = geometry(path, &fields, layout.dimension)?;
    let spacing = check_affine(path, &affine)?;
    Ok(VolumeFile {
        volume: Volume {
            dims: layout.dims,
            spacing,
            affine,
            samples,
            slope: 1.0,
            intercept: 0.0,
            units: None,
        },
        format: Format::Nrrd,
        notes,
        inflate: clock.spent(),
    })
}

/// The `field: value` lines of a header, and where the header ended.
struct Fields {
    /// Values by field name, names lower-cased; the last of a repeated field wins.
    map: HashMap<String, String>,
    /// Whether a blank line ended the header (attached data may follow it).
    ended: bool,
    /// Bytes read from the header file, the blank line included: where attached data
    /// starts.
    len: u64,
}

impl Fields {
    fn get(&self, key: &str) -> Option<&str> {
        self.map.get(key).map(String::as_str)
    }

    fn required(&self, path: &Path, key: &str) -> Result<&str, IoError> {
        self.get(key)
            .ok_or_else(|| invalid(path, format!("missing required field '{key}'")))
    }
}

/// Reads the magic line and the header's fields, up to the blank line that ends it (or
/// the end of the file, for a detached header); at most [`MAX_HEADER_BYTES`].
fn read_fields(path: &Path) -> Result<Fields, IoError> {
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
enum Codec {
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
enum ByteSkip {
    /// Bytes to skip before the samples.
    Bytes(u64),
    /// `-1`: the samples are the last bytes of the (raw) data file.
    ToEnd,
}

/// The samples a header announces and how they are stored, validated.
struct Layout {
    ty: ScalarType,
    /// 2 or 3.
    dimension: usize,
    /// Sizes, 1 for the third of a 2D image.
    dims: [usize; 3],
    /// Voxels, within the reader's limit.
    count: usize,
    /// Bytes of the samples: `count` times the sample size, known not to overflow.
    nbytes: usize,
    codec: Codec,
    endian: Endian,
    line_skip: u64,
    byte_skip: ByteSkip,
}

impl Layout {
    /// Validates the fields that say what the samples are and where they start.
    fn parse(path: &Path, fields: &Fields, options: &ReadOptions) -> Result<Layout, IoError> {
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

/// Opens the file holding the samples (the header's own file after its blank line, or
/// the detached `data file`) and skips its first `line_skip` lines.
fn open_data(
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
fn decode(
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
    let bytes = read_exact_growing(dpath, &mut data, nbytes, "voxel data")?;
    Ok(decode_samples(&bytes, layout.ty, layout.endian))
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
    let bytes = read_exact_growing(dpath, &mut gz, layout.nbytes, "gzip-compressed voxel data")?;
    Ok(decode_samples(&bytes, layout.ty, layout.endian))
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

/// The voxel-to-RAS affine and notes on where it came from: `space directions` and
/// `space origin`, or `spacings` (1 mm without them), converted from the header's
/// `space` to RAS.
fn geometry(
    path: &Path,
    fields: &Fields,
    dimension: usize,
) -> Result<([[f64; 4]; 4], Vec<String>), IoError> {
    check_kinds(path, fields, dimension)?;
    let mut notes = Vec::new();
    let space = fields.get("space").map(str::to_ascii_lowercase);
    let flip = match space.as_deref() {
        Some("right-anterior-superior" | "ras") | None => [1.0, 1.0, 1.0],
        Some("left-posterior-superior" | "lps") => [-1.0, -1.0, 1.0],
        Some("left-anterior-superior" | "las") => [-1.0, 1.0, 1.0],
        Some(s) => {
            notes.push(format!("space '{s}' taken as RAS"));
            [1.0, 1.0, 1.0]
        }
    };
    let affine = if let Some(dirs) = fields.get("space directions") {
        let cols = direction_columns(path, dirs, dimension)?;
        let origin = space_origin(path, fields)?;
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
        let spacing = spacings(path, fields, &mut notes)?;
        // A space origin is a world position even without space directions.
        let origin = space_origin(path, fields)?;
        diagonal_affine(spacing, std::array::from_fn(|r| flip[r] * origin[r]))
    };
    Ok((affine, notes))
}

/// Every axis must be spatial: a color or vector axis (kinds RGB-color, vector, list,
/// ...) is not a voxel dimension.
fn check_kinds(path: &Path, fields: &Fields, dimension: usize) -> Result<(), IoError> {
    let Some(kinds) = fields.get("kinds") else {
        return Ok(());
    };
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
    Ok(())
}

/// The `space directions`, one per axis, in the header's space; a 2D image gets a
/// unit third axis along its plane's normal.
fn direction_columns(path: &Path, dirs: &str, dimension: usize) -> Result<[[f64; 3]; 3], IoError> {
    let items = vectors(dirs);
    if items.len() != dimension {
        return Err(invalid(
            path,
            format!("{} space directions for dimension {dimension}", items.len()),
        ));
    }
    let mut cols = [[0.0; 3]; 3];
    for (col, item) in cols.iter_mut().zip(items) {
        *col = vector(path, item)?.ok_or_else(|| IoError::Unsupported {
            path: path.into(),
            what: "a non-spatial axis ('none' direction)".into(),
        })?;
    }
    if dimension == 2 {
        cols[2] = unit_normal(cols[0], cols[1]);
    }
    Ok(cols)
}

/// `a` x `b` scaled to unit length (left at zero when `a` and `b` are parallel).
fn unit_normal(a: [f64; 3], b: [f64; 3]) -> [f64; 3] {
    let n = [
        a[1] * b[2] - a[2] * b[1],
        a[2] * b[0] - a[0] * b[2],
        a[0] * b[1] - a[1] * b[0],
    ];
    let l = (n[0] * n[0] + n[1] * n[1] + n[2] * n[2]).sqrt();
    if l > 0.0 {
        n.map(|x| x / l)
    } else {
        n
    }
}

/// The `space origin`, zero when absent or `none`.
fn space_origin(path: &Path, fields: &Fields) -> Result<[f64; 3], IoError> {
    match fields.get("space origin") {
        Some(o) => Ok(vector(path, o)?.unwrap_or([0.0; 3])),
        None => Ok([0.0; 3]),
    }
}

/// The voxel size from `spacings` (checked finite and positive), 1 mm when absent (with
/// a note).
fn spacings(path: &Path, fields: &Fields, notes: &mut Vec<String>) -> Result<[f64; 3], IoError> {
    let mut spacing = [1.0; 3];
    match fields.get("spacings") {
        Some(s) => {
            for (i, t) in s.split_whitespace().take(3).enumerate() {
                spacing[i] = t.parse::<f64>().unwrap_or(f64::NAN);
            }
            check_spacing(path, spacing)?;
        }
        None => notes.push("no spacings or space directions: 1 mm voxels".into()),
    }
    Ok(spacing)
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
