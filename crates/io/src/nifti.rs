//! NIfTI-1 and NIfTI-2 volumes (`.nii`, `.nii.gz`), and header/image pairs (`.hdr` +
//! `.img`: NIfTI-1, NIfTI-2 or ANALYZE 7.5).
//!
//! The 348-byte header is parsed here rather than with the `nifti` crate: that crate
//! reads the whole data block into memory sized by the header before any check we could
//! apply (no voxel limit, no growth-with-data), and pulls in nalgebra and ndarray for
//! what is a fixed table of offsets. The layout follows nifti1.h
//! (<https://nifti.nimh.nih.gov/pub/dist/src/niftilib/nifti1.h>), and the qform
//! quaternion formula follows nifti1_io.c `nifti_quatern_to_mat44`. NIfTI-2 follows
//! nifti2.h (<https://nifti.nimh.nih.gov/pub/dist/doc/nifti2.h>): the same fields as
//! 64-bit integers and doubles in a 540-byte header.

use std::io::{BufReader, Read, Write};
use std::path::{Path, PathBuf};

use flate2::read::MultiGzDecoder;

use crate::clock::Clock;

use crate::common::{
    check_affine, checked_voxels, decode_samples, encode_samples, is_gzip, open, os_or_invalid,
    read_exact_growing, write_atomic, Endian, ScalarType,
};
use crate::{IoError, ReadOptions, Volume, VolumeFile};

const HEADER_SIZE: usize = 348;
/// The NIfTI-2 header (nifti2.h); its single-file data starts 4 bytes later.
const HEADER2_SIZE: usize = 540;
/// Header plus the 4-byte extension flag: where a single-file image's data starts.
const DATA_OFFSET: usize = 352;

/// NIfTI datatype code of a scalar type (nifti1.h `DT_*`).
fn code_of(ty: ScalarType) -> i16 {
    match ty {
        ScalarType::U8 => 2,
        ScalarType::I16 => 4,
        ScalarType::I32 => 8,
        ScalarType::F32 => 16,
        ScalarType::F64 => 64,
        ScalarType::I8 => 256,
        ScalarType::U16 => 512,
        ScalarType::U32 => 768,
    }
}

fn type_of(code: i16) -> Option<ScalarType> {
    ScalarType::ALL.into_iter().find(|&t| code_of(t) == code)
}

/// Names of the NIfTI datatypes this reader refuses, for the error message.
fn unsupported_type_name(code: i16) -> &'static str {
    match code {
        1 => "binary",
        32 => "complex64",
        128 => "rgb24",
        1024 => "int64",
        1280 => "uint64",
        1536 => "float128",
        1792 => "complex128",
        2048 => "complex256",
        2304 => "rgba32",
        _ => "unknown",
    }
}

/// Which header a file has.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum Version {
    /// NIfTI-1, 348 bytes (nifti1.h).
    One,
    /// NIfTI-2, 540 bytes, 64-bit dims and doubles (nifti2.h).
    Two,
    /// ANALYZE 7.5: NIfTI-1's layout without the magic, sform or qform.
    Analyze,
}

/// Reads header fields at fixed offsets in the file's byte order.
struct Fields<'a> {
    b: &'a [u8],
    endian: Endian,
}

impl Fields<'_> {
    fn bytes<const N: usize>(&self, at: usize) -> [u8; N] {
        let mut a: [u8; N] = self.b[at..at + N].try_into().expect("N bytes");
        if self.endian == Endian::Big {
            a.reverse();
        }
        a
    }
    fn i16(&self, at: usize) -> i16 {
        i16::from_le_bytes(self.bytes(at))
    }
    fn i32(&self, at: usize) -> i32 {
        i32::from_le_bytes(self.bytes(at))
    }
    fn i64(&self, at: usize) -> i64 {
        i64::from_le_bytes(self.bytes(at))
    }
    fn f32(&self, at: usize) -> f64 {
        f64::from(f32::from_le_bytes(self.bytes(at)))
    }
    fn f64(&self, at: usize) -> f64 {
        f64::from_le_bytes(self.bytes(at))
    }
}

