//! Shared by every target: the readers take paths, so each input is written to a file
//! with the format's extension in a per-process directory (in /dev/shm when there is
//! one, to keep the disk out of the loop), read, and its error checked for one line.

use std::path::PathBuf;
use std::sync::OnceLock;

static DIR: OnceLock<tempfile_dir::Dir> = OnceLock::new();

mod tempfile_dir {
    /// A directory removed when the process ends normally.
    pub struct Dir(pub std::path::PathBuf);
    impl Drop for Dir {
        fn drop(&mut self) {
            let _ = std::fs::remove_dir_all(&self.0);
        }
    }
}

/// The process's directory.
fn dir() -> &'static std::path::Path {
    &DIR.get_or_init(|| {
        let base = if std::path::Path::new("/dev/shm").is_dir() {
            PathBuf::from("/dev/shm")
        } else {
            std::env::temp_dir()
        };
        let d = base.join(format!("glint-fuzz-{}", std::process::id()));
        std::fs::create_dir_all(&d).expect("create the fuzz directory");
        tempfile_dir::Dir(d)
    })
    .0
}

/// The path `input.<ext>` in the process's directory, for a target that writes a
/// directory (a Zarr store).
#[allow(dead_code)]
pub fn input_dir(ext: &str) -> PathBuf {
    dir().join(format!("input.{ext}"))
}

/// Writes `data` to `input.<ext>` in the process's directory and returns the path.
#[allow(dead_code)]
pub fn input_file(data: &[u8], ext: &str) -> PathBuf {
    let path = dir().join(format!("input.{ext}"));
    std::fs::write(&path, data).expect("write the fuzz input");
    path
}

/// The limit every volume target reads with: small enough that a header announcing a
/// huge volume is refused rather than allocated.
pub fn options() -> glint_io::ReadOptions {
    glint_io::ReadOptions {
        max_voxels: 1 << 22,
        ..Default::default()
    }
}

/// Errors must stay on one line whatever bytes they quote (issue 17).
pub fn check_error<T>(r: Result<T, glint_io::IoError>) {
    if let Err(e) = r {
        let s = e.to_string();
        assert!(!s.contains('\n') && !s.contains('\r'), "multi-line error: {s:?}");
    }
}
