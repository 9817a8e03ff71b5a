//! FreeSurfer MGH volumes (`.mgh`, and `.mgz` or `.mgh.gz` when gzip-compressed):
//! `brain.mgz`, `aseg.mgz`, `T1.mgz` and every other volume FreeSurfer writes.
//!
//! No maintained Rust crate reads MGH; the format is a fixed 284-byte big-endian header,
//! the samples, and an optional footer, so it is read here. The layout follows
//! FreeSurfer's `mghRead` (utils/mriio.cpp) and its description at
//! <https://surfer.nmr.mgh.harvard.edu/fswiki/FsTutorial/MghFormat>, with nibabel's
//! `freesurfer/mghformat.py` (5.4) as the reference reader:
//!
//! | offset | field | type |
//! | --- | --- | --- |
//! | 0 | version (1) | int32 |
//! | 4 | width, height, depth, nframes | 4 x int32 |
//! | 20 | type: 0 uchar, 1 int, 3 float, 4 short, 10 ushort | int32 |
//! | 24 | dof | int32 |
//! | 28 | goodRASFlag | int16 |
//! | 30 | delta: voxel sizes (x, y, z) | 3 x float32 |
//! | 42 | Mdc: direction cosines of x, y, z, one after the other | 9 x float32 |
//! | 78 | Pxyz_c: RAS of the volume's centre | 3 x float32 |
//! | 284 | the samples, x fastest, frame slowest | big endian |
//!
//! The voxel-to-RAS affine is FreeSurfer's `vox2ras` (nibabel `MGHHeader.get_affine`):
//! `M = Mdc^T · diag(delta)`, translation `Pxyz_c - M · (dims / 2)` (a half-voxel
//! centre for odd sizes: the division is in floating point). When goodRASFlag is not
//! positive the direction cosines are not valid: FreeSurfer and nibabel then take 1 mm
//! coronal voxels centred on the origin (`Mdc = [[-1,0,0],[0,0,1],[0,-1,0]]`), and so
//! does glint, with a note.
//!
//! After the samples may come scan parameters (TR, flip angle, TE, TI, field of view:
//! 5 x float32) and FreeSurfer tags (`int32` tag, `int64` length, data; utils/tags.cpp
//! `znzTAGreadStart`). They are reported in the notes; a damaged footer is noted, not
//! refused, since the samples are complete without it. A 4D file yields its first frame,
//! with a note, after the other frames are checked to be present.

use std::io::Read;
use std::path::Path;

use crate::clock::Clock;
use crate::common::{
    check_affine, checked_voxels, open_maybe_gz, os_or_invalid, read_decoded, read_exact_growing,
    Endian, ScalarType,
};
use crate::{Format, IoError, ReadOptions, Volume, VolumeFile};

/// The header's size: the samples start here.
pub const DATA_OFFSET: usize = 284;

/// Bytes of the header fields glint reads (the rest up to [`DATA_OFFSET`] is unused).
const FIELDS_LEN: usize = 90;

/// Most footer bytes read: scan parameters and tags (a command line, a colour table of a
/// few kilobytes, transforms) are far smaller.
const MAX_FOOTER_BYTES: u64 = 1 << 20;

/// FreeSurfer tag numbers (utils/tags.h) named in the notes.
const TAG_NAMES: [(i32, &str); 16] = [
    (1, "old colour table"),
    (2, "old use-real-RAS"),
    (3, "command line"),
    (4, "use-real-RAS"),
    (5, "colour table"),
    (10, "GCA morph geometry"),
    (11, "GCA morph type"),
    (12, "GCA morph labels"),
    (20, "old surface geometry"),
    (21, "surface geometry"),
    (30, "old transform"),
    (31, "transform"),
    (33, "auto-align matrix"),
    (41, "phase-encode direction"),
    (43, "field strength"),
    (44, "original RAS-to-voxel"),
];

/// The header fields.
#[derive(Clone, Debug, PartialEq)]
struct Header {
    version: i32,
    dims: [i32; 4],
    type_code: i32,
    good_ras: i16,
    delta: [f64; 3],
    /// Direction cosines of the x, y and z voxel axes, one after the other.
    mdc: [[f64; 3]; 3],
    centre: [f64; 3],
}