/// The fields glint uses, whatever the header version.
struct Header {
    version: Version,
    endian: Endian,
    dim: [i64; 8],
    datatype: i16,
    pixdim: [f64; 8],
    vox_offset: f64,
    slope: f64,
    intercept: f64,
    xyzt_units: u8,
    qform_code: i32,
    sform_code: i32,
    /// quatern_b, c, d, qoffset_x, y, z.
    quatern: [f64; 6],
    srow: [[f64; 4]; 3],
}

/// Parses a NIfTI-1 or ANALYZE header (the 348 bytes of `head`), or a NIfTI-2 one
/// (`head` and the 192 bytes `more` reads). `pair`: the header of a `.hdr`/`.img` pair.
fn parse_header(
    path: &Path,
    head: &[u8],
    more: impl FnOnce() -> Result<Vec<u8>, IoError>,
    pair: bool,
) -> Result<Header, IoError> {
    let le = i32::from_le_bytes(head[0..4].try_into().expect("4 bytes"));
    let be = i32::from_be_bytes(head[0..4].try_into().expect("4 bytes"));
    let endian = match (le, be) {
        (348 | 540, _) => Endian::Little,
        (_, 348 | 540) => Endian::Big,
        (n, _) => {
            return Err(IoError::BadMagic {
                path: path.into(),
                format: "NIfTI",
                what: format!("header size field is {n}, expected 348 (NIfTI-1) or 540 (NIfTI-2)"),
            })
        }
    };
    if le == 540 || be == 540 {
        let mut full = head.to_vec();
        full.extend(more()?);
        return parse_nifti2(path, &full, endian, pair);
    }
    let f = Fields { b: head, endian };
    let magic = &head[344..348];
    let version = match (magic, pair) {
        (b"n+1\0", false) | (b"ni1\0", true) => Version::One,
        (b"n+1\0", true) | (b"ni1\0", false) => {
            return Err(IoError::Invalid {
                path: path.into(),
                what: format!(
                    "magic {:?} is for a {} file",
                    String::from_utf8_lossy(&magic[..3]),
                    if pair {
                        "single .nii"
                    } else {
                        "header/image pair (.hdr + .img)"
                    }
                ),
            })
        }
        (_, true) => Version::Analyze,
        (_, false) => {
            return Err(IoError::BadMagic {
                path: path.into(),
                format: "NIfTI-1",
                what: format!(
                    "magic is {:?}, expected \"n+1\\0\"",
                    String::from_utf8_lossy(magic)
                ),
            })
        }
    };
    let nifti = version == Version::One;
    Ok(Header {
        version,
        endian,
        dim: std::array::from_fn(|i| i64::from(f.i16(40 + 2 * i))),
        datatype: f.i16(70),
        pixdim: std::array::from_fn(|i| f.f32(76 + 4 * i)),
        vox_offset: f.f32(108),
        // ANALYZE 7.5 has no scl_slope (SPM reuses the field as a scale factor, which
        // other readers ignore), no units, no qform or sform.
        slope: if nifti { f.f32(112) } else { 0.0 },
        intercept: if nifti { f.f32(116) } else { 0.0 },
        xyzt_units: if nifti { head[123] } else { 0 },
        qform_code: if nifti { i32::from(f.i16(252)) } else { 0 },
        sform_code: if nifti { i32::from(f.i16(254)) } else { 0 },
        quatern: std::array::from_fn(|i| f.f32(256 + 4 * i)),
        srow: std::array::from_fn(|r| std::array::from_fn(|c| f.f32(280 + 16 * r + 4 * c))),
    })
}

/// NIfTI-2 field offsets from nifti2.h (`nifti_2_header`).
fn parse_nifti2(path: &Path, b: &[u8], endian: Endian, pair: bool) -> Result<Header, IoError> {
    let want: &[u8] = if pair { b"ni2\0" } else { b"n+2\0" };
    if &b[4..8] != want {
        return Err(IoError::BadMagic {
            path: path.into(),
            format: "NIfTI-2",
            what: format!(
                "magic is {:?}, expected {:?}",
                String::from_utf8_lossy(&b[4..8]),
                String::from_utf8_lossy(want)
            ),
        });
    }
    let f = Fields { b, endian };
    Ok(Header {
        version: Version::Two,
        endian,
        dim: std::array::from_fn(|i| f.i64(16 + 8 * i)),
        datatype: f.i16(12),
        pixdim: std::array::from_fn(|i| f.f64(104 + 8 * i)),
        vox_offset: f.i64(168) as f64,
        slope: f.f64(176),
        intercept: f.f64(184),
        xyzt_units: (f.i32(500) & 0xff) as u8,
        qform_code: f.i32(344),
        sform_code: f.i32(348),
        quatern: std::array::from_fn(|i| f.f64(352 + 8 * i)),
        srow: std::array::from_fn(|r| std::array::from_fn(|c| f.f64(400 + 32 * r + 8 * c))),
    })
}

