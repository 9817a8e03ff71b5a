//! The checksum of an input: what a rerun compares to know that an input's bytes did
//! not change.

use std::io::Read;
use std::path::Path;

use blake3::Hasher;

use crate::{os_error, BatchError};

/// `blake3:` and the hex BLAKE3 (256 bits) of the input's bytes: of a file, what
/// `b3sum` prints for it; of a `.hdr` header, of the header followed by its `.img` data file
/// when there is one; of a directory (a DICOM series), of its regular files (and links to them) in name
/// order, each as its name, a NUL byte, its length as 8 little-endian bytes and its
/// bytes (so renaming or moving bytes between files changes it). An `.nhdr`'s detached
/// data file is not included.
pub fn checksum(path: &Path) -> Result<String, BatchError> {
    let mut hash = Hasher::new();
    let meta = std::fs::metadata(path).map_err(|e| os_error(path, e))?;
    if meta.is_dir() {
        let mut files = Vec::new();
        for entry in std::fs::read_dir(path).map_err(|e| os_error(path, e))? {
            let entry = entry.map_err(|e| os_error(path, e))?;
            // Regular files and symbolic links to them (a DataLad dataset's files are
            // links into its annex); a link to nothing is a file too, whose read fails
            // with the error that names it.
            let file = entry.path();
            let regular = match std::fs::metadata(&file) {
                Ok(meta) => meta.is_file(),
                Err(_) => glint_io::broken_link(&file).is_some(),
            };
            if regular {
                files.push(file);
            }
        }
        files.sort();
        for file in files {
            let name = file.file_name().unwrap_or_default().to_string_lossy();
            let len = std::fs::metadata(&file)
                .map_err(|e| os_error(&file, e))?
                .len();
            hash.update(name.as_bytes());
            hash.update(&[0]);
            hash.update(&len.to_le_bytes());
            feed(&mut hash, &file)?;
        }
    } else {
        feed(&mut hash, path)?;
        let is_hdr = path
            .extension()
            .is_some_and(|e| e.eq_ignore_ascii_case("hdr"));
        if is_hdr {
            for ext in ["img", "IMG"] {
                let img = path.with_extension(ext);
                if img.is_file() {
                    feed(&mut hash, &img)?;
                    break;
                }
            }
        }
    }
    Ok(format!("blake3:{}", hash.finalize().to_hex()))
}

/// Feeds a file's bytes to the hash, in 1 MiB reads.
fn feed(hash: &mut Hasher, path: &Path) -> Result<(), BatchError> {
    let mut file = std::fs::File::open(path).map_err(|e| os_error(path, e))?;
    let mut buf = vec![0u8; 1 << 20];
    loop {
        let n = file.read(&mut buf).map_err(|e| os_error(path, e))?;
        if n == 0 {
            return Ok(());
        }
        hash.update(&buf[..n]);
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_file_hashes_as_b3sum_does() {
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("abc.nii");
        std::fs::write(&path, b"abc").unwrap();
        // `printf abc | b3sum` (b3sum 1.2.0).
        assert_eq!(
            checksum(&path).unwrap(),
            "blake3:6437b3ac38465133ffb63b75273a8db548c558465d79db03fd359c6cd5bd9d85"
        );
        // More than one 1 MiB read and more than one BLAKE3 chunk (1 KiB), so the
        // SIMD kernels' paths count: `head -c 3000000 /dev/zero | b3sum`.
        std::fs::write(&path, vec![0u8; 3_000_000]).unwrap();
        assert_eq!(
            checksum(&path).unwrap(),
            "blake3:72f882f1b5dd958d1b163829c126e1b02e876ea671ce0198bacbdbbf83b16e4d"
        );
    }

    #[test]
    fn pairs_and_series_change_with_any_of_their_files() {
        let dir = tempfile::tempdir().unwrap();
        let hdr = dir.path().join("p.hdr");
        std::fs::write(&hdr, b"header").unwrap();
        let alone = checksum(&hdr).unwrap();
        std::fs::write(dir.path().join("p.img"), b"data").unwrap();
        let paired = checksum(&hdr).unwrap();
        assert_ne!(alone, paired);
        std::fs::write(dir.path().join("p.img"), b"datb").unwrap();
        assert_ne!(checksum(&hdr).unwrap(), paired);

        let series = dir.path().join("series");
        std::fs::create_dir(&series).unwrap();
        std::fs::write(series.join("1.dcm"), b"ab").unwrap();
        std::fs::write(series.join("2.dcm"), b"c").unwrap();
        let first = checksum(&series).unwrap();
        // The same bytes split differently between the files.
        std::fs::write(series.join("1.dcm"), b"a").unwrap();
        std::fs::write(series.join("2.dcm"), b"bc").unwrap();
        assert_ne!(checksum(&series).unwrap(), first);
        let err = checksum(&dir.path().join("missing.nii")).unwrap_err();
        assert!(glint_io::one_line(&err).contains("missing.nii"), "{err}");
    }
}