/// Reads the big-endian fields of the header's first [`FIELDS_LEN`] bytes.
fn parse_header(b: &[u8]) -> Header {
    let i32_at = |at: usize| i32::from_be_bytes([b[at], b[at + 1], b[at + 2], b[at + 3]]);
    let f32_at =
        |at: usize| f64::from(f32::from_be_bytes([b[at], b[at + 1], b[at + 2], b[at + 3]]));
    Header {
        version: i32_at(0),
        dims: std::array::from_fn(|i| i32_at(4 + 4 * i)),
        type_code: i32_at(20),
        good_ras: i16::from_be_bytes([b[28], b[29]]),
        delta: std::array::from_fn(|i| f32_at(30 + 4 * i)),
        mdc: std::array::from_fn(|r| std::array::from_fn(|c| f32_at(42 + 12 * r + 4 * c))),
        centre: std::array::from_fn(|i| f32_at(78 + 4 * i)),
    }
}

/// The sample type of a FreeSurfer type code (include/mri.h `MRI_UCHAR` ...).
fn sample_type(path: &Path, code: i32) -> Result<ScalarType, IoError> {
    Ok(match code {
        0 => ScalarType::U8,
        1 => ScalarType::I32,
        3 => ScalarType::F32,
        4 => ScalarType::I16,
        10 => ScalarType::U16,
        _ => {
            let name = match code {
                2 => "long",
                5 => "bitmap",
                6 => "tensor",
                7 => "float complex",
                8 => "double complex",
                9 => "RGB",
                _ => "unknown",
            };
            return Err(IoError::Unsupported {
                path: path.into(),
                what: format!(
                    "MGH data type {code} ({name}); supported: 0 uchar, 1 int, 3 float, \
                     4 short, 10 ushort"
                ),
            });
        }
    })
}

/// Checks the version and the dimensions; returns the 3-D size and the frame count.
fn dims_of(path: &Path, h: &Header) -> Result<([usize; 3], u64), IoError> {
    if h.version != 1 {
        return Err(IoError::BadMagic {
            path: path.into(),
            format: "MGH",
            what: format!("version is {}, expected 1", h.version),
        });
    }
    if let Some(d) = h.dims.iter().find(|&&d| d < 1) {
        return Err(IoError::Invalid {
            path: path.into(),
            what: format!(
                "dimensions {:?} (width, height, depth, frames): {d} is not a size",
                h.dims
            ),
        });
    }
    // Positive i32s fit usize and u64 on every target glint builds for (64-bit).
    let d = h.dims.map(|d| d as usize);
    Ok(([d[0], d[1], d[2]], d[3] as u64))
}

/// The voxel-to-RAS affine (see the module documentation), and whether the default
/// geometry was taken.
fn affine_of(path: &Path, h: &Header, dims: [usize; 3]) -> Result<([[f64; 4]; 4], bool), IoError> {
    let good = h.good_ras > 0;
    let (delta, mdc, centre) = if good {
        (h.delta, h.mdc, h.centre)
    } else {
        (
            [1.0; 3],
            [[-1.0, 0.0, 0.0], [0.0, 0.0, 1.0], [0.0, -1.0, 0.0]],
            [0.0; 3],
        )
    };
    if delta.iter().any(|d| !d.is_finite() || *d <= 0.0) {
        return Err(IoError::Geometry {
            path: path.into(),
            what: format!("voxel sizes (delta) {delta:?} must be finite and positive"),
        });
    }
    let mut a = [[0.0; 4]; 4];
    for r in 0..3 {
        for c in 0..3 {
            // Column c is axis c's direction cosines times its voxel size.
            a[r][c] = mdc[c][r] * delta[c];
        }
        let half: f64 = (0..3).map(|c| a[r][c] * dims[c] as f64 / 2.0).sum();
        a[r][3] = centre[r] - half;
    }
    a[3][3] = 1.0;
    Ok((a, !good))
}

