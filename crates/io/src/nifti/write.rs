//! Writing single-file NIfTI-1 and NIfTI-2 volumes.

use std::io::Write;
use std::path::Path;

use super::header::code_of;
use super::HEADER2_SIZE;
use crate::common::{encode_samples, write_atomic, Endian, ScalarType};
use crate::{IoError, Volume};

/// Header plus the 4-byte extension flag: where a single-file image's data starts.
const DATA_OFFSET: usize = 352;

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