/// Opens a file, gunzipping it when it starts with the gzip signature (the time spent
/// inflating goes to `clock`); the length is known only for an uncompressed file.
fn open_maybe_gz(path: &Path, clock: &Clock) -> Result<(Box<dyn Read>, Option<u64>), IoError> {
    let gz = is_gzip(path)?;
    let file = open(path)?;
    let len = file.metadata().map(|m| m.len()).ok();
    Ok(if gz {
        let inflater = MultiGzDecoder::new(BufReader::new(file));
        (Box::new(BufReader::new(clock.timed(inflater))), None)
    } else {
        (Box::new(BufReader::new(file)), len)
    })
}

/// The image file of a `.hdr` (`.img`, or `.img.gz`, beside it).
fn image_of(path: &Path) -> Result<PathBuf, IoError> {
    let name = path
        .file_name()
        .map(|n| n.to_string_lossy().into_owned())
        .unwrap_or_default();
    let stem_len = name.to_ascii_lowercase().find(".hdr").unwrap_or(name.len());
    let stem = &name[..stem_len];
    [".img", ".IMG", ".img.gz", ".IMG.GZ"]
        .iter()
        .map(|ext| path.with_file_name(format!("{stem}{ext}")))
        .find(|p| p.is_file())
        .ok_or_else(|| IoError::Invalid {
            path: path.into(),
            what: format!("no image file {stem}.img beside the header"),
        })
}