/// Reads an MGH or MGZ volume (gzip is recognised by its signature, whatever the
/// extension). 4D files yield their first frame, with a note.
///
/// The steps, in the order their errors are reported: the header, the sample layout it
/// announces (checked against `options.max_voxels` before anything is allocated), the
/// samples of the first frame, the presence of the other frames, the geometry; then the
/// footer, which only adds notes.
pub fn read(path: &Path, options: &ReadOptions) -> Result<VolumeFile, IoError> {
    let clock = Clock::default();
    let (mut reader, file_len) = open_maybe_gz(path, &clock)?;
    let head = read_exact_growing(path, &mut reader, DATA_OFFSET, "MGH header")?;
    let h = parse_header(&head[..FIELDS_LEN]);
    let (dims, frames) = dims_of(path, &h)?;
    let ty = sample_type(path, h.type_code)?;
    let count = checked_voxels(path, dims, ty.size(), options.max_voxels)?;
    let frame_bytes = (count * ty.size()) as u64;
    let all_bytes = frame_bytes
        .checked_mul(frames)
        .ok_or_else(|| IoError::TooLarge {
            path: path.into(),
            what: format!("{frames} frames of {frame_bytes} bytes overflow"),
        })?;
    if let Some(len) = file_len {
        let need = DATA_OFFSET as u64 + all_bytes;
        if len < need {
            return Err(IoError::SizeMismatch {
                path: path.into(),
                what: format!(
                    "the header announces {frames} frame(s) of {}x{}x{} {ty} ({all_bytes} bytes \
                     after the {DATA_OFFSET}-byte header), but the file has {len} bytes",
                    dims[0], dims[1], dims[2]
                ),
            });
        }
    }
    let checked = file_len.is_some();
    let samples = read_decoded(
        path,
        &mut reader,
        count,
        ty,
        Endian::Big,
        "voxel data",
        checked,
    )?;
    let rest = all_bytes - frame_bytes;
    let skipped = std::io::copy(&mut (&mut reader).take(rest), &mut std::io::sink())
        .map_err(|e| os_or_invalid(path, e))?;
    if skipped < rest {
        return Err(IoError::Truncated {
            path: path.into(),
            what: format!(
                "frames 2..{frames}: expected {rest} bytes after the first frame, found {skipped}"
            ),
        });
    }
    let (affine, default_geometry) = affine_of(path, &h, dims)?;
    let spacing = check_affine(path, &affine)?;
    let mut notes = vec![format!("MGH, {}", type_name(ty))];
    if default_geometry {
        notes.push(
            "geometry assumed: goodRASFlag is not set, 1 mm coronal voxels centred on the \
             origin (as FreeSurfer and nibabel)"
                .into(),
        );
    }
    if frames > 1 {
        notes.push(format!("4D image: read the first of {frames} frames"));
    }
    footer_notes(path, &mut reader, &mut notes);
    Ok(VolumeFile {
        volume: Volume {
            dims,
            spacing,
            affine,
            samples,
            slope: 1.0,
            intercept: 0.0,
            units: None,
            colour: None,
        },
        format: Format::Mgh,
        notes,
        inflate: clock.spent(),
    })
}

/// FreeSurfer's name of a sample type.
fn type_name(ty: ScalarType) -> &'static str {
    match ty {
        ScalarType::U8 => "uchar",
        ScalarType::I32 => "int",
        ScalarType::F32 => "float",
        ScalarType::I16 => "short",
        _ => "ushort",
    }
}

/// Reads the footer after the samples (at most [`MAX_FOOTER_BYTES`]) and describes it in
/// the notes; a footer that cannot be read is noted, never an error.
fn footer_notes(path: &Path, reader: &mut impl Read, notes: &mut Vec<String>) {
    let mut footer = Vec::new();
    if let Err(e) = reader.take(MAX_FOOTER_BYTES).read_to_end(&mut footer) {
        notes.push(format!(
            "footer not read ({}): scan parameters and tags ignored",
            os_or_invalid(path, e)
        ));
        return;
    }
    notes.extend(describe_footer(&footer));
}

