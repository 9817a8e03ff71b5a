//! Pieces every reader shares: sample types, byte order, size checks before allocation,
//! affine geometry, and atomic writes.

use std::io::{BufReader, Read, Write};
use std::path::{Path, PathBuf};
use std::sync::{Mutex, MutexGuard, PoisonError};

use flate2::read::MultiGzDecoder;

use crate::clock::Clock;
use crate::{IoError, Samples};

/// The stored type of a volume's samples, by name `u8`, `i8`, `u16`, `i16`, `u32`, `i32`,
/// `f32`, `f64` (also the NIfTI/NRRD-style long names: `uint16`, `float`, ...).
#[derive(
    Clone,
    Copy,
    Debug,
    PartialEq,
    Eq,
    Hash,
    strum::EnumString,
    strum::IntoStaticStr,
    strum::Display,
    strum::VariantNames,
    strum::VariantArray,
)]
#[strum(
    serialize_all = "lowercase",
    ascii_case_insensitive,
    parse_err_ty = ParseScalarTypeError,
    parse_err_fn = ParseScalarTypeError::new
)]
pub enum ScalarType {
    /// Unsigned 8-bit.
    #[strum(to_string = "u8", serialize = "uint8", serialize = "uchar")]
    U8,
    /// Signed 8-bit.
    #[strum(to_string = "i8", serialize = "int8", serialize = "char")]
    I8,
    /// Unsigned 16-bit.
    #[strum(to_string = "u16", serialize = "uint16", serialize = "ushort")]
    U16,
    /// Signed 16-bit.
    #[strum(to_string = "i16", serialize = "int16", serialize = "short")]
    I16,
    /// Unsigned 32-bit.
    #[strum(to_string = "u32", serialize = "uint32", serialize = "uint")]
    U32,
    /// Signed 32-bit.
    #[strum(to_string = "i32", serialize = "int32", serialize = "int")]
    I32,
    /// 32-bit IEEE float.
    #[strum(to_string = "f32", serialize = "float32", serialize = "float")]
    F32,
    /// 64-bit IEEE float.
    #[strum(to_string = "f64", serialize = "float64", serialize = "double")]
    F64,
}

impl ScalarType {
    /// Every supported type.
    pub const ALL: &'static [ScalarType] = <ScalarType as strum::VariantArray>::VARIANTS;

    /// Bytes per sample.
    pub fn size(self) -> usize {
        match self {
            ScalarType::U8 | ScalarType::I8 => 1,
            ScalarType::U16 | ScalarType::I16 => 2,
            ScalarType::U32 | ScalarType::I32 | ScalarType::F32 => 4,
            ScalarType::F64 => 8,
        }
    }

    /// The short name used on the command line (`u8`, `i16`, `f32`, ...).
    pub fn short_name(self) -> &'static str {
        self.into()
    }

    /// The type of stored samples.
    pub fn of(samples: &Samples) -> ScalarType {
        match samples {
            Samples::U8(_) => ScalarType::U8,
            Samples::I8(_) => ScalarType::I8,
            Samples::U16(_) => ScalarType::U16,
            Samples::I16(_) => ScalarType::I16,
            Samples::U32(_) => ScalarType::U32,
            Samples::I32(_) => ScalarType::I32,
            Samples::F32(_) => ScalarType::F32,
            Samples::F64(_) => ScalarType::F64,
        }
    }
}

/// Error of parsing a [`ScalarType`] name.
#[derive(Debug, thiserror::Error)]
#[error("unknown sample type '{0}' (expected u8, i8, u16, i16, u32, i32, f32 or f64)")]
pub struct ParseScalarTypeError(String);

impl ParseScalarTypeError {
    fn new(name: &str) -> ParseScalarTypeError {
        ParseScalarTypeError(name.to_string())
    }
}

/// Byte order of multi-byte samples (`little` or `le`, `big` or `be`).
#[derive(
    Clone,
    Copy,
    Debug,
    Default,
    PartialEq,
    Eq,
    Hash,
    strum::EnumString,
    strum::IntoStaticStr,
    strum::Display,
    strum::VariantNames,
)]
#[strum(serialize_all = "lowercase", ascii_case_insensitive)]
pub enum Endian {
    /// Least significant byte first (x86, ARM, most files).
    #[default]
    #[strum(to_string = "little", serialize = "le")]
    Little,
    /// Most significant byte first.
    #[strum(to_string = "big", serialize = "be")]
    Big,
}

