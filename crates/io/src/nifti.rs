//! NIfTI-1 single-file volumes (`.nii`, `.nii.gz`).
//!
//! The 348-byte header is parsed here rather than with the `nifti` crate: that crate
//! reads the whole data block into memory sized by the header before any check we could
//! apply (no voxel limit, no growth-with-data), and pulls in nalgebra and ndarray for
//! what is a fixed table of offsets. The layout follows nifti1.h
//! (<https://nifti.nimh.nih.gov/pub/dist/src/niftilib/nifti1.h>), and the qform
//! quaternion formula follows nifti1_io.c `nifti_quatern_to_mat44`.

use std::io::{BufReader, Read, Write};
use std::path::Path;

use flate2::read::MultiGzDecoder;

use crate::common::{
    check_affine, checked_voxels, decode_samples, encode_samples, is_gzip, open, os_or_invalid,
    read_exact_growing, spacing_of, write_atomic, Endian, ScalarType,
};
use crate::{IoError, ReadOptions, Volume, VolumeFile};

const HEADER_SIZE: usize = 348;
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

/// Reads the header fields at fixed offsets in the file's byte order.
struct Header<'a> {
    b: &'a [u8],
    endian: Endian,
}

impl Header<'_> {
    fn i16(&self, at: usize) -> i16 {
        let a = [self.b[at], self.b[at + 1]];
        match self.endian {
            Endian::Little => i16::from_le_bytes(a),
            Endian::Big => i16::from_be_bytes(a),
        }
    }
    fn f32(&self, at: usize) -> f64 {
        let a = [self.b[at], self.b[at + 1], self.b[at + 2], self.b[at + 3]];
        f64::from(match self.endian {
            Endian::Little => f32::from_le_bytes(a),
            Endian::Big => f32::from_be_bytes(a),
        })
    }
}

/// Reads a NIfTI-1 volume (gzip-compressed or not, either byte order). 4D files yield
/// their first volume, with a note.
pub fn read(path: &Path, options: &ReadOptions) -> Result<VolumeFile, IoError> {
    let gz = is_gzip(path)?;
    let file = open(path)?;
    let file_len = file.metadata().map(|m| m.len()).ok();
    let mut reader: Box<dyn Read> = if gz {
        Box::new(BufReader::new(MultiGzDecoder::new(BufReader::new(file))))
    } else {
        Box::new(BufReader::new(file))
    };
    let head = read_exact_growing(path, &mut reader, HEADER_SIZE, "NIfTI header")?;

    let endian = match (
        i32::from_le_bytes(head[0..4].try_into().expect("4 bytes")),
        i32::from_be_bytes(head[0..4].try_into().expect("4 bytes")),
    ) {
        (348, _) => Endian::Little,
        (_, 348) => Endian::Big,
        (540, _) | (_, 540) => {
            return Err(IoError::Unsupported {
                path: path.into(),
                what: "NIfTI-2 (540-byte header)".into(),
            })
        }
        (n, _) => {
            return Err(IoError::BadMagic {
                path: path.into(),
                format: "NIfTI-1",
                what: format!("header size field is {n}, expected 348"),
            })
        }
    };
    let magic = &head[344..348];
    if magic == b"ni1\0" {
        return Err(IoError::Unsupported {
            path: path.into(),
            what: "two-file NIfTI (.hdr/.img); convert to a single .nii".into(),
        });
    }
    if magic != b"n+1\0" {
        return Err(IoError::BadMagic {
            path: path.into(),
            format: "NIfTI-1",
            what: format!(
                "magic is {:?}, expected \"n+1\\0\"",
                String::from_utf8_lossy(magic)
            ),
        });
    }
    let h = Header { b: &head, endian };

    // Dimensions.
    let ndim = h.i16(40);
    if !(1..=7).contains(&ndim) {
        return Err(IoError::Invalid {
            path: path.into(),
            what: format!("dim[0] = {ndim}, expected 1..7"),
        });
    }
    let mut dim = [1usize; 8];
    for (i, d) in dim.iter_mut().enumerate().take(ndim as usize + 1).skip(1) {
        let v = h.i16(40 + 2 * i);
        if v < 1 {
            return Err(IoError::Invalid {
                path: path.into(),
                what: format!("dim[{i}] = {v}, expected at least 1"),
            });
        }
        *d = v as usize;
    }
    let dims = [dim[1], dim[2], dim[3]];
    let extra: u64 = dim[4..].iter().map(|&d| d as u64).product();

    let code = h.i16(70);
    let ty = type_of(code).ok_or_else(|| IoError::Unsupported {
        path: path.into(),
        what: format!(
            "datatype {code} ({}); supported: uint8, int8, uint16, int16, uint32, int32, \
             float32, float64",
            unsupported_type_name(code)
        ),
    })?;
    let count = checked_voxels(path, dims, ty.size(), options.max_voxels)?;
    let nbytes = count * ty.size();

    let vox_offset = h.f32(108);
    if !vox_offset.is_finite() || vox_offset < HEADER_SIZE as f64 || vox_offset > 1e12 {
        return Err(IoError::Invalid {
            path: path.into(),
            what: format!("vox_offset {vox_offset} is not a byte offset past the header"),
        });
    }
    let offset = vox_offset as u64;

    // For an uncompressed file the size is known up front.
    if let (false, Some(len)) = (gz, file_len) {
        if len < offset + nbytes as u64 {
            return Err(IoError::SizeMismatch {
                path: path.into(),
                what: format!(
                    "the header announces {nbytes} bytes of {ty} data at offset {offset} \
                     ({}x{}x{}), but the file has {len} bytes",
                    dims[0], dims[1], dims[2]
                ),
            });
        }
    }

    // Skip extensions up to the data.
    let skip = offset - HEADER_SIZE as u64;
    let skipped = std::io::copy(&mut (&mut reader).take(skip), &mut std::io::sink())
        .map_err(|e| os_or_invalid(path, e))?;
    if skipped < skip {
        return Err(IoError::Truncated {
            path: path.into(),
            what: format!("the file ends before the data offset {offset}"),
        });
    }
    let bytes = read_exact_growing(path, &mut reader, nbytes, "voxel data")?;
    let samples = decode_samples(&bytes, ty, endian);
    drop(bytes);

    let mut notes = Vec::new();
    if extra > 1 {
        notes.push(format!("4D+ image: read the first of {extra} volumes"));
    }
    let (affine, source) = affine_of(path, &h)?;
    notes.push(format!("affine from {source}"));
    let spacing = check_affine(path, &affine)?;

    let (mut slope, mut intercept) = (h.f32(112), h.f32(116));
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
    })
}

