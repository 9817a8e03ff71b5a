//! The NIfTI-1, NIfTI-2 and ANALYZE 7.5 headers: field offsets, datatype codes, the
//! dimensions, and the affine by the NIfTI rules.

use std::path::Path;

use crate::common::{Endian, ScalarType};
use crate::IoError;

/// NIfTI datatype code of a scalar type (nifti1.h `DT_*`).
pub(super) fn code_of(ty: ScalarType) -> i16 {
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

pub(super) fn type_of(code: i16) -> Option<ScalarType> {
    ScalarType::ALL
        .iter()
        .copied()
        .find(|&t| code_of(t) == code)
}

/// Names of the NIfTI datatypes this reader refuses, for the error message.
pub(super) fn unsupported_type_name(code: i16) -> &'static str {
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
pub(super) enum Version {
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
pub(super) struct Header {
    pub(super) version: Version,
    pub(super) endian: Endian,
    pub(super) dim: [i64; 8],
    pub(super) datatype: i16,
    pub(super) pixdim: [f64; 8],
    pub(super) vox_offset: f64,
    pub(super) slope: f64,
    pub(super) intercept: f64,
    pub(super) xyzt_units: u8,
    pub(super) qform_code: i32,
    pub(super) sform_code: i32,
    /// quatern_b, c, d, qoffset_x, y, z.
    pub(super) quatern: [f64; 6],
    pub(super) srow: [[f64; 4]; 3],
}

/// Parses a NIfTI-1 or ANALYZE header (the 348 bytes of `head`), or a NIfTI-2 one
/// (`head` and the 192 bytes `more` reads). `pair`: the header of a `.hdr`/`.img` pair.
pub(super) fn parse_header(
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

/// The first three dimensions and the product of the rest, checked.
pub(super) fn dims_of(path: &Path, h: &Header) -> Result<([usize; 3], u64), IoError> {
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
pub(super) fn affine_of(path: &Path, h: &Header) -> Result<([[f64; 4]; 4], &'static str), IoError> {
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
