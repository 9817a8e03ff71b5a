//! Writing NRRD volumes, attached (`.nrrd`) or detached (`.nhdr` + data file).

use std::io::Write;
use std::path::{Path, PathBuf};

use super::Encoding;
use crate::common::{encode_samples, write_atomic, Endian, ScalarType};
use crate::{IoError, Volume};

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