/// The voxel-to-RAS affine by the NIfTI rules: sform if sform_code > 0, else qform if
/// qform_code > 0, else the pixdim diagonal ("method 1", ANALYZE 7.5 compatibility).
fn affine_of(path: &Path, h: &Header) -> Result<([[f64; 4]; 4], &'static str), IoError> {
    // Spatial units: xyzt_units & 7 is 1 metre, 2 mm, 3 micron (0 unknown, taken as mm).
    let to_mm = match h.b[123] & 7 {
        1 => 1000.0,
        3 => 0.001,
        _ => 1.0,
    };
    let (sform_code, qform_code) = (h.i16(254), h.i16(252));
    let pixdim: [f64; 4] = std::array::from_fn(|i| h.f32(76 + 4 * i));
    let mut a = [[0.0; 4]; 4];
    a[3][3] = 1.0;
    let source;
    if sform_code > 0 {
        for (r, row) in a.iter_mut().take(3).enumerate() {
            for (c, x) in row.iter_mut().enumerate() {
                *x = h.f32(280 + 16 * r + 4 * c);
            }
        }
        source = "sform";
    } else {
        let d = [pixdim[1], pixdim[2], pixdim[3]];
        if d.iter().any(|x| !x.is_finite() || *x <= 0.0) {
            return Err(IoError::Geometry {
                path: path.into(),
                what: format!("pixdim[1..4] = {d:?} must be finite and positive"),
            });
        }
        if qform_code > 0 {
            let (b, c, dq) = (h.f32(256), h.f32(260), h.f32(264));
            let (mut a_, mut b, mut c, mut dq) = (1.0 - (b * b + c * c + dq * dq), b, c, dq);
            if a_ < 1e-7 {
                // nifti1_io.c: a 180-degree rotation; renormalise (b, c, d).
                let n = 1.0 / (b * b + c * c + dq * dq).sqrt();
                b *= n;
                c *= n;
                dq *= n;
                a_ = 0.0;
            } else {
                a_ = a_.sqrt();
            }
            let r = [
                [
                    a_ * a_ + b * b - c * c - dq * dq,
                    2.0 * (b * c - a_ * dq),
                    2.0 * (b * dq + a_ * c),
                ],
                [
                    2.0 * (b * c + a_ * dq),
                    a_ * a_ + c * c - b * b - dq * dq,
                    2.0 * (c * dq - a_ * b),
                ],
                [
                    2.0 * (b * dq - a_ * c),
                    2.0 * (c * dq + a_ * b),
                    a_ * a_ + dq * dq - c * c - b * b,
                ],
            ];
            let qfac = if pixdim[0] < 0.0 { -1.0 } else { 1.0 };
            let scale = [d[0], d[1], qfac * d[2]];
            for (row, rrow) in a.iter_mut().zip(r) {
                for col in 0..3 {
                    row[col] = rrow[col] * scale[col];
                }
            }
            a[0][3] = h.f32(268);
            a[1][3] = h.f32(272);
            a[2][3] = h.f32(276);
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
    let spacing = spacing_of(&volume.affine);
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
