//! Headerless volumes: samples only, described by the caller's [`RawParams`].

use std::io::{BufReader, Seek, SeekFrom};
use std::path::Path;

use crate::common::{
    check_affine, check_spacing, checked_voxels, diagonal_affine, encode_samples, open,
    os_or_invalid, read_decoded, write_atomic, Endian,
};
use crate::{Format, IoError, RawParams, ReadOptions, Volume, VolumeFile};

/// Reads `params.dims` samples of `params.scalar` after `params.offset` bytes. The file
/// must hold exactly that many bytes: a different size usually means wrong parameters.
pub fn read(path: &Path, params: &RawParams, options: &ReadOptions) -> Result<VolumeFile, IoError> {
    check_spacing(path, params.spacing)?;
    // Positive but degenerate sizes (1e-300 mm: a zero voxel volume) are refused too.
    check_affine(path, &diagonal_affine(params.spacing, [0.0; 3]))?;
    let size = params.scalar.size();
    let count = checked_voxels(path, params.dims, size, options.max_voxels)?;
    let nbytes = (count * size) as u64;
    let mut file = open(path)?;
    let len = file.metadata().map_err(|e| os_or_invalid(path, e))?.len();
    let want = params.offset.saturating_add(nbytes);
    if len != want {
        return Err(IoError::SizeMismatch {
            path: path.into(),
            what: format!(
                "{}x{}x{} {} samples after {} bytes need {want} bytes, the file has {len}",
                params.dims[0], params.dims[1], params.dims[2], params.scalar, params.offset
            ),
        });
    }
    file.seek(SeekFrom::Start(params.offset))
        .map_err(|e| os_or_invalid(path, e))?;
    let samples = read_decoded(
        path,
        BufReader::new(file),
        count,
        params.scalar,
        params.endian,
        "samples",
        true,
    )?;
    Ok(VolumeFile {
        volume: Volume {
            dims: params.dims,
            spacing: params.spacing,
            affine: diagonal_affine(params.spacing, [0.0; 3]),
            samples,
            slope: 1.0,
            intercept: 0.0,
            units: None,
            colour: None,
        },
        format: Format::Raw,
        notes: vec!["raw samples: geometry from the caller, origin at voxel 0".into()],
        inflate: None,
    })
}

/// Writes the samples alone, in the given byte order (the geometry is lost).
pub fn write(path: &Path, volume: &Volume, endian: Endian) -> Result<(), IoError> {
    let data = encode_samples(&volume.samples, endian);
    write_atomic(path, |w| w.write_all(&data))
}