/// Encodes samples as bytes in the given order.
pub(crate) fn encode_samples(samples: &Samples, endian: Endian) -> Vec<u8> {
    macro_rules! enc {
        ($v:expr) => {
            $v.iter()
                .flat_map(|x| match endian {
                    Endian::Little => x.to_le_bytes(),
                    Endian::Big => x.to_be_bytes(),
                })
                .collect()
        };
    }
    match samples {
        Samples::U8(v) => v.clone(),
        Samples::I8(v) => v.iter().map(|&x| x as u8).collect(),
        Samples::U16(v) => enc!(v),
        Samples::I16(v) => enc!(v),
        Samples::U32(v) => enc!(v),
        Samples::I32(v) => enc!(v),
        Samples::F32(v) => enc!(v),
        Samples::F64(v) => enc!(v),
    }
}

/// The voxel count of `dims`, refused if it is zero, overflows, or exceeds `max_voxels`;
/// also refused if the byte size overflows. Called before any allocation for samples.
pub(crate) fn checked_voxels(
    path: &Path,
    dims: [usize; 3],
    bytes_per_sample: usize,
    max_voxels: u64,
) -> Result<usize, IoError> {
    if dims.contains(&0) {
        return Err(IoError::Invalid {
            path: path.into(),
            what: format!("dimensions {dims:?} contain a zero"),
        });
    }
    let count = dims
        .iter()
        .try_fold(1u64, |acc, &d| acc.checked_mul(d as u64))
        .ok_or_else(|| IoError::TooLarge {
            path: path.into(),
            what: format!("dimensions {dims:?} overflow a 64-bit voxel count"),
        })?;
    if count > max_voxels {
        return Err(IoError::TooLarge {
            path: path.into(),
            what: format!(
                "dimensions {}x{}x{} = {count} voxels exceed the limit of {max_voxels} \
                 (raise it with --max-voxels)",
                dims[0], dims[1], dims[2]
            ),
        });
    }
    let count = usize::try_from(count).map_err(|_| IoError::TooLarge {
        path: path.into(),
        what: format!("{count} voxels do not fit this machine's address space"),
    })?;
    count
        .checked_mul(bytes_per_sample)
        .ok_or_else(|| IoError::TooLarge {
            path: path.into(),
            what: format!("{count} voxels of {bytes_per_sample} bytes overflow"),
        })?;
    Ok(count)
}

/// Reads exactly `n` bytes. The buffer grows with the data actually read, so a header
/// that lies about the size costs no more memory than the file holds.
pub(crate) fn read_exact_growing(
    path: &Path,
    reader: impl Read,
    n: usize,
    what: &str,
) -> Result<Vec<u8>, IoError> {
    let mut buf = Vec::with_capacity(n.min(1 << 24));
    reader
        .take(n as u64)
        .read_to_end(&mut buf)
        .map_err(|e| os_or_invalid(path, e))?;
    if buf.len() < n {
        return Err(IoError::Truncated {
            path: path.into(),
            what: format!("{what}: expected {n} bytes, found {}", buf.len()),
        });
    }
    Ok(buf)
}

/// The most bytes a deflate stream inflates to per byte: 1032 (zlib's technical
/// details, <https://www.zlib.net/zlib_tech.html>, "the limit is 1032:1").
const MAX_INFLATE: u64 = 1032;

/// Whether the (compressed) file at `path` is long enough to inflate to `bytes`: then
/// a header announcing that many bytes of data is possible, and allocating them at once
/// costs at most [`MAX_INFLATE`] times the file, not what a lying header says. Growing
/// the samples from a small buffer instead copies and page-faults them about twice (a
/// tenth of `glint batch`'s time on a gzipped 35 MB float volume, issue 32).
pub(crate) fn can_inflate_to(path: &Path, bytes: u64) -> bool {
    std::fs::metadata(path).is_ok_and(|m| m.len().saturating_mul(MAX_INFLATE) >= bytes)
}

/// Bytes read and decoded at a time by [`read_decoded`]: a multiple of every sample size.
const DECODE_CHUNK: usize = 4 << 20;

/// Sample buffers handed back by [`recycle`], for the next reads.
static SPARES: Mutex<Vec<Samples>> = Mutex::new(Vec::new());

/// Most buffers [`recycle`] keeps.
const MAX_SPARES: usize = 8;