/// Reads a NIfTI-1 or NIfTI-2 volume (`.nii`, `.nii.gz`), or a header/image pair
/// (`.hdr` + `.img`: NIfTI-1 `ni1`, NIfTI-2 `ni2`, or ANALYZE 7.5), gzip-compressed or
/// not, either byte order. 4D files yield their first volume, with a note.
pub fn read(path: &Path, options: &ReadOptions) -> Result<VolumeFile, IoError> {
    let lower = path.to_string_lossy().to_ascii_lowercase();
    let pair = lower.ends_with(".hdr") || lower.ends_with(".hdr.gz");
    let clock = Clock::default();
    let (mut reader, file_len) = open_maybe_gz(path, &clock)?;
    let head = read_exact_growing(path, &mut reader, HEADER_SIZE, "NIfTI header")?;
    let h = parse_header(
        path,
        &head,
        || {
            read_exact_growing(
                path,
                &mut reader,
                HEADER2_SIZE - HEADER_SIZE,
                "NIfTI-2 header",
            )
        },
        pair,
    )?;
    let header_len = if h.version == Version::Two {
        HEADER2_SIZE
    } else {
        HEADER_SIZE
    };
    let (dims, extra) = dims_of(path, &h)?;
    let ty = type_of(h.datatype).ok_or_else(|| IoError::Unsupported {
        path: path.into(),
        what: format!(
            "datatype {} ({}); supported: uint8, int8, uint16, int16, uint32, int32, \
             float32, float64",
            h.datatype,
            unsupported_type_name(h.datatype)
        ),
    })?;
    let count = checked_voxels(path, dims, ty.size(), options.max_voxels)?;
    let nbytes = count * ty.size();
    // A pair's image usually starts at 0; a single file's data after the header.
    let min_offset = if pair { 0.0 } else { header_len as f64 };
    if !h.vox_offset.is_finite() || h.vox_offset < min_offset || h.vox_offset > 1e12 {
        return Err(IoError::Invalid {
            path: path.into(),
            what: format!(
                "vox_offset {} is not a byte offset past the header",
                h.vox_offset
            ),
        });
    }
    let offset = h.vox_offset as u64;
    let (data_path, mut data, data_len, skip) = if pair {
        let img = image_of(path)?;
        let (r, len) = open_maybe_gz(&img, &clock)?;
        (img, r, len, offset)
    } else {
        (
            path.to_path_buf(),
            reader,
            file_len,
            offset - header_len as u64,
        )
    };
    // For an uncompressed file the size is known up front.
    if let Some(len) = data_len {
        if len < offset + nbytes as u64 {
            return Err(IoError::SizeMismatch {
                path: data_path,
                what: format!(
                    "the header announces {nbytes} bytes of {ty} data at offset {offset} \
                     ({}x{}x{}), but the file has {len} bytes",
                    dims[0], dims[1], dims[2]
                ),
            });
        }
    }
    let skipped = std::io::copy(&mut (&mut data).take(skip), &mut std::io::sink())
        .map_err(|e| os_or_invalid(&data_path, e))?;
    if skipped < skip {
        return Err(IoError::Truncated {
            path: data_path,
            what: format!("the file ends before the data offset {offset}"),
        });
    }
    let bytes = read_exact_growing(&data_path, &mut data, nbytes, "voxel data")?;
    let samples = decode_samples(&bytes, ty, h.endian);
    drop(bytes);

    let mut notes = vec![match h.version {
        Version::One if pair => "NIfTI-1 header/image pair".to_string(),
        Version::One => "NIfTI-1".into(),
        Version::Two if pair => "NIfTI-2 header/image pair".into(),
        Version::Two => "NIfTI-2".into(),
        Version::Analyze => "ANALYZE 7.5 (no orientation: axes taken as RAS)".into(),
    }];
    if extra > 1 {
        notes.push(format!("4D+ image: read the first of {extra} volumes"));
    }
    let (affine, source) = affine_of(path, &h)?;
    notes.push(format!("affine from {source}"));
    let spacing = check_affine(path, &affine)?;

    let (mut slope, mut intercept) = (h.slope, h.intercept);
    // nifti1.h: "If the scl_slope field is nonzero, then each voxel value in the dataset
    // should be scaled as y = scl_slope * x + scl_inter".
    if slope == 0.0 || !slope.is_finite() {
        slope = 1.0;
        intercept = 0.0;
    }
    if !intercept.is_finite() {
        intercept = 0.0;
    }
    Ok(VolumeFile {
        volume: Volume {
            dims,
            spacing,
            affine,
            samples,
            slope,
            intercept,
            units: None,
        },
        format: crate::Format::Nifti,
        notes,
        inflate: clock.spent(),
    })
}

/// The first three dimensions and the product of the rest, checked.
fn dims_of(path: &Path, h: &Header) -> Result<([usize; 3], u64), IoError> {
    let ndim = h.dim[0];
    if !(1..=7).contains(&ndim) {
        return Err(IoError::Invalid {
            path: path.into(),
            what: format!("dim[0] = {ndim}, expected 1..7"),
        });
    }
    let mut dim = [1usize; 8];
    for (i, d) in dim.iter_mut().enumerate().take(ndim as usize + 1).skip(1) {
        let v = h.dim[i];
        if v < 1 {
            return Err(IoError::Invalid {
                path: path.into(),
                what: format!("dim[{i}] = {v}, expected at least 1"),
            });
        }
        *d = usize::try_from(v).map_err(|_| IoError::TooLarge {
            path: path.into(),
            what: format!("dim[{i}] = {v} does not fit this machine's address space"),
        })?;
    }
    let extra = dim[4..]
        .iter()
        .fold(1u64, |acc, &d| acc.saturating_mul(d as u64));
    Ok(([dim[1], dim[2], dim[3]], extra))
}

