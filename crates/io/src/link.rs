//! Symbolic links whose target is missing, named for what they are.
//!
//! A DataLad dataset (OpenNeuro's are) keeps every file as a symbolic link into
//! `.git/annex/objects/`; a file whose content was never fetched is a link to nothing.
//! Opening one fails with the operating system's "No such file or directory", which
//! hides that the file is there and only its content is not: [`broken_link`] tells
//! the two apart, and every reader's "not found" goes through it.

use std::path::{Path, PathBuf};

use crate::IoError;

/// What marks a link's target as git-annex's object store (DataLad datasets included).
const ANNEX_OBJECTS: &str = ".git/annex/objects";

/// The error for `path` when it is a symbolic link whose target does not exist:
/// [`IoError::AnnexMissing`] when the target lies in a git-annex object store (its
/// path holds `.git/annex/objects`), else [`IoError::BrokenLink`]. `None` when
/// `path` is not a symbolic link or its target exists.
///
/// ```
/// # #[cfg(unix)] {
/// let dir = tempfile::tempdir().unwrap();
/// let link = dir.path().join("sub-01_T1w.nii.gz");
/// std::os::unix::fs::symlink(".git/annex/objects/Xy/Zw/KEY/KEY", &link).unwrap();
/// let err = glint_io::broken_link(&link).unwrap();
/// assert!(err.to_string().contains("content not present (git-annex): run `datalad get"));
/// # }
/// ```
pub fn broken_link(path: &Path) -> Option<IoError> {
    let meta = std::fs::symlink_metadata(path).ok()?;
    if !meta.file_type().is_symlink() || std::fs::metadata(path).is_ok() {
        return None;
    }
    let target = std::fs::read_link(path).unwrap_or_default();
    Some(if is_annex(&target) {
        IoError::AnnexMissing { path: path.into() }
    } else {
        IoError::BrokenLink {
            path: path.into(),
            target,
        }
    })
}

/// Whether a link target points into a git-annex object store.
fn is_annex(target: &Path) -> bool {
    target
        .to_string_lossy()
        .replace('\\', "/")
        .contains(ANNEX_OBJECTS)
}

/// The error of a failed file-system call on `path`: a broken link named as such
/// ([`broken_link`]) when the file was not found, else [`IoError::Os`].
pub(crate) fn os_error(path: &Path, source: std::io::Error) -> IoError {
    if source.kind() == std::io::ErrorKind::NotFound {
        if let Some(e) = broken_link(path) {
            return e;
        }
    }
    IoError::Os {
        path: PathBuf::from(path),
        source,
    }
}

#[cfg(all(test, unix))]
mod tests {
    use super::*;
    use std::os::unix::fs::symlink;

    #[test]
    fn links_to_nothing_are_named_for_what_they_are() {
        let dir = tempfile::tempdir().unwrap();
        let root = dir.path();
        let annex = root.join("a.nii.gz");
        symlink(
            "../.git/annex/objects/pX/3k/MD5E-s1--x.nii.gz/MD5E-s1--x.nii.gz",
            &annex,
        )
        .unwrap();
        let plain = root.join("b.nii.gz");
        symlink("/nowhere/b.nii.gz", &plain).unwrap();
        let real = root.join("c.nii.gz");
        std::fs::write(&real, b"x").unwrap();
        let good = root.join("d.nii.gz");
        symlink(&real, &good).unwrap();

        let e = broken_link(&annex).unwrap();
        assert!(matches!(e, IoError::AnnexMissing { .. }), "{e}");
        assert_eq!(
            e.to_string(),
            format!(
                "{}: content not present (git-annex): run `datalad get {}`",
                annex.display(),
                annex.display()
            )
        );
        let e = broken_link(&plain).unwrap();
        assert_eq!(
            e.to_string(),
            format!(
                "{}: broken symbolic link to /nowhere/b.nii.gz",
                plain.display()
            )
        );
        // A link that resolves, a plain file and a missing file are not broken links.
        assert!(broken_link(&good).is_none());
        assert!(broken_link(&real).is_none());
        assert!(broken_link(&root.join("gone.nii")).is_none());
        let missing = std::io::Error::from(std::io::ErrorKind::NotFound);
        assert!(matches!(
            os_error(&root.join("gone.nii"), missing),
            IoError::Os { .. }
        ));
    }
}