fn spares() -> MutexGuard<'static, Vec<Samples>> {
    // Every update is a push or a removal: a poisoned pool is still consistent.
    SPARES.lock().unwrap_or_else(PoisonError::into_inner)
}

/// Hands back the samples of a volume the caller is done with, for a later read of
/// samples of the same type: a reader that needs `n` samples takes a kept buffer of
/// capacity `n ..= 2n` instead of allocating, so the next volume reuses memory already
/// paged in. A fresh allocation of a volume's size is mapped afresh and cleared by the
/// kernel page by page: 9% of a `glint batch` subject's CPU (issue 47), where each
/// input's samples are handed back once it is made. At most 8 buffers are kept (the
/// others are freed); nothing else changes what a read returns.
pub fn recycle(samples: Samples) {
    let mut pool = spares();
    if pool.len() < MAX_SPARES && samples.capacity() > 0 {
        pool.push(samples);
    }
}

/// Whether a kept buffer of `capacity` suits a read of `want` samples.
fn suits(capacity: usize, want: usize) -> bool {
    capacity >= want && capacity / 2 <= want
}

/// Reads exactly `count` samples of `ty` and decodes them a chunk at a time, so a volume
/// costs its samples and one 4 MiB buffer rather than its bytes and then its samples (a
/// 512^3 int16 NIfTI peaked at 3x its size with a whole-file buffer, issue 31).
///
/// `checked`: the data's length was checked against the file before the call (an
/// uncompressed file, or a compressed one that can inflate to it: [`can_inflate_to`]),
/// so the samples are allocated once at their full size; otherwise they grow with the
/// data actually read, so a header that lies about the size costs no more memory than
/// the stream holds. Errors name `what` when the data ends early.
pub(crate) fn read_decoded(
    path: &Path,
    reader: impl Read,
    count: usize,
    ty: ScalarType,
    endian: Endian,
    what: &str,
    checked: bool,
) -> Result<Samples, IoError> {
    let n = count * ty.size();
    let mut reader = reader.take(n as u64);
    let mut buf = vec![0u8; DECODE_CHUNK.min(n)];
    let initial = if checked {
        count
    } else {
        count.min(DECODE_CHUNK)
    };
    let mut done = 0usize;
    // Fills `buf` (or what is left of the data) and hands the bytes read to `decode`;
    // false once the data is exhausted.
    let mut next = |decode: &mut dyn FnMut(&[u8])| -> Result<bool, IoError> {
        let want = buf.len().min(n - done);
        let mut got = 0;
        while got < want {
            match reader.read(&mut buf[got..want]) {
                Ok(0) => break,
                Ok(k) => got += k,
                Err(e) if e.kind() == std::io::ErrorKind::Interrupted => {}
                Err(e) => return Err(os_or_invalid(path, e)),
            }
        }
        done += got;
        decode(&buf[..got]);
        Ok(got == want && done < n)
    };
    macro_rules! typed {
        ($variant:ident, $t:ty) => {{
            const SIZE: usize = std::mem::size_of::<$t>();
            // A buffer handed back by `recycle` when one suits, else a new one.
            let mut out: Vec<$t> = {
                let mut pool = spares();
                let fits = |s: &Samples| {
                    matches!(s, Samples::$variant(v) if checked && suits(v.capacity(), count))
                };
                match pool.iter().position(fits).map(|i| pool.swap_remove(i)) {
                    Some(Samples::$variant(mut v)) => {
                        v.clear();
                        v
                    }
                    _ => Vec::with_capacity(initial),
                }
            };
            let mut decode = |bytes: &[u8]| {
                out.extend(bytes.chunks_exact(SIZE).map(|c| {
                    let mut a = [0u8; SIZE];
                    a.copy_from_slice(c);
                    match endian {
                        Endian::Little => <$t>::from_le_bytes(a),
                        Endian::Big => <$t>::from_be_bytes(a),
                    }
                }))
            };
            while next(&mut decode)? {}
            Samples::$variant(out)
        }};
    }
    let samples = match ty {
        ScalarType::U8 => typed!(U8, u8),
        ScalarType::I8 => typed!(I8, i8),
        ScalarType::U16 => typed!(U16, u16),
        ScalarType::I16 => typed!(I16, i16),
        ScalarType::U32 => typed!(U32, u32),
        ScalarType::I32 => typed!(I32, i32),
        ScalarType::F32 => typed!(F32, f32),
        ScalarType::F64 => typed!(F64, f64),
    };
    if done < n {
        return Err(IoError::Truncated {
            path: path.into(),
            what: format!("{what}: expected {n} bytes, found {done}"),
        });
    }
    Ok(samples)
}