/// The voxel-to-RAS affine by the NIfTI rules: sform if sform_code > 0, else qform if
/// qform_code > 0, else the pixdim diagonal ("method 1", ANALYZE 7.5 compatibility).
fn affine_of(path: &Path, h: &Header) -> Result<([[f64; 4]; 4], &'static str), IoError> {
    // Spatial units: xyzt_units & 7 is 1 metre, 2 mm, 3 micron (0 unknown, taken as mm).
    let to_mm = match h.xyzt_units & 7 {
        1 => 1000.0,
        3 => 0.001,
        _ => 1.0,
    };
    let pixdim = h.pixdim;
    let mut a = [[0.0; 4]; 4];
    a[3][3] = 1.0;
    let source;
    if h.sform_code > 0 {
        a[..3].copy_from_slice(&h.srow);
        source = "sform";
    } else {
        let d = [pixdim[1], pixdim[2], pixdim[3]];
        if d.iter().any(|x| !x.is_finite() || *x <= 0.0) {
            return Err(IoError::Geometry {
                path: path.into(),
                what: format!("pixdim[1..4] = {d:?} must be finite and positive"),
            });
        }
        if h.qform_code > 0 {
            let qfac = if pixdim[0] < 0.0 { -1.0 } else { 1.0 };
            let r = quatern_to_rotation(h.quatern[0], h.quatern[1], h.quatern[2]);
            let scale = [d[0], d[1], qfac * d[2]];
            for (row, rrow) in a.iter_mut().zip(r) {
                for col in 0..3 {
                    row[col] = rrow[col] * scale[col];
                }
            }
            for (row, offset) in a.iter_mut().zip(&h.quatern[3..]) {
                row[3] = *offset;
            }
            source = "qform";
        } else {
            for i in 0..3 {
                a[i][i] = d[i];
            }
            source = "pixdim (no sform or qform)";
        }
    }
    for row in a.iter_mut().take(3) {
        for x in row.iter_mut() {
            *x *= to_mm;
        }
    }
    Ok((a, source))
}

/// The rotation of quaternion (a, b, c, d) with a = sqrt(1 - b² - c² - d²), as in
/// nifti1_io.c `nifti_quatern_to_mat44`.
fn quatern_to_rotation(b: f64, c: f64, d: f64) -> [[f64; 3]; 3] {
    let (mut a, mut b, mut c, mut d) = (1.0 - (b * b + c * c + d * d), b, c, d);
    if a < 1e-7 {
        // nifti1_io.c: a 180-degree rotation; renormalise (b, c, d).
        let n = 1.0 / (b * b + c * c + d * d).sqrt();
        b *= n;
        c *= n;
        d *= n;
        a = 0.0;
    } else {
        a = a.sqrt();
    }
    [
        [
            a * a + b * b - c * c - d * d,
            2.0 * (b * c - a * d),
            2.0 * (b * d + a * c),
        ],
        [
            2.0 * (b * c + a * d),
            a * a + c * c - b * b - d * d,
            2.0 * (c * d - a * b),
        ],
        [
            2.0 * (b * d - a * c),
            2.0 * (c * d + a * b),
            a * a + d * d - c * c - b * b,
        ],
    ]
}