/// The notes for a footer: scan parameters (when the five floats are there and not all
/// zero), then the tags, until a zero tag, the end, or a tag that cannot be skipped.
pub(crate) fn describe_footer(b: &[u8]) -> Vec<String> {
    let mut notes = Vec::new();
    if b.len() < 20 {
        return notes;
    }
    let f = |i: usize| f32::from_be_bytes([b[4 * i], b[4 * i + 1], b[4 * i + 2], b[4 * i + 3]]);
    let [tr, flip, te, ti, fov] = std::array::from_fn(f);
    if [tr, flip, te, ti, fov].iter().any(|&x| x != 0.0) {
        // mriio.cpp: TR, TE, TI in ms; the flip angle in radians.
        notes.push(format!(
            "scan parameters: TR {tr} ms, flip angle {:.4} deg, TE {te} ms, TI {ti} ms, \
             FoV {fov} mm",
            f64::from(flip).to_degrees()
        ));
    }
    let mut tags = Vec::new();
    let mut pos = 20usize;
    while let Some(t) = b.get(pos..pos + 4) {
        let tag = i32::from_be_bytes([t[0], t[1], t[2], t[3]]);
        if tag == 0 {
            break;
        }
        let name = TAG_NAMES
            .iter()
            .find(|(n, _)| *n == tag)
            .map_or_else(|| format!("tag {tag}"), |(_, s)| (*s).to_string());
        // tags.cpp znzTAGreadStart: the old transform has a 32-bit length, three old
        // tags none at all (their data cannot be skipped), every other a 64-bit one.
        let (len, header) = match tag {
            30 => (
                b.get(pos + 4..pos + 8)
                    .map(|l| u64::from(u32::from_be_bytes([l[0], l[1], l[2], l[3]]))),
                8,
            ),
            1 | 2 | 20 => {
                tags.push(format!("{name} (not skippable: later tags not read)"));
                break;
            }
            _ => (
                b.get(pos + 4..pos + 12)
                    .map(|l| u64::from_be_bytes(l.try_into().expect("8 bytes"))),
                12,
            ),
        };
        let Some(len) = len.filter(|&l| l <= (b.len() - pos - header) as u64) else {
            tags.push(format!("{name} (cut short: later tags not read)"));
            break;
        };
        let data = &b[pos + header..pos + header + len as usize];
        if tag == 3 {
            let text = String::from_utf8_lossy(data);
            tags.push(format!(
                "{name} '{}'",
                crate::dicom::one_line(text.trim_end_matches('\0').trim())
            ));
        } else {
            tags.push(format!("{name} ({len} bytes)"));
        }
        pos += header + len as usize;
    }
    if !tags.is_empty() {
        notes.push(format!("footer tags: {}", tags.join("; ")));
    }
    notes
}

#[cfg(test)]
mod tests {
    use super::describe_footer;

    fn tag(t: i32, data: &[u8]) -> Vec<u8> {
        let mut v = t.to_be_bytes().to_vec();
        v.extend((data.len() as i64).to_be_bytes());
        v.extend(data);
        v
    }

    #[test]
    fn footer_parameters_and_tags() {
        let mut b: Vec<u8> = [2300f32, 0.15708, 2.98, 900.0, 256.0]
            .iter()
            .flat_map(|x| x.to_be_bytes())
            .collect();
        b.extend(tag(3, b"mri_convert a.nii b.mgz\0"));
        b.extend(tag(43, &3.0f32.to_be_bytes()));
        let notes = describe_footer(&b);
        assert_eq!(notes.len(), 2, "{notes:?}");
        assert!(notes[0].contains("TR 2300 ms"), "{notes:?}");
        assert!(notes[0].contains("flip angle 9.0000 deg"), "{notes:?}");
        assert_eq!(
            notes[1],
            "footer tags: command line 'mri_convert a.nii b.mgz'; field strength (4 bytes)"
        );
    }

    #[test]
    fn footer_with_a_tag_past_the_end_or_an_old_tag_stops() {
        let mut b = vec![0u8; 20];
        let mut t = tag(5, &[1, 2, 3]);
        t.truncate(t.len() - 1);
        b.extend(t);
        assert_eq!(
            describe_footer(&b),
            vec!["footer tags: colour table (cut short: later tags not read)".to_string()]
        );
        let mut b = vec![0u8; 20];
        b.extend(1i32.to_be_bytes());
        b.extend(tag(3, b"x"));
        assert_eq!(
            describe_footer(&b),
            vec!["footer tags: old colour table (not skippable: later tags not read)".to_string()]
        );
        // No footer at all, or scan parameters all zero: nothing to say.
        assert!(describe_footer(&[]).is_empty());
        assert!(describe_footer(&[0; 20]).is_empty());
    }
}