/// Maps a read error: corrupt compressed streams are the file's fault, the rest the OS's.
pub(crate) fn os_or_invalid(path: &Path, e: std::io::Error) -> IoError {
    match e.kind() {
        std::io::ErrorKind::InvalidData | std::io::ErrorKind::InvalidInput => IoError::Invalid {
            path: path.into(),
            what: format!("corrupt data: {e}"),
        },
        std::io::ErrorKind::UnexpectedEof => IoError::Truncated {
            path: path.into(),
            what: e.to_string(),
        },
        _ => IoError::Os {
            path: path.into(),
            source: e,
        },
    }
}

/// Opens a file for reading, naming it in the error.
pub(crate) fn open(path: &Path) -> Result<std::fs::File, IoError> {
    std::fs::File::open(path).map_err(|e| crate::link::os_error(path, e))
}

/// Opens a file, gunzipping it when it starts with the gzip signature (the time spent
/// inflating goes to `clock`); the length is known only for an uncompressed file.
pub(crate) fn open_maybe_gz(
    path: &Path,
    clock: &Clock,
) -> Result<(Box<dyn Read>, Option<u64>), IoError> {
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

/// Whether the file starts with the gzip signature.
pub(crate) fn is_gzip(path: &Path) -> Result<bool, IoError> {
    let mut magic = [0u8; 2];
    let mut f = open(path)?;
    let mut got = 0;
    while got < 2 {
        match f.read(&mut magic[got..]) {
            Ok(0) => break,
            Ok(k) => got += k,
            Err(e) => return Err(os_or_invalid(path, e)),
        }
    }
    Ok(got == 2 && magic == [0x1f, 0x8b])
}

/// Checks that an affine places voxels in 3-D space ([`crate::affine::check`]) and
/// returns its spacing; the error names the file.
pub(crate) fn check_affine(path: &Path, affine: &[[f64; 4]; 4]) -> Result<[f64; 3], IoError> {
    crate::affine::check(affine).map_err(|e| IoError::Geometry {
        path: path.into(),
        what: e.to_string(),
    })
}

/// Refuses a scaling `slope * stored + intercept` (NIfTI's scl_slope and scl_inter,
/// named in the error as `names`) that would make the volume render black without a
/// word: values beyond f32 (the renderer's samples: they become infinite), a value
/// range wider than f32 holds (the normalisation divides by it), or an intercept so
/// large that distinct stored values all become one f32 (a constant image). Integer samples whose type
/// cannot reach the bounds are not scanned.
pub(crate) fn check_scaling(
    path: &Path,
    samples: &crate::Samples,
    (slope, intercept): (f64, f64),
    names: [&str; 2],
) -> Result<(), IoError> {
    let limit = f64::from(f32::MAX);
    if slope == 1.0 && intercept == 0.0 {
        return Ok(());
    }
    // Far below the limits, and coarse enough that f32 tells the stored steps apart
    // (|slope| >= 2^-20 of the intercept's magnitude keeps one step above an f32 ulp).
    let fast = samples.type_bound().is_some_and(|bound| {
        slope.abs() * bound + intercept.abs() <= limit / 4.0
            && slope.abs() >= intercept.abs() * f64::from(f32::EPSILON) * 4.0
    });
    if fast {
        return Ok(());
    }
    let Some((lo, hi)) = samples.finite_range() else {
        return Ok(());
    };
    let (a, b) = (slope * lo + intercept, slope * hi + intercept);
    let (plo, phi) = (a.min(b), a.max(b));
    let why = if !(plo.abs() <= limit && phi.abs() <= limit) {
        "beyond f32's range (|value| <= 3.4e38)"
    } else if phi - plo > limit {
        "a range wider than f32 holds (3.4e38)"
    } else if hi > lo && plo as f32 == phi as f32 && (slope * lo) as f32 != (slope * hi) as f32 {
        "one f32 value: every distinction between the stored values is lost"
    } else {
        return Ok(());
    };
    // The header's numbers as it stores them (NIfTI's are f32: 1e38, not
    // 9.999999680285692e37).
    let short = |x: f64| match x as f32 {
        y if f64::from(y) == x => format!("{y:e}"),
        _ => format!("{x:e}"),
    };
    Err(IoError::Invalid {
        path: path.into(),
        what: format!(
            "{} {} and {} {} scale the stored values {lo}..{hi} to {:e}..{:e}, {why}: \
             refusing a scaling that renders black",
            names[0],
            short(slope),
            names[1],
            short(intercept),
            plo as f32,
            phi as f32,
        ),
    })
}

/// Checks user- or header-given voxel sizes.
pub(crate) fn check_spacing(path: &Path, spacing: [f64; 3]) -> Result<(), IoError> {
    if spacing.iter().any(|s| !s.is_finite() || *s <= 0.0) {
        return Err(IoError::Geometry {
            path: path.into(),
            what: format!("voxel spacing {spacing:?} must be finite and positive"),
        });
    }
    Ok(())
}

/// A diagonal affine of `spacing` with the given origin.
pub(crate) fn diagonal_affine(spacing: [f64; 3], origin: [f64; 3]) -> [[f64; 4]; 4] {
    let mut a = [[0.0; 4]; 4];
    for i in 0..3 {
        a[i][i] = spacing[i];
        a[i][3] = origin[i];
    }
    a[3][3] = 1.0;
    a
}

/// Writes a file atomically: into a temporary file in the same directory, renamed into
/// place only when complete, so a failure leaves no partial output. The one atomic
/// writer of the workspace (volumes, meshes, PNGs, ROM files).
///
/// ```
/// let dir = tempfile::tempdir().unwrap();
/// let path = dir.path().join("hello.txt");
/// glint_io::write_atomic(&path, |w| w.write_all(b"hello")).unwrap();
/// assert_eq!(std::fs::read(&path).unwrap(), b"hello");
/// ```
pub fn write_atomic(
    path: &Path,
    body: impl FnOnce(&mut dyn Write) -> std::io::Result<()>,
) -> Result<(), IoError> {
    let os = |e: std::io::Error| IoError::Os {
        path: path.into(),
        source: e,
    };
    let dir = match path.parent() {
        Some(d) if !d.as_os_str().is_empty() => d.to_path_buf(),
        _ => PathBuf::from("."),
    };
    let mut builder = tempfile::Builder::new();
    // A temporary file is private (0600); an output is an ordinary file, created with
    // 0666 less the umask like any other.
    #[cfg(unix)]
    {
        use std::os::unix::fs::PermissionsExt;
        builder.permissions(std::fs::Permissions::from_mode(0o666));
    }
    let mut tmp = builder.tempfile_in(&dir).map_err(os)?;
    {
        let mut w = std::io::BufWriter::new(tmp.as_file_mut());
        body(&mut w).map_err(os)?;
        w.flush().map_err(os)?;
    }
    tmp.persist(path).map_err(|e| os(e.error))?;
    Ok(())
}

/// Whether a file has DICOM's "DICM" marker after the 128-byte preamble (PS3.10 7.1).
pub(crate) fn has_dicom_magic(path: &Path) -> bool {
    let mut head = [0u8; 132];
    std::fs::File::open(path)
        .and_then(|mut f| f.read_exact(&mut head))
        .is_ok()
        && &head[128..] == b"DICM"
}

#[cfg(test)]
mod tests {
    use super::ScalarType;

    #[test]
    fn a_compressed_file_is_sized_up_front_only_for_what_it_can_inflate_to() {
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("v.nii.gz");
        std::fs::write(&path, [0u8; 100]).unwrap();
        // 100 bytes of deflate inflate to at most 103,200 bytes (zlib's 1032:1).
        assert!(super::can_inflate_to(&path, 103_200));
        assert!(!super::can_inflate_to(&path, 103_201));
        assert!(!super::can_inflate_to(&dir.path().join("missing.gz"), 1));
    }

    #[test]
    fn scalar_type_names_print_short_and_parse_long() {
        let short: Vec<String> = ScalarType::ALL.iter().map(|t| t.to_string()).collect();
        assert_eq!(
            short,
            ["u8", "i8", "u16", "i16", "u32", "i32", "f32", "f64"]
        );
        for (long, t) in [
            ("uint8", ScalarType::U8),
            ("char", ScalarType::I8),
            ("USHORT", ScalarType::U16),
            ("short", ScalarType::I16),
            ("uint", ScalarType::U32),
            ("int32", ScalarType::I32),
            ("float", ScalarType::F32),
            ("double", ScalarType::F64),
        ] {
            assert_eq!(long.parse::<ScalarType>().unwrap(), t);
        }
        assert!("u12".parse::<ScalarType>().is_err());
    }

    /// An atomically written output gets the permissions of any file the user creates
    /// (0666 less the umask), not the temporary file's private 0600.
    #[cfg(unix)]
    #[test]
    fn atomic_outputs_have_ordinary_permissions() {
        use std::os::unix::fs::PermissionsExt;
        let dir = tempfile::tempdir().unwrap();
        let ours = dir.path().join("ours.png");
        super::write_atomic(&ours, |w| w.write_all(b"x")).unwrap();
        let plain = dir.path().join("plain.png");
        std::fs::write(&plain, b"x").unwrap();
        let mode = |p: &std::path::Path| std::fs::metadata(p).unwrap().permissions().mode() & 0o777;
        assert_eq!(mode(&ours), mode(&plain));
    }

    /// Samples decoded a chunk at a time are the bytes' values across chunk boundaries
    /// (a chunk of 4 MiB ends inside no sample), in both byte orders, checked or not;
    /// data that ends early is an error naming the bytes found.
    #[test]
    fn chunked_decoding_matches_the_bytes_and_refuses_short_data() {
        use super::{read_decoded, Endian, ScalarType};
        use crate::Samples;
        let count = super::DECODE_CHUNK / 2 + 3;
        let values: Vec<i16> = (0..count)
            .map(|i| (i as i64 * 7919 % 65536 - 32768) as i16)
            .collect();
        let le: Vec<u8> = values.iter().flat_map(|v| v.to_le_bytes()).collect();
        let be: Vec<u8> = values.iter().flat_map(|v| v.to_be_bytes()).collect();
        let path = std::path::Path::new("x.raw");
        for checked in [true, false] {
            for (bytes, endian) in [(&le, Endian::Little), (&be, Endian::Big)] {
                let got = read_decoded(
                    path,
                    &bytes[..],
                    count,
                    ScalarType::I16,
                    endian,
                    "v",
                    checked,
                );
                assert_eq!(got.unwrap(), Samples::I16(values.clone()));
            }
        }
        let short = read_decoded(
            path,
            &le[..le.len() - 1],
            count,
            ScalarType::I16,
            Endian::Little,
            "v",
            true,
        );
        let err = short.unwrap_err().to_string();
        assert!(
            err.contains(&format!(
                "expected {} bytes, found {}",
                le.len(),
                le.len() - 1
            )),
            "{err}"
        );
    }

    /// A buffer handed back by `recycle` is what the next read of its type and about
    /// its size fills (its old values gone), and the samples read are those of a new
    /// buffer; a buffer too large for the read, or of another type, stays kept.
    #[test]
    fn recycled_buffers_are_filled_as_new_ones() {
        use super::{read_decoded, recycle, spares, Endian, ScalarType};
        use crate::Samples;
        // A type and sizes no other test reads, so the shared pool is this test's.
        let count = 3001;
        let values: Vec<u32> = (0..count as u32)
            .map(|i| i.wrapping_mul(2_654_435_761))
            .collect();
        let bytes: Vec<u8> = values.iter().flat_map(|v| v.to_le_bytes()).collect();
        let read = || {
            let path = std::path::Path::new("r.raw");
            read_decoded(
                path,
                &bytes[..],
                count,
                ScalarType::U32,
                Endian::Little,
                "v",
                true,
            )
            .unwrap()
        };
        let mut old = vec![7u32; 4000];
        old.truncate(3500);
        let at = old.as_ptr();
        recycle(Samples::U32(vec![1u32; 7000]));
        recycle(Samples::I32(vec![2i32; 3100]));
        recycle(Samples::U32(old));
        let Samples::U32(got) = read() else {
            panic!("not u32")
        };
        assert_eq!(got, values);
        assert_eq!(got.as_ptr(), at, "the kept buffer of 4000 was reused");
        let kept = |n: usize| spares().iter().any(|s| s.capacity() == n);
        assert!(kept(7000) && kept(3100));
        assert_eq!(read(), Samples::U32(values.clone()));
        spares().retain(|s| ![7000, 3100].contains(&s.capacity()));
    }
}