/// Writes a single-file NIfTI-1 volume: the affine as an sform (code 2, aligned), pixdim
/// from the spacing, millimetre units; gzip-compressed if `gzip`. The file appears only
/// when complete.
pub fn write(path: &Path, volume: &Volume, gzip: bool, endian: Endian) -> Result<(), IoError> {
    if volume.dims.iter().any(|&d| d > i16::MAX as usize) {
        return Err(IoError::Unsupported {
            path: path.into(),
            what: format!("dimensions {:?} exceed NIfTI-1's 32767", volume.dims),
        });
    }
    let ty = ScalarType::of(&volume.samples);
    let mut h = vec![0u8; DATA_OFFSET];
    let put_i16 = |h: &mut [u8], at: usize, v: i16| {
        h[at..at + 2].copy_from_slice(&match endian {
            Endian::Little => v.to_le_bytes(),
            Endian::Big => v.to_be_bytes(),
        })
    };
    let put_f32 = |h: &mut [u8], at: usize, v: f64| {
        let v = v as f32;
        h[at..at + 4].copy_from_slice(&match endian {
            Endian::Little => v.to_le_bytes(),
            Endian::Big => v.to_be_bytes(),
        })
    };
    h[0..4].copy_from_slice(&match endian {
        Endian::Little => 348i32.to_le_bytes(),
        Endian::Big => 348i32.to_be_bytes(),
    });
    h[38] = b'r';
    put_i16(&mut h, 40, 3);
    for i in 0..3 {
        put_i16(&mut h, 42 + 2 * i, volume.dims[i] as i16);
    }
    for i in 3..7 {
        put_i16(&mut h, 42 + 2 * i, 1);
    }
    put_i16(&mut h, 70, code_of(ty));
    put_i16(&mut h, 72, (8 * ty.size()) as i16);
    let spacing = crate::affine::spacing(&volume.affine);
    put_f32(&mut h, 76, 1.0);
    for (i, &s) in spacing.iter().enumerate() {
        put_f32(&mut h, 80 + 4 * i, s);
    }
    put_f32(&mut h, 108, DATA_OFFSET as f64);
    put_f32(&mut h, 112, volume.slope);
    put_f32(&mut h, 116, volume.intercept);
    h[123] = 2; // NIFTI_UNITS_MM
    put_i16(&mut h, 254, 2); // NIFTI_XFORM_ALIGNED_ANAT
    for r in 0..3 {
        for c in 0..4 {
            put_f32(&mut h, 280 + 16 * r + 4 * c, volume.affine[r][c]);
        }
    }
    h[344..348].copy_from_slice(b"n+1\0");
    let data = encode_samples(&volume.samples, endian);
    write_atomic(path, |w| {
        if gzip {
            let mut gz = flate2::write::GzEncoder::new(w, flate2::Compression::default());
            gz.write_all(&h)?;
            gz.write_all(&data)?;
            gz.finish()?;
        } else {
            w.write_all(&h)?;
            w.write_all(&data)?;
        }
        Ok(())
    })
}

/// Writes a single-file NIfTI-2 volume (nifti2.h): like [`write()`], with 64-bit
/// dimensions (so sides over 32767 voxels) and double-precision geometry.
pub fn write_nifti2(
    path: &Path,
    volume: &Volume,
    gzip: bool,
    endian: Endian,
) -> Result<(), IoError> {
    let ty = ScalarType::of(&volume.samples);
    let mut h = vec![0u8; HEADER2_SIZE + 4];
    let put = |h: &mut [u8], at: usize, le: &[u8]| {
        let mut b = le.to_vec();
        if endian == Endian::Big {
            b.reverse();
        }
        h[at..at + b.len()].copy_from_slice(&b);
    };
    put(&mut h, 0, &(HEADER2_SIZE as i32).to_le_bytes());
    h[4..12].copy_from_slice(b"n+2\0\r\n\x1a\n");
    put(&mut h, 12, &code_of(ty).to_le_bytes());
    put(&mut h, 14, &((8 * ty.size()) as i16).to_le_bytes());
    let mut dim = [1i64; 8];
    dim[0] = 3;
    for i in 0..3 {
        dim[i + 1] = volume.dims[i] as i64;
    }
    for (i, d) in dim.iter().enumerate() {
        put(&mut h, 16 + 8 * i, &d.to_le_bytes());
    }
    let spacing = crate::affine::spacing(&volume.affine);
    put(&mut h, 104, &1f64.to_le_bytes());
    for (i, s) in spacing.iter().enumerate() {
        put(&mut h, 112 + 8 * i, &s.to_le_bytes());
    }
    put(&mut h, 168, &((HEADER2_SIZE + 4) as i64).to_le_bytes());
    put(&mut h, 176, &volume.slope.to_le_bytes());
    put(&mut h, 184, &volume.intercept.to_le_bytes());
    put(&mut h, 348, &2i32.to_le_bytes()); // sform_code NIFTI_XFORM_ALIGNED_ANAT
    for r in 0..3 {
        for c in 0..4 {
            put(
                &mut h,
                400 + 32 * r + 8 * c,
                &volume.affine[r][c].to_le_bytes(),
            );
        }
    }
    put(&mut h, 500, &2i32.to_le_bytes()); // xyzt_units NIFTI_UNITS_MM
    let data = encode_samples(&volume.samples, endian);
    write_atomic(path, |w| {
        if gzip {
            let mut gz = flate2::write::GzEncoder::new(w, flate2::Compression::default());
            gz.write_all(&h)?;
            gz.write_all(&data)?;
            gz.finish()?;
        } else {
            w.write_all(&h)?;
            w.write_all(&data)?;
        }
        Ok(())
    })
}
